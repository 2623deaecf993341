package io.ecvo

import java.nio.ByteBuffer
import java.nio.ByteOrder
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Test

/**
 * Direct buffers at the JNI edge (issue 31): the byte order of depth and the buffers'
 * position and limit. Run with -Xcheck:jni by `rust/ecvo-jni/tests/jvm.rs`, like
 * [NativeBridgeTest]. A frame pushed twice is [PushStatus.REPEATED] (bit-identical to the
 * previous one), which shows which bytes the library read.
 */
class BufferEdgeTest {
    private val w = 320
    private val h = 180
    private val n = w * h

    private fun config() = TrackerConfig(
        width = w, height = h, fx = 250.0, fy = 250.0, cx = 159.5, cy = 89.5,
        admission = Admission.OFFLINE, threads = 1,
    )

    private fun depthAt(k: Int): Short = (1000 + (k * 7919) % 1500).toShort()
    private fun grayAt(k: Int): Byte = ((k * 31 + k / w) % 251).toByte()

    /** The test frame written with absolute puts at byte [offset] of a buffer of [extra] more bytes. */
    private fun depth(offset: Int = 0, extra: Int = 0, order: ByteOrder = ByteOrder.LITTLE_ENDIAN): ByteBuffer {
        val b = ByteBuffer.allocateDirect(offset + 2 * n + extra).order(order)
        for (i in 0 until offset + 2 * n + extra) b.put(i, 0x5A) // garbage around the frame
        for (k in 0 until n) b.putShort(offset + 2 * k, depthAt(k))
        return b
    }

    private fun gray(offset: Int = 0, extra: Int = 0): ByteBuffer {
        val b = ByteBuffer.allocateDirect(offset + n + extra)
        for (i in 0 until offset + n + extra) b.put(i, 0x33)
        for (k in 0 until n) b.put(offset + k, grayAt(k))
        return b
    }

    private fun iae(contains: List<String>, block: () -> Unit) {
        try {
            block()
        } catch (e: IllegalArgumentException) {
            for (c in contains) assertTrue("message '${e.message}' should mention '$c'", e.message?.contains(c) == true)
            return
        }
        fail("expected an IllegalArgumentException mentioning $contains")
    }

    @Test fun bigEndianDepthIsRefusedAndLittleEndianRead(): Unit = Tracker(config()).use { t ->
        // allocateDirect's default order is BIG_ENDIAN: the easiest mistake.
        iae(listOf("depth", "BIG_ENDIAN", "LITTLE_ENDIAN")) { t.pushFrame(1, depth(order = ByteOrder.BIG_ENDIAN), gray()) }
        iae(listOf("depth", "BIG_ENDIAN")) { t.pushFrame(1, depth(order = ByteOrder.BIG_ENDIAN), 2 * w, gray(), w) }
        // The refusal tracked nothing, and intensity's order does not matter (one byte a pixel).
        val g = gray().order(ByteOrder.BIG_ENDIAN)
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(1, depth(), g))
        // The same samples, written big-endian into a buffer then flagged little-endian
        // would be other values; written little-endian they are the same frame.
        assertEquals(PushStatus.REPEATED, t.pushFrame(2, depth(), gray()))
        val swapped = depth(order = ByteOrder.BIG_ENDIAN).order(ByteOrder.LITTLE_ENDIAN)
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(3, swapped, gray()))
    }

    @Test fun theFrameIsReadFromPosition(): Unit = Tracker(config()).use { t ->
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(1, depth(), gray()))
        // The same frame at byte 64 (depth) and 17 (intensity), garbage before it.
        val d = depth(offset = 64); d.position(64)
        val g = gray(offset = 17); g.position(17)
        assertEquals(PushStatus.REPEATED, t.pushFrame(2, d, g))
        // Padded rows from a position too.
        val ds = depth(offset = 6); ds.position(6)
        assertEquals(PushStatus.REPEATED, t.pushFrame(3, ds, 2 * w, gray(), w))
        // Read from position 0, the same buffer is another frame.
        d.position(0); g.position(0)
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(4, d, g))
    }

    @Test fun aLimitShortOfTheFrameIsRefused(): Unit = Tracker(config()).use { t ->
        val d = depth(); d.limit(2 * n - 2)
        iae(listOf("depth: buffer holds ${2 * n - 2} bytes", "limit ${2 * n - 2}", "needs ${2 * n}")) { t.pushFrame(1, d, gray()) }
        val g = gray(); g.limit(n - 1)
        iae(listOf("intensity: buffer holds", "needs $n")) { t.pushFrame(1, depth(), g) }
        // A position that leaves less than a frame before the limit.
        val dp = depth(extra = 10); dp.position(12)
        iae(listOf("depth", "position 12", "needs ${2 * n}")) { t.pushFrame(1, dp, gray()) }
        // Written with relative puts and not flipped: position == limit, nothing framed.
        val rel = ByteBuffer.allocateDirect(n); for (k in 0 until n) rel.put(grayAt(k))
        iae(listOf("intensity: buffer holds 0 bytes", "flip()")) { t.pushFrame(1, depth(), rel) }
        rel.flip()
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(1, depth(), rel))
        // A limit past the frame is fine: the bytes after it are not read.
        val big = depth(extra = 100)
        assertEquals(PushStatus.REPEATED, t.pushFrame(2, big, gray(extra = 3)))
    }
}
