package io.ecvo

import io.ecvo.shared.TumTrajectory
import java.io.File
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Test
import kotlin.math.abs
import kotlin.math.atan2
import kotlin.math.sqrt

/**
 * Issue 47 through JNI: `Tracker.pushImu` (one sample and a batch) on the replay stream of
 * scripts/jni-jvm-tests.sh, with a gyroscope made from the stream's ground truth
 * (`testdata/synth_phone_320x180/groundtruth.txt`): a simulated, noise-free gyroscope.
 */
class ImuJniTest {
    private fun config(s: JvmTestStream) = TrackerConfig(
        width = s.width, height = s.height, fx = s.fx, fy = s.fy, cx = s.cx, cy = s.cy,
        preset = Preset.PHONE, mode = Mode.L2, admission = Admission.OFFLINE, threads = 2,
    )

    private inline fun <reified E : Throwable> assertThrows(contains: String, block: () -> Unit) {
        try {
            block()
        } catch (e: Throwable) {
            if (e is E) {
                assertTrue("message '${e.message}' should mention '$contains'", e.message?.contains(contains) == true)
                return
            }
            throw AssertionError("expected ${E::class.simpleName}, got $e", e)
        }
        fail("expected ${E::class.simpleName}, nothing thrown")
    }

    /** q⁻¹ p as (x, y, z, w) for unit quaternions given as poses. */
    private fun relative(a: TimedPose, b: TimedPose): DoubleArray {
        // conj(a) * b
        val (ax, ay, az, aw) = listOf(-a.qx, -a.qy, -a.qz, a.qw)
        return doubleArrayOf(
            aw * b.qx + ax * b.qw + ay * b.qz - az * b.qy,
            aw * b.qy - ax * b.qz + ay * b.qw + az * b.qx,
            aw * b.qz + ax * b.qy - ay * b.qx + az * b.qw,
            aw * b.qw - ax * b.qx - ay * b.qy - az * b.qz,
        )
    }

    /** The rotation angle of a unit quaternion (x, y, z, w), radians in [0, π]. */
    private fun angle(q: DoubleArray): Double {
        val v = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
        return 2 * atan2(v, abs(q[3]))
    }

    /** The body rate (rad/s, camera axes) that turns [a] into [b] over their interval. */
    private fun rate(a: TimedPose, b: TimedPose): DoubleArray {
        val q = relative(a, b)
        if (q[3] < 0) for (k in 0 until 4) q[k] = -q[k]
        val v = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
        val dt = b.timestamp - a.timestamp
        if (v < 1e-15) return DoubleArray(3)
        val th = 2 * atan2(v, q[3])
        return DoubleArray(3) { q[it] / v * th / dt }
    }

    /** Mean rotation error of [est] against [gt] (both from their first pose on), radians. */
    private fun meanRotationError(est: List<TimedPose>, gt: List<TimedPose>): Double {
        var sum = 0.0
        for (i in est.indices) {
            val e = relative(est[0], est[i]); val g = relative(gt[0], gt[i])
            val d = relative(TimedPose(0.0, 0.0, 0.0, 0.0, g[0], g[1], g[2], g[3]), TimedPose(0.0, 0.0, 0.0, 0.0, e[0], e[1], e[2], e[3]))
            sum += angle(d)
        }
        return sum / est.size
    }

    @Test
    fun aGyroscopeFromTheGroundTruthGivesEveryFrameAPriorAndKeepsTheTrack() {
        val s = JvmTestStream.load()
        val repo = File(System.getProperty("ecvo.repo") ?: ".")
        val gt = TumTrajectory.read(File(repo, "testdata/synth_phone_320x180/groundtruth.txt")).take(s.stamps.size)
        assertEquals(s.stamps.size, gt.size)
        for (i in gt.indices) assertEquals("frame $i", s.stamps[i] / 1e9, gt[i].timestamp, 1e-6)
        // 400 Hz: in each frame interval (t[i-1], t[i]] the rate that turns pose i-1 into pose i.
        val periodNs = 2_500_000L
        val ts = LongArray(Tracker.MAX_IMU_BATCH); val w = FloatArray(3 * Tracker.MAX_IMU_BATCH)
        var pushed = 0L
        val plain = Tracker(config(s)).use { t ->
            for (i in s.stamps.indices) t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i])
            t.flush()
            t.trajectory()
        }
        Tracker(config(s)).use { t ->
            var next = s.stamps[0] - 20 * periodNs
            for (i in s.stamps.indices) {
                val r = if (i == 0) DoubleArray(3) else rate(gt[i - 1], gt[i])
                var n = 0
                while (next <= s.stamps[i]) {
                    ts[n] = next; w[3 * n] = r[0].toFloat(); w[3 * n + 1] = r[1].toFloat(); w[3 * n + 2] = r[2].toFloat()
                    n++; next += periodNs
                }
                if (i % 2 == 0) {
                    t.pushImu(ts, w, n)
                } else {
                    for (k in 0 until n) t.pushImu(ts[k], w[3 * k].toDouble(), w[3 * k + 1].toDouble(), w[3 * k + 2].toDouble())
                }
                pushed += n
                t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i])
            }
            t.flush()
            val st = t.stats()
            assertEquals(pushed, st.imuSamples)
            assertEquals(0L, st.imuRefused)
            assertEquals(0L, st.imuDropped)
            assertEquals(0L, st.imuLate)
            assertTrue("frames with a gyro prior: ${st.imuPriors} of ${s.stamps.size}", st.imuPriors >= s.stamps.size - 2)
            val withImu = t.trajectory()
            assertEquals(s.stamps.size, withImu.size)
            val e0 = meanRotationError(plain, gt); val e1 = meanRotationError(withImu, gt)
            println("ImuJniTest: mean rotation error against the ground truth ${"%.5f".format(e0)} rad without the gyroscope, ${"%.5f".format(e1)} with")
            assertTrue("with the gyroscope $e1 rad, without $e0 rad", e1 <= e0 * 1.25 + 1e-3)
            // A repeated sample is dropped and counted (when the next frame takes it), never an error.
            t.pushImu(ts, w, 1)
            t.pushFrame(s.stamps.last() + 33_000_000L, s.depth[0], s.intensity[0])
            t.flush()
            assertEquals(1L, t.stats().imuRefused)
            assertEquals(pushed, t.stats().imuSamples)
        }
    }

    @Test
    fun badSamplesAreExceptionsAndNothingOfTheBatchIsTaken() {
        val s = JvmTestStream.load()
        val t = Tracker(config(s))
        var frame = 0
        // The tracker takes the samples pushed before a frame when it tracks that frame.
        fun taken(): Long {
            t.pushFrame(s.stamps[frame], s.depth[frame], s.intensity[frame]); frame++
            t.flush()
            return t.stats().imuSamples
        }
        t.pushImu(longArrayOf(1, 2, 3), FloatArray(9), 3)
        assertEquals(3L, taken())
        assertThrows<IllegalArgumentException>("sample 1") { t.pushImu(longArrayOf(4, 5, 6), floatArrayOf(0f, 0f, 0f, 0f, Float.NaN, 0f, 0f, 0f, 0f), 3) }
        assertThrows<IllegalArgumentException>("not finite") { t.pushImu(7, 0.0, Double.POSITIVE_INFINITY, 0.0) }
        assertThrows<IllegalArgumentException>("rates: array has 5 values, 2 samples need 6") { t.pushImu(longArrayOf(8, 9), FloatArray(5), 2) }
        assertThrows<IllegalArgumentException>("timestampsNs: array has 1 values, count is 2") { t.pushImu(longArrayOf(8), FloatArray(6), 2) }
        assertThrows<IllegalArgumentException>("count: -1 is negative") { t.pushImu(longArrayOf(8), FloatArray(3), -1) }
        assertThrows<IllegalArgumentException>("more than 4096") {
            t.pushImu(LongArray(5000) { 100L + it }, FloatArray(15000), 5000)
        }
        val h = NativeBridgeAccess.handle(t)
        assertThrows<IllegalArgumentException>("timestampsNs: array is null") { NativeBridge.nativePushImuBatch(h, null, FloatArray(3), 1) }
        assertThrows<IllegalArgumentException>("rates: array is null") { NativeBridge.nativePushImuBatch(h, LongArray(1), null, 1) }
        t.pushImu(LongArray(0), FloatArray(0), 0) // count 0 takes nothing
        assertEquals("nothing of a refused batch was taken", 3L, taken())
        // A batch over several native chunks (256 samples each) is taken whole, in order.
        val n = Tracker.MAX_IMU_BATCH
        t.pushImu(LongArray(n) { 1_000L + it }, FloatArray(3 * n) { 0.01f }, n)
        assertEquals(3L + n, taken())
        assertEquals(0L, t.stats().imuRefused)
        t.close()
        assertThrows<IllegalStateException>("closed") { t.pushImu(1, 0.0, 0.0, 0.0) }
        assertThrows<IllegalStateException>("released or unknown") { NativeBridge.nativePushImu(h, 1, 0.0, 0.0, 0.0) }
    }
}
