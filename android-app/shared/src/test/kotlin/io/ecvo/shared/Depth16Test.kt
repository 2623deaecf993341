package io.ecvo.shared

import io.ecvo.shared.TestSupport.assertThrows
import java.nio.ByteBuffer
import java.nio.ByteOrder
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Test

class Depth16Test {
    @Test
    fun confidenceFollowsAndroidsDefinition() {
        // Raw top bits 0 = 100 %, 1 = 0 %, c = (c - 1) / 7.
        assertEquals(7, Depth16.confidence(1234.toShort()))
        assertEquals(0, Depth16.confidence(((1 shl 13) or 1234).toShort()))
        assertEquals(1, Depth16.confidence(((2 shl 13) or 1234).toShort()))
        assertEquals(6, Depth16.confidence(((7 shl 13) or 1234).toShort()))
        assertEquals(1f, Depth16.confidenceFraction(0), 0f)
        assertEquals(3f / 7f, Depth16.confidenceFraction(((4 shl 13) or 5).toShort()), 1e-7f)
        for (level in 0..7) for (mm in intArrayOf(0, 1, 4321, 8191)) {
            val s = Depth16.encode(mm, level)
            assertEquals(mm, Depth16.rangeMm(s))
            assertEquals(level, Depth16.confidence(s))
        }
        assertThrows<IllegalArgumentException> { Depth16.encode(8192, 7) }
    }

    @Test
    fun lowConfidenceAndEmptyPixelsBecomeZero() {
        val raw = shortArrayOf(
            Depth16.encode(1500, 7), Depth16.encode(1500, 0), Depth16.encode(1500, 3),
            Depth16.encode(0, 7), Depth16.encode(8191, 4),
        )
        assertArrayEquals(shortArrayOf(1500, 1500, 1500, 0, 8191), Depth16.decode(raw, 0))
        assertArrayEquals(shortArrayOf(1500, 0, 1500, 0, 8191), Depth16.decode(raw, 1))
        assertArrayEquals(shortArrayOf(1500, 0, 0, 0, 8191), Depth16.decode(raw, 4))
        assertArrayEquals(shortArrayOf(1500, 0, 0, 0, 0), Depth16.decode(raw, 7))
        // In place.
        Depth16.decode(raw, 4, raw)
        assertArrayEquals(shortArrayOf(1500, 0, 0, 0, 8191), raw)
        assertThrows<IllegalArgumentException> { Depth16.decode(raw, 8) }
    }

    @Test
    fun planesWithRowPaddingDecode() {
        val (w, h, stride) = Triple(3, 2, 10) // 6 bytes of samples, 4 of padding per row
        val b = ByteBuffer.allocateDirect(stride * (h - 1) + 2 * w).order(ByteOrder.LITTLE_ENDIAN)
        val values = arrayOf(
            shortArrayOf(Depth16.encode(100, 7), Depth16.encode(200, 0), Depth16.encode(300, 5)),
            shortArrayOf(Depth16.encode(400, 2), Depth16.encode(0, 7), Depth16.encode(8000, 6)),
        )
        for (y in 0 until h) {
            for (x in 0 until w) b.putShort(y * stride + 2 * x, values[y][x])
            if (y < h - 1) for (p in 2 * w until stride) b.put(y * stride + p, 0x55)
        }
        val out = Depth16.decodePlane(b, stride, w, h, 2, order = ByteOrder.LITTLE_ENDIAN)
        assertArrayEquals(shortArrayOf(100, 0, 300, 400, 0, 8000), out)
        assertThrows<IllegalArgumentException> { Depth16.decodePlane(b, 4, w, h, 0) }
    }
}
