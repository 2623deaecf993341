package io.ecvo

import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Test

/**
 * Issue 50 through JNI: each frame's registration quality (the 6x6 information matrix,
 * the residual scale, the fraction of points used) and the reason a lost frame was lost,
 * read with `Tracker.frameQuality` on the replay stream of scripts/jni-jvm-tests.sh.
 */
class FrameQualityTest {
    private fun config(s: JvmTestStream) = TrackerConfig(
        width = s.width, height = s.height, fx = s.fx, fy = s.fy, cx = s.cx, cy = s.cy,
        preset = Preset.PHONE, mode = Mode.L2, admission = Admission.OFFLINE, threads = 2,
    )

    /** Cholesky of a symmetric 6x6 matrix: the smallest pivot (> 0 iff positive definite). */
    private fun smallestCholeskyPivot(m: DoubleArray): Double {
        val l = DoubleArray(36)
        var smallest = Double.POSITIVE_INFINITY
        for (j in 0 until 6) {
            var d = m[6 * j + j]
            for (k in 0 until j) d -= l[6 * j + k] * l[6 * j + k]
            smallest = minOf(smallest, d)
            if (d <= 0.0) return d
            l[6 * j + j] = Math.sqrt(d)
            for (i in j + 1 until 6) {
                var s = m[6 * i + j]
                for (k in 0 until j) s -= l[6 * i + k] * l[6 * j + k]
                l[6 * i + j] = s / l[6 * j + j]
            }
        }
        return smallest
    }

    @Test
    fun trackedFramesHaveASymmetricPositiveDefiniteInformationMatrix() {
        val s = JvmTestStream.load()
        val out = DoubleArray(FrameQuality.SIZE)
        Tracker(config(s)).use { t ->
            assertEquals(Tracker.NO_POSE, t.frameQuality(out))
            assertNull(t.frameQuality())
            val expected = TimedPose.listFromArray(s.expectedTrajectory)
            var registered = 0
            for (i in s.stamps.indices) {
                t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i])
                t.flush()
                assertEquals("timestamp of frame $i", s.stamps[i], t.frameQuality(out))
                val q = FrameQuality.fromArray(out)
                assertEquals(i.toLong(), q.index)
                assertEquals("the pose beside the quality is frame $i's", expected[i], q.pose)
                if (i == 0) {
                    assertFalse("the first frame has no registration", q.hasRegistration)
                    assertTrue(q.information.all { it == 0.0 })
                    assertNull(q.residualScale)
                    continue
                }
                if (q.state != TrackingState.TRACKING) continue
                assertNull(q.lostReason)
                if (!q.hasRegistration) continue
                registered++
                val m = q.information
                val big = m.maxOf { Math.abs(it) }
                assertTrue("frame $i: information is not zero", big > 0.0)
                for (r in 0 until 6) for (c in 0 until 6) {
                    assertEquals("frame $i: information symmetric at ($r, $c)", m[6 * r + c], m[6 * c + r], 1e-12 * big)
                }
                assertTrue("frame $i: information positive definite (smallest pivot ${smallestCholeskyPivot(m)})",
                    smallestCholeskyPivot(m) > 0.0)
                val scale = q.residualScale ?: fail("frame $i: no residual scale").let { return }
                assertTrue("frame $i: scale ${scale.toList()}", scale[0] > 0.0 && scale[2] > 0.0 && scale[0] * scale[2] > scale[1] * scale[1])
                assertTrue("frame $i: ${q.validPoints} of ${q.templatePoints} points",
                    q.templatePoints > 100 && q.validPoints in 1..q.templatePoints)
                assertTrue(q.pointFraction > 0.5 && q.pointFraction <= 1.0)
                assertEquals(q.information[6 * 1 + 4], q.information(1, 4), 0.0)
            }
            assertTrue("frames with a registration: $registered of ${s.stamps.size}", registered >= s.stamps.size - 2)
            val last = t.frameQuality() ?: fail("no quality").let { return }
            assertEquals(s.stamps.size - 1L, last.index)
        }
    }

    @Test
    fun aLostFrameSaysWhy() {
        val s = JvmTestStream.load()
        val out = DoubleArray(FrameQuality.SIZE)
        Tracker(config(s)).use { t ->
            for (i in 0 until 5) t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i])
            t.flush()
            val tracked = t.frameQuality() ?: fail("no quality").let { return }
            assertEquals(TrackingState.TRACKING, tracked.state)
            // A covered lens: no valid depth pixel, a flat grey image (with the image alone
            // the frame still registers photometrically).
            t.pushFrame(s.stamps[5], ShortArray(s.width * s.height), ByteArray(s.width * s.height) { 128.toByte() })
            t.flush()
            assertEquals(s.stamps[5], t.frameQuality(out))
            val lost = FrameQuality.fromArray(out)
            assertEquals(TrackingState.LOST, lost.state)
            assertEquals(LostReason.NO_VALID_DEPTH, lost.lostReason)
            assertEquals("no_valid_depth", lost.lostReason?.reasonName)
            assertFalse(lost.hasRegistration)
            assertTrue("a lost frame carries no constraint", lost.information.all { it == 0.0 })
            assertEquals("a lost frame keeps the last good pose", tracked.pose.copy(timestamp = lost.pose.timestamp), lost.pose)
            // The next real frame registers again, and has no reason.
            t.pushFrame(s.stamps[6], s.depth[6], s.intensity[6])
            t.flush()
            val back = t.frameQuality() ?: fail("no quality").let { return }
            assertEquals(TrackingState.TRACKING, back.state)
            assertNull(back.lostReason)
            assertTrue(back.hasRegistration)
            // A far view turned upside down: no rigid motion explains it.
            val far = s.stamps.size - 1
            t.pushFrame(s.stamps[7], s.depth[far].reversedArray(), s.intensity[far].reversedArray())
            t.flush()
            val wrong = t.frameQuality() ?: fail("no quality").let { return }
            assertEquals(TrackingState.LOST, wrong.state)
            assertTrue("a reason other than no depth: ${wrong.lostReason}",
                wrong.lostReason != null && wrong.lostReason != LostReason.NO_VALID_DEPTH)
            assertFalse(wrong.hasRegistration)
        }
    }

    @Test
    fun badArraysAndClosedTrackersAreExceptions() {
        val s = JvmTestStream.load()
        val t = Tracker(config(s))
        t.pushFrame(s.stamps[0], s.depth[0], s.intensity[0])
        t.flush()
        try {
            t.frameQuality(DoubleArray(FrameQuality.SIZE - 1))
            fail("a short array was accepted")
        } catch (e: IllegalArgumentException) {
            assertTrue(e.message, e.message!!.contains("out: array has 52 values") && e.message!!.contains("53"))
        }
        try {
            NativeBridge.nativeFrameQuality(NativeBridgeAccess.handle(t), null)
            fail("a null array was accepted")
        } catch (e: IllegalArgumentException) {
            assertTrue(e.message, e.message!!.contains("null"))
        }
        val sentinel = DoubleArray(FrameQuality.SIZE) { -1.0 }
        t.close()
        try {
            t.frameQuality(sentinel)
            fail("a closed tracker answered")
        } catch (e: IllegalStateException) {
            assertTrue(e.message, e.message!!.contains("closed"))
        }
        try {
            NativeBridge.nativeFrameQuality(123_456_789L, sentinel)
            fail("an unknown handle answered")
        } catch (e: IllegalStateException) {
            assertTrue(e.message, e.message!!.contains("released or unknown"))
        }
        assertArrayEquals(DoubleArray(FrameQuality.SIZE) { -1.0 }, sentinel, 0.0)
    }

    @Test
    fun theLayoutReadsBackAndRefusesShortArrays() {
        val a = DoubleArray(FrameQuality.SIZE)
        a[0] = 7.0; a[1] = 2.0; a[2] = 5.0; a[3] = 1.5; a[10] = 1.0; a[47] = Double.NaN
        val q = FrameQuality.fromArray(a)
        assertEquals(7L, q.index)
        assertEquals(TrackingState.LOST, q.state)
        assertEquals(LostReason.INCONSISTENT, q.lostReason)
        assertEquals(1.5, q.pose.timestamp, 0.0)
        assertNull(q.residualScale)
        assertEquals(0.0, q.pointFraction, 0.0)
        try {
            FrameQuality.fromArray(DoubleArray(10)); fail("short array read")
        } catch (e: IllegalArgumentException) {
            assertTrue(e.message!!.contains("expected at least ${FrameQuality.SIZE}"))
        }
        try {
            LostReason.fromCode(99); fail("unknown code read")
        } catch (e: IllegalStateException) {
            assertTrue(e.message!!.contains("99"))
        }
    }
}
