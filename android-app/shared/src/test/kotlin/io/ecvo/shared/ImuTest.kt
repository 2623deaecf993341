package io.ecvo.shared

import java.io.File
import java.io.IOException
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertNotNull
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** Issue 47 on the app's side: imu.txt written and read, the calibration, the clocks, the buffer, the session. */
class ImuTest {
    private val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)
    private val depth = ShortArray(64) { 1000 }
    private val gray = ByteArray(64) { (it * 3).toByte() }

    private fun ioError(text: String): String = TestSupport.assertThrows<IOException> { ImuFile.parse(text, "imu.txt") }.message!!

    // --- imu.txt ------------------------------------------------------------------------

    @Test
    fun recorderAndReaderRoundTripExactTimestamps() {
        val dir = TestSupport.tempDir()
        ImuRecorder(dir).use { r ->
            r.write(longArrayOf(1_000_000_001L, 1_002_500_000L, 1_002_500_000L), floatArrayOf(0.1f, -0.2f, 3.25f, 1e-7f, 0f, -35f, 9f, 9f, 9f), 3)
            r.write(longArrayOf(86_400_123_456_789L), floatArrayOf(0.5f, 0.25f, -0.125f), 1)
            assertEquals(3L, r.samplesWritten)
            assertEquals("a repeated timestamp is skipped, not written", 1L, r.samplesRefused)
        }
        val d = ImuFile.read(File(dir, ImuFile.FILE_NAME))
        assertArrayEquals(longArrayOf(1_000_000_001L, 1_002_500_000L, 86_400_123_456_789L), d.timestampsNs)
        // Written as the float's shortest decimal, read back as that decimal.
        assertArrayEquals(doubleArrayOf(0.1, -0.2, 3.25, 1e-7, 0.0, -35.0, 0.5, 0.25, -0.125), d.gyro, 0.0)
        assertNull(d.accel)
        TestSupport.assertThrows<IOException> { ImuRecorder(dir) } // never overwrites
    }

    @Test
    fun readsAccelerometerColumnsAndComments() {
        val d = ImuFile.parse("# timestamp wx wy wz ax ay az\n\n1.5 0 0 1 0 9.81 0\n  1.6\t0 0 2 0.1 9.8 0.2  \n# end\n")
        assertEquals(2, d.count)
        assertArrayEquals(longArrayOf(1_500_000_000L, 1_600_000_000L), d.timestampsNs)
        assertArrayEquals(doubleArrayOf(0.0, 0.0, 1.0, 0.0, 0.0, 2.0), d.gyro, 0.0)
        assertArrayEquals(doubleArrayOf(0.0, 9.81, 0.0, 0.1, 9.8, 0.2), d.accel!!, 0.0)
        assertEquals(0, ImuFile.parse("# only a header\n").count)
    }

    @Test
    fun hostileInputIsAnErrorNamingFileAndLine() {
        assertTrue(ioError("1 0 0\n").contains("imu.txt:1: expected `timestamp wx wy wz [ax ay az]`, found 3"))
        assertTrue(ioError("1 0 0 0 1 2\n").contains("found 6"))
        assertTrue(ioError("1 0 0 0\n2 0 0 0 1 2 3\n").contains("imu.txt:2: 7 fields, but the first sample had 4"))
        assertTrue(ioError("1 0 0 0\n1 0 0 0\n").contains("imu.txt:2: timestamp 1 is not after the previous one"))
        assertTrue(ioError("2 0 0 0\n1 0 0 0\n").contains("not after"))
        assertTrue(ioError("1 NaN 0 0\n").contains("`NaN` is not"))
        assertTrue(ioError("1 0 Infinity 0\n").contains("not finite"))
        assertTrue(ioError("1 0 0 x\n").contains("`x` is not a number"))
        assertTrue(ioError("1 0 0 1e30\n").contains("beyond any gyroscope"))
        assertTrue(ioError("1 0 0 0 0 0 -1e9\n").contains("beyond any accelerometer"))
        assertTrue(ioError("1e400 0 0 0\n").contains("imu.txt:1:"))
        assertTrue(ioError("99999999999999999999 0 0 0\n").contains("out of range"))
        assertTrue(ioError("0x10 0 0 0\n").contains("is not a number"))
        // A file without newlines cannot fill memory; a file over the limit is refused before reading.
        assertTrue(ioError("1".repeat(ImuFile.MAX_LINE_CHARS + 1)).contains("longer than"))
        val big = TestSupport.assertThrows<IOException> {
            ImuFile.read(java.io.ByteArrayInputStream(ByteArray(0)), ImuFile.MAX_BYTES + 1, "big/imu.txt")
        }
        assertTrue(big.message!!.contains("big/imu.txt: ${ImuFile.MAX_BYTES + 1} bytes"))
        // A stream that gives more than it declared (a growing file) is cut at the limit.
        val endless = object : java.io.InputStream() {
            override fun read(): Int = '\n'.code
        }
        val grown = TestSupport.assertThrows<IOException> { ImuFile.read(endless, 10, "grow/imu.txt") }
        assertTrue(grown.message!!.contains("more than the"))
        TestSupport.assertThrows<IOException> { ImuFile.read(TestSupport.tempDir()) } // a folder
    }

    // --- calibration ----------------------------------------------------------------------

    @Test
    fun cameraJsonCarriesTheCalibrationAndTheRustFieldsStay() {
        val r = ImuCalibration.cameraFromDevice(90, true)
        val imu = ImuCalibration(r, 0.0, "monotonic", gyroNoiseDensity = 1.2e-4)
        val text = cam.toJson(imu)
        assertEquals(cam, CameraIntrinsics.fromJson(text))
        assertTrue("camera.json holds only the keys ecvo-io knows: $text", !text.contains("clock"))
        val back = ImuCalibration.fromCameraJson(text)!!
        assertArrayEquals(r, back.rotationCameraImu, 1e-9)
        assertEquals(1.2e-4, back.gyroNoiseDensity!!, 0.0)
        assertNull(back.gyroBiasRandomWalk)
        assertNull(ImuCalibration.fromCameraJson(cam.toJson()))
        fun bad(imuJson: String) = TestSupport.assertThrows<IOException> {
            ImuCalibration.fromCameraJson("{\"width\": 8, \"imu\": $imuJson}", "c.json")
        }.message!!
        assertTrue(bad("[1]").contains("`imu` is not an object"))
        assertTrue(bad("{}").contains("camera_from_imu is missing"))
        val id = "[[1,0,0],[0,1,0],[0,0,1]]"
        assertTrue(bad("{\"camera_from_imu\": [[1,0,0],[0,1,0]]}").contains("has 2 rows"))
        assertTrue(bad("{\"camera_from_imu\": [1,0,0,0,1,0,0,0,1]}").contains("has 9 rows"))
        assertTrue(bad("{\"camera_from_imu\": [1,[0,1,0],[0,0,1]]}").contains("camera_from_imu[0] is not an array"))
        assertTrue(bad("{\"camera_from_imu\": [[1,0,0],[0,1],[0,0,1]]}").contains("camera_from_imu[1] has 2 values"))
        assertTrue(bad("{\"camera_from_imu\": [[2,0,0],[0,1,0],[0,0,1]]}").contains("not a rotation"))
        assertTrue(bad("{\"camera_from_imu\": [[-1,0,0],[0,1,0],[0,0,1]]}").contains("not a rotation")) // a mirror
        assertTrue(bad("{\"camera_from_imu\": $id, \"time_offset\": 5}").contains("time_offset"))
        assertTrue(bad("{\"camera_from_imu\": $id, \"gyro_noise_density\": -1}").contains("gyro_noise_density"))
        assertTrue(bad("{\"camera_from_imu\": [[1,0,0],[0,\"a\",0],[0,0,1]]}").contains("camera_from_imu[1][1] is not a number"))
        // The example of docs/imu.md reads.
        val doc = ImuCalibration.fromCameraJson("{\"width\": 640, \"imu\": {\"camera_from_imu\": $id, \"time_offset\": 0.012, " +
            "\"gyro_noise_density\": 0.000122, \"gyro_bias_random_walk\": 0.000014}}")!!
        assertEquals(0.012, doc.timeOffsetS, 0.0)
        assertEquals(0.000014, doc.gyroBiasRandomWalk!!, 0.0)
    }

    @Test
    fun cameraFromDeviceMapsGravityAsTheGravityAlignmentDoes() {
        for (o in listOf(0, 90, 180, 270)) for (back in listOf(true, false)) {
            val r = ImuCalibration.cameraFromDevice(o, back)
            assertTrue("orientation $o back $back is a rotation", ImuCalibration.isRotation(r))
            val g = doubleArrayOf(0.3, 9.2, 2.1)
            val n = Math.sqrt(g.sumOf { it * it })
            val viaR = ImuCalibration(r).toCamera(g[0] / n, g[1] / n, g[2] / n)
            assertArrayEquals(GravityAlignment.upInCamera(g[0], g[1], g[2], o, back), viaR, 1e-12)
        }
        // A back camera mounted at 90° (the usual): the device's y axis (up the screen in
        // portrait) is the image's -x (the sensor's long side runs along the phone), and
        // the device's z (out of the screen) is the camera's -z (it looks out of the back).
        val r = ImuCalibration(ImuCalibration.cameraFromDevice(90, true))
        assertArrayEquals(doubleArrayOf(-1.0, 0.0, 0.0), r.toCamera(0.0, 1.0, 0.0), 1e-12)
        assertArrayEquals(doubleArrayOf(0.0, 0.0, -1.0), r.toCamera(0.0, 0.0, 1.0), 1e-12)
    }

    // --- clocks ---------------------------------------------------------------------------

    @Test
    fun realtimeCamerasNeedNoOffset() {
        val c = CameraClock(realtimeSource = true, boottimeMinusMonotonicNs = 123)
        assertEquals(0L, c.offsetNs)
        assertEquals(CameraClock.Method.REALTIME, c.method)
        assertEquals(5_000L, c.toCamera(5_000L))
    }

    @Test
    fun anUnknownSourceOnTheMonotonicClockGetsTheBracketedOffset() {
        // BOOTTIME runs 3,600 s ahead of MONOTONIC (an hour of deep sleep since boot); the
        // camera stamps on MONOTONIC and frames arrive 8-30 ms later.
        val sleep = 3_600_000_000_000L
        var mono = 10_000_000_000L
        val monoClock = { mono += 1_000; mono }
        val bootClock = { mono + sleep + 500 } // read halfway between two monotonic reads
        val offset = CameraClock.bracket(bootClock, monoClock)
        assertEquals(sleep, offset)
        val c = CameraClock(false, offset, framesToMeasure = 10)
        for (i in 0 until 10) {
            assertNull(c.offsetNs)
            val t = 20_000_000_000L + i * 33_333_333L
            val latency = 8_000_000L + (i * 7_000_000L) % 22_000_000L
            c.onFrame(t, t + latency + sleep, t + latency)
        }
        assertEquals(CameraClock.Method.MONOTONIC, c.method)
        assertEquals(sleep, c.offsetNs)
        // A gyro sample taken at the same instant as a frame maps onto that frame's stamp.
        assertEquals(20_000_000_000L, c.toCamera(20_000_000_000L + sleep))
    }

    @Test
    fun anUnknownClockFallsBackToTheSmallestArrivalDelay() {
        // The camera's clock is neither: timestamps 5 s behind BOOTTIME's, 7 s off MONOTONIC's.
        val c = CameraClock(false, boottimeMinusMonotonicNs = 2_000_000_000L, framesToMeasure = 5)
        for (i in 0 until 5) {
            val t = 1_000_000_000L + i * 33_000_000L
            val latency = longArrayOf(12, 9, 30, 15, 11)[i] * 1_000_000L
            c.onFrame(t, t + 5_000_000_000L + latency, t - 7_000_000_000L + latency)
        }
        assertEquals(CameraClock.Method.ARRIVAL, c.method)
        assertEquals("smallest delay: 9 ms late at most", 5_009_000_000L, c.offsetNs)
    }

    // --- the buffer -----------------------------------------------------------------------

    @Test
    fun theBufferDrainsInOrderAndDropsTheOldestWhenFull() {
        val b = GyroBuffer(capacity = 4)
        val got = ArrayList<Long>()
        val sink = GyroSink { t, w, n -> for (i in 0 until n) { got += t[i]; assertEquals(t[i].toFloat(), w[3 * i + 2], 0f) } }
        assertEquals(0, b.drain(sink))
        for (i in 1..6) b.add(i.toLong(), 0f, 0f, i.toFloat())
        assertEquals(4, b.waiting)
        assertEquals(2L, b.dropped)
        assertEquals(4, b.drain(sink))
        assertEquals(listOf(3L, 4L, 5L, 6L), got)
        b.add(7, 0f, 0f, 7f)
        assertEquals(1, b.drain(sink))
        assertEquals(7L, got.last())
        b.add(8, 0f, 0f, 8f); b.clear()
        assertEquals(0, b.drain(sink))
    }

    @Test
    fun theBufferTakesASensorThreadWhileTheCameraThreadDrains() {
        val b = GyroBuffer(capacity = 64)
        val total = 200_000
        val producer = Thread {
            for (i in 1..total) b.add(i.toLong(), i.toFloat(), 0f, 0f)
        }
        var last = 0L
        var seen = 0L
        val sink = GyroSink { t, w, n ->
            for (i in 0 until n) {
                assertTrue("increasing: ${t[i]} after $last", t[i] > last)
                assertEquals(t[i].toFloat(), w[3 * i], 0f)
                last = t[i]
            }
            seen += n
        }
        producer.start()
        while (producer.isAlive) b.drain(sink)
        producer.join()
        b.drain(sink)
        assertEquals(total.toLong(), seen + b.dropped)
        assertEquals(total.toLong(), last)
    }

    // --- the session ----------------------------------------------------------------------

    @Test
    fun aSessionPutsTheSamplesOnTheFramesTimelineAndRecordsThem() {
        val dir = File(TestSupport.tempDir(), "rec")
        val fake = FakeTracker()
        TrackingSession(fake).use { s ->
            s.imuRotation = ImuCalibration.cameraFromDevice(90, true)
            // No clock yet (no live camera): samples wait, nothing is recorded.
            s.gyro.add(1, 0f, 0f, 0f)
            s.push(1_000_000_000L, depth, gray)
            assertEquals(0L, s.imuSamples)
            s.gyro.clear()
            // A camera on BOOTTIME whose second instance is re-based by the timeline.
            s.timeline.newInstance(realtimeClock = true)
            s.cameraClock = CameraClock(true, 0)
            val r = StreamRecorder(dir, cam, s.imuCalibration(ImuCalibration.cameraFromDevice(90, true)))
            s.startRecording(r)
            for (i in 0 until 4) {
                val frame = 2_000_000_000L + i * 33_000_000L
                for (k in 0 until 8) s.gyro.add(frame - 33_000_000L + k * 4_125_000L, k.toFloat(), 0f, 1f)
                s.push(frame, depth, gray, arrivalNs = frame + 10_000_000L)
            }
            assertEquals(32L, s.imuSamples)
            assertEquals(0L, s.imuSamplesDropped)
            // The tracker got them on the same clock, in the camera's axes: device (k, 0, 1)
            // is camera (0, -k, -1) for a back camera mounted at 90°.
            assertEquals(32, fake.imu.size)
            assertEquals(listOf(2_000_000_000.0 - 33_000_000.0 + 7 * 4_125_000.0, 0.0, -7.0, -1.0), fake.imu[7].toList())
            val res = s.stopRecordingAndWait()!!
            assertNull(res.error)
        }
        val imu = ImuFile.read(File(dir, ImuFile.FILE_NAME))
        assertEquals(32, imu.count)
        assertEquals(2_000_000_000L - 33_000_000L, imu.timestampsNs[0])
        assertEquals(2_000_000_000L + 3 * 33_000_000L - 33_000_000L + 7 * 4_125_000L, imu.timestampsNs[31])
        assertEquals(7.0, imu.gyro[3 * 31], 0.0)
        val cal = ImuCalibration.fromCameraJson(File(dir, CameraIntrinsics.FILE_NAME).readText())
        assertNotNull(cal)
        assertEquals(0.0, cal!!.timeOffsetS, 0.0)
        assertArrayEquals(ImuCalibration.cameraFromDevice(90, true), cal.rotationCameraImu, 1e-9)
        // The frames and the samples are on one clock: the reader sees both.
        val stream = StreamReader(dir)
        assertEquals(4, stream.size)
        assertEquals(2_000_000_000L, stream.frames[0].timestampNs)
    }

    @Test
    fun samplesBeforeTheClockIsMeasuredAreDroppedAndCounted() {
        TrackingSession(FakeTracker()).use { s ->
            s.timeline.newInstance(realtimeClock = false)
            s.cameraClock = CameraClock(false, 0, framesToMeasure = 3)
            for (i in 0 until 5) {
                val t = 1_000_000_000L + i * 33_000_000L
                s.gyro.add(t - 1_000L, 0f, 0f, 0f)
                s.push(t, depth, gray, arrivalNs = t + 5_000_000L, arrivalMonotonicNs = t + 5_000_000L)
            }
            // Frames 0 and 1 did not complete the measurement; from frame 2 on samples are placed.
            assertEquals(CameraClock.Method.MONOTONIC, s.cameraClock!!.method)
            assertEquals(3L, s.imuSamples)
            assertEquals(2L, s.imuSamplesDropped)
        }
    }
}
