package io.ecvo.shared

import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertTrue
import org.junit.Test

class PairingTest {
    private val ms = 1_000_000L

    @Test
    fun captureTimeOnlyWhenBothCamerasUseTheRealtimeClock() {
        assertEquals(Pairing.CAPTURE_TIME, Pairing.choose(TimestampSource.REALTIME, TimestampSource.REALTIME))
        assertEquals(Pairing.ARRIVAL_TIME, Pairing.choose(TimestampSource.UNKNOWN, TimestampSource.REALTIME))
        assertEquals(Pairing.ARRIVAL_TIME, Pairing.choose(TimestampSource.REALTIME, TimestampSource.fromCode(null)))
        assertEquals(TimestampSource.REALTIME, TimestampSource.fromCode(1))
    }

    @Test
    fun depthWithoutAColourFrameCloseInTimeIsDroppedAndCounted() {
        val p = FramePairer(Pairing.CAPTURE_TIME, maxDtNs = 20 * ms)
        assertFalse(p.onDepth(100 * ms, 0)) // no colour yet
        p.onColour(110 * ms, 999 * ms)
        assertTrue(p.onDepth(125 * ms, 0))
        assertFalse(p.onDepth(131 * ms, 0)) // 21 ms away
        assertEquals(2L, p.droppedNoColour)
        assertEquals(1L, p.paired)
    }

    @Test
    fun arrivalPairingIgnoresIncomparableCaptureTimes() {
        val p = FramePairer(Pairing.ARRIVAL_TIME, maxDtNs = 20 * ms)
        // Capture clocks a second apart (UNKNOWN sources), arrival 5 ms apart: paired.
        p.onColour(5_000 * ms, 100 * ms)
        assertTrue(p.onDepth(4_000 * ms, 105 * ms))
        assertFalse(p.onDepth(5_000 * ms, 200 * ms))
        assertEquals(1L, p.droppedNoColour)
    }
}
