package io.ecvo

import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Test

/**
 * A process holds at most 16 live trackers (`ecvo_jni::MAX_LIVE_TRACKERS`: each has its
 * own threads); the 17th `init` is an IllegalStateException saying so, and `close()`
 * gives the place back. Run with -Xcheck:jni by `scripts/jni-jvm-tests.sh`.
 */
class TrackerLimitTest {
    private fun small() = TrackerConfig(
        width = 64, height = 48, fx = 50.0, fy = 50.0, cx = 31.5, cy = 23.5,
        admission = Admission.OFFLINE, threads = 1,
    )

    @Test fun liveTrackersAreCappedAndClosingGivesThePlaceBack() {
        val open = ArrayList<Tracker>()
        var capacity = 0
        try {
            var refused: IllegalStateException? = null
            // Trackers of other tests not yet collected may hold places: at most 16 open.
            for (i in 0 until 17) {
                try {
                    open += Tracker(small())
                } catch (e: IllegalStateException) {
                    refused = e
                    break
                }
            }
            val e = refused ?: fail("17 trackers opened") as Nothing
            capacity = open.size
            assertTrue("$capacity opened", capacity in 1..16)
            assertTrue(e.message, e.message!!.contains("16 trackers are live") && e.message!!.contains("close()"))
            open.removeAt(0).close()
            open += Tracker(small())
            assertEquals(PushStatus.ACCEPTED, open.last().pushFrame(1, ShortArray(64 * 48) { 1000 }, ByteArray(64 * 48) { 7 }))
        } finally {
            open.forEach { it.close() }
        }
        // All places are back.
        val again = (0 until capacity).map { Tracker(small()) }
        again.forEach { it.close() }
    }

    /**
     * Trackers dropped without close(): at the cap a new Tracker asks for a collection and
     * releases the unreachable ones (as java.nio does for direct memory), so 2,000 of them
     * in a loop all open.
     */
    @Test fun trackersDroppedWithoutCloseDoNotExhaustTheCap() {
        for (i in 0 until 2000) {
            val t = Tracker(small())
            if (i % 100 == 0) {
                assertEquals(PushStatus.ACCEPTED, t.pushFrame(1, ShortArray(64 * 48) { 1000 }, ByteArray(64 * 48) { 7 }))
            }
        }
    }
}
