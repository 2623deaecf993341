package io.ecvo

import java.lang.reflect.Modifier
import java.nio.ByteBuffer
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Test

/** The parts of the tracker API that need no native library: codes, layouts, pose math. */
class TrackerApiTest {
    private inline fun <reified E : Throwable> assertThrows(block: () -> Unit): E {
        try {
            block()
        } catch (e: Throwable) {
            if (e is E) return e
            throw AssertionError("expected ${E::class.simpleName}, got $e", e)
        }
        fail("expected ${E::class.simpleName}, nothing thrown")
        throw IllegalStateException()
    }

    @Test
    fun codesMatchTheDocumentedTables() {
        assertEquals(listOf(0, 1, 2), DepthFormat.entries.map { it.code })
        assertEquals(listOf("MILLIMETRES", "DEPTH16", "CUSTOM_SCALE"), DepthFormat.entries.map { it.name })
        assertEquals(listOf(0, 1), Preset.entries.map { it.code })
        assertEquals(listOf("PC", "PHONE"), Preset.entries.map { it.name })
        assertEquals(listOf(0, 1, 2), Mode.entries.map { it.code })
        assertEquals(listOf("NAIVE", "L1", "L2"), Mode.entries.map { it.name })
        assertEquals(listOf(0, 1), Admission.entries.map { it.code })
        assertTrue(Admission.LIVE.live)
        assertFalse(Admission.OFFLINE.live)
        assertEquals(listOf(0, 1, 2), PushStatus.entries.map { it.code })
        assertEquals(listOf("ACCEPTED", "DROPPED", "REPEATED"), PushStatus.entries.map { it.name })
        assertEquals(listOf(0, 1, 2), TrackingState.entries.map { it.code })
        assertEquals(listOf("INITIALISING", "TRACKING", "LOST"), TrackingState.entries.map { it.name })
    }

    @Test
    fun fromCodeRoundTripsAndRejectsUnknownCodes() {
        DepthFormat.entries.forEach { assertEquals(it, DepthFormat.fromCode(it.code)) }
        Preset.entries.forEach { assertEquals(it, Preset.fromCode(it.code)) }
        Mode.entries.forEach { assertEquals(it, Mode.fromCode(it.code)) }
        Admission.entries.forEach { assertEquals(it, Admission.fromCode(it.code)) }
        PushStatus.entries.forEach { assertEquals(it, PushStatus.fromCode(it.code)) }
        TrackingState.entries.forEach { assertEquals(it, TrackingState.fromCode(it.code)) }
        assertThrows<IllegalArgumentException> { DepthFormat.fromCode(3) }
        assertThrows<IllegalArgumentException> { Mode.fromCode(-1) }
        // Codes coming back from the library: a mismatch is a broken build, not bad input.
        val e = assertThrows<IllegalStateException> { TrackingState.fromCode(7) }
        assertTrue(e.message!!.contains("7"))
        assertThrows<IllegalStateException> { PushStatus.fromCode(3) }
    }

    @Test
    fun configDefaultsAreThePhoneSetup() {
        val c = TrackerConfig(fx = 258.65, fy = 258.25, cx = 159.05, cy = 97.4)
        assertEquals(320, c.width)
        assertEquals(180, c.height)
        assertEquals(DepthFormat.MILLIMETRES, c.depthFormat)
        assertEquals(1000.0, c.depthScale, 0.0)
        assertEquals(0, c.minConfidence)
        assertEquals(Preset.PHONE, c.preset)
        assertEquals(Mode.L2, c.mode)
        assertEquals(Admission.LIVE, c.admission)
        assertEquals(2, c.threads)
    }

    @Test
    fun statsLayoutRoundTrips() {
        val a = DoubleArray(TrackerStats.SIZE) { (it + 1).toDouble() }
        a[9] = 1.25; a[10] = 2.5; a[11] = 0.75; a[12] = 4.5; a[13] = 5.0
        val s = TrackerStats.fromArray(a)
        assertEquals(1L, s.framesPushed)
        assertEquals(2L, s.framesDropped)
        assertEquals(3L, s.framesTracked)
        assertEquals(4L, s.motionEstimations)
        assertEquals(5L, s.referencesL1)
        assertEquals(6L, s.referencesL2)
        assertEquals(7L, s.lostFrames)
        assertEquals(8L, s.failedCorrections)
        assertEquals(9L, s.reanchors)
        assertEquals(1.25, s.filterMs, 0.0)
        assertEquals(2.5, s.trackerMs, 0.0)
        assertEquals(0.75, s.geometryMs, 0.0)
        assertEquals(4.5, s.latencyMs, 0.0)
        assertEquals(5.0, s.totalMs, 0.0)
        assertEquals(15L, s.trajectoryStart)
        assertEquals(16L, s.imuSamples)
        assertEquals(17L, s.imuRefused)
        assertEquals(18L, s.imuDropped)
        assertEquals(19L, s.imuPriors)
        assertEquals(20L, s.imuLate)
        assertEquals(21L, s.imuMissing)
        assertArrayEquals(a, s.toArray(), 0.0)
        // Appended fields of a newer library are ignored; a short array is refused.
        assertEquals(s, TrackerStats.fromArray(a + doubleArrayOf(99.0, 98.0)))
        assertThrows<IllegalArgumentException> { TrackerStats.fromArray(DoubleArray(TrackerStats.SIZE - 1)) }
        assertEquals(0L, TrackerStats.EMPTY.framesTracked)
    }

    @Test
    fun poseAxesAndMatrixFollowTheQuaternion() {
        val identity = TimedPose(1.0, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0)
        val m = identity.toMatrix()
        assertArrayEquals(floatArrayOf(1f, 0f, 0f, 0f, 0f, 1f, 0f, 0f, 0f, 0f, 1f, 0f, 0.1f, 0.2f, 0.3f, 1f), m, 1e-7f)
        // 90 degrees about y: the camera's forward (z) axis points along world +x, its x axis along -z.
        val h = Math.sqrt(0.5)
        val yaw = TimedPose(0.0, 0.0, 0.0, 0.0, 0.0, h, 0.0, h)
        assertArrayEquals(doubleArrayOf(1.0, 0.0, 0.0), yaw.axis(2), 1e-12)
        assertArrayEquals(doubleArrayOf(0.0, 0.0, -1.0), yaw.axis(0), 1e-12)
        assertArrayEquals(doubleArrayOf(0.0, 1.0, 0.0), yaw.axis(1), 1e-12)
        // Column-major: column 2 (forward) is out[8..10].
        val my = yaw.toMatrix()
        assertArrayEquals(floatArrayOf(1f, 0f, 0f), my.copyOfRange(8, 11), 1e-7f)
        // 90 degrees about x: forward z -> -y (up), y -> z.
        val pitch = TimedPose(0.0, 0.0, 0.0, 0.0, h, 0.0, 0.0, h)
        assertArrayEquals(doubleArrayOf(0.0, -1.0, 0.0), pitch.axis(2), 1e-12)
        assertArrayEquals(doubleArrayOf(0.0, 0.0, 1.0), pitch.axis(1), 1e-12)
    }

    @Test
    fun nativeArraysSplitIntoPosesAndReferences() {
        val traj = doubleArrayOf(1.0, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0, 2.0, 1.1, 1.2, 1.3, 0.0, 1.0, 0.0, 0.0)
        val poses = TimedPose.listFromArray(traj)
        assertEquals(2, poses.size)
        assertEquals(TimedPose(2.0, 1.1, 1.2, 1.3, 0.0, 1.0, 0.0, 0.0), poses[1])
        val refs = ReferenceFrame.listFromArray(doubleArrayOf(1.0, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0, 2.0))
        assertEquals(listOf(ReferenceFrame(poses[0], 2)), refs)
        assertTrue(TimedPose.listFromArray(DoubleArray(0)).isEmpty())
        assertThrows<IllegalArgumentException> { TimedPose.listFromArray(DoubleArray(9)) }
        assertThrows<IllegalArgumentException> { ReferenceFrame.listFromArray(DoubleArray(8)) }
    }

    @Test
    fun nativeBridgeDeclaresTheContract() {
        // Load without initialising, so the library is not needed.
        val c = Class.forName("io.ecvo.NativeBridge", false, javaClass.classLoader)
        val natives = c.declaredMethods.filter { Modifier.isNative(it.modifiers) }.associateBy { it.name }
        val J = java.lang.Long.TYPE
        val I = Integer.TYPE
        val D = java.lang.Double.TYPE
        val expected = mapOf(
            "nativeInit" to listOf(I, I, D, D, D, D, I, D, I, I, I, java.lang.Boolean.TYPE, I, java.lang.Boolean.TYPE),
            "nativePushBuffers" to listOf(J, J, ByteBuffer::class.java, ByteBuffer::class.java),
            "nativePushStrided" to listOf(J, J, ByteBuffer::class.java, I, ByteBuffer::class.java, I),
            "nativePushArrays" to listOf(J, J, ShortArray::class.java, ByteArray::class.java),
            "nativeGetPose" to listOf(J, FloatArray::class.java),
            "nativeFrameQuality" to listOf(J, DoubleArray::class.java),
            "nativePushImu" to listOf(J, J, D, D, D),
            "nativePushImuBatch" to listOf(J, LongArray::class.java, FloatArray::class.java, I),
            "nativeState" to listOf(J),
            "nativeFlush" to listOf(J),
            "nativeSetIntrinsics" to listOf(J, D, D, D, D),
            "nativeTrajectory" to listOf(J),
            "nativeTrajectorySince" to listOf(J, I),
            "nativeReferences" to listOf(J),
            "nativeStats" to listOf(J),
            "nativePointCloud" to listOf(J, I),
            "nativeRelease" to listOf(J),
            "nativeMemoryNeeded" to listOf(I, I, D, D, D, D, I, D, I, I, I, java.lang.Boolean.TYPE, I, java.lang.Boolean.TYPE),
            "nativeSetMemoryBudget" to listOf(J),
        )
        assertEquals(expected.keys, natives.keys)
        for ((name, params) in expected) {
            val m = natives.getValue(name)
            assertTrue("$name is static", Modifier.isStatic(m.modifiers))
            assertEquals(name, params, m.parameterTypes.toList())
        }
        assertEquals(Tracker.NO_POSE, Long.MIN_VALUE)
    }
}
