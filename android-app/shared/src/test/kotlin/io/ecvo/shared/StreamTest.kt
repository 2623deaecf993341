package io.ecvo.shared

import io.ecvo.TimedPose
import io.ecvo.shared.TestSupport.assertThrows
import java.io.File
import java.io.IOException
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Assume.assumeTrue
import org.junit.Test

/** Recording and reading streams in the layout of `ecvo-io`. */
class StreamTest {
    private val camera = CameraIntrinsics(320, 180, 258.65, 258.25, 159.05, 97.4, 1000.0)

    private fun frame(k: Int): Pair<ShortArray, ByteArray> {
        val depth = ShortArray(camera.pixels) { i -> if ((i + k) % 11 == 0) 0 else (500 + (i * 7 + k * 13) % 4000).toShort() }
        val gray = ByteArray(camera.pixels) { i -> ((i % 320) + (i / 320) * 3 + k * 5).toByte() }
        return depth to gray
    }

    @Test
    fun timestampsAreFormattedWithSixDecimals() {
        assertEquals("0.000000", Timestamps.formatSeconds(0))
        assertEquals("1.000000", Timestamps.formatSeconds(1_000_000_000))
        assertEquals("1234.567890", Timestamps.formatSeconds(1_234_567_890_123))
        assertEquals("1.000001", Timestamps.formatSeconds(1_000_000_500)) // halves round up
        assertEquals("1.000000", Timestamps.formatSeconds(1_000_000_499))
        assertEquals("98765.000042", Timestamps.formatSeconds(98_765_000_042_000))
        assertEquals(1_305_031_102_175_304_000L, Timestamps.parseSecondsToNs("1305031102.175304"))
        assertEquals(1_500_000_000L, Timestamps.parseSecondsToNs("1.5"))
        assertEquals("1305031102.175304", Timestamps.plain(1305031102.175304))
        assertEquals("0.00001", Timestamps.plain(1e-5))
        assertEquals("-2", Timestamps.plain(-2.0))
        assertThrows<IllegalArgumentException> { Timestamps.formatSeconds(-1) }
    }

    @Test
    fun recorderWritesTheHostLayoutAndReaderReadsItBack() {
        val dir = File(TestSupport.tempDir(), "rec")
        val stamps = longArrayOf(1_000_000_000, 1_033_333_333, 1_066_666_667, 2_000_000_000)
        StreamRecorder(dir, camera).use { r ->
            for ((k, t) in stamps.withIndex()) {
                val (d, g) = frame(k)
                r.writeFrame(t, d, g)
            }
            assertEquals(4, r.framesWritten)
        }
        assertEquals(
            StreamRecorder.RGB_HEADER + "1.000000 rgb/1.000000.png\n1.033333 rgb/1.033333.png\n" +
                "1.066667 rgb/1.066667.png\n2.000000 rgb/2.000000.png\n",
            File(dir, "rgb.txt").readText(),
        )
        assertEquals(
            "# depth maps\n# file: 'ecvo recording'\n# timestamp filename\n1.000000 depth/1.000000.png\n",
            File(dir, "depth.txt").readLines().take(4).joinToString("") { "$it\n" },
        )
        assertEquals(
            "{\n  \"width\": 320,\n  \"height\": 180,\n  \"fx\": 258.65,\n  \"fy\": 258.25,\n  \"cx\": 159.05,\n" +
                "  \"cy\": 97.4,\n  \"depth_scale\": 1000.0\n}\n",
            File(dir, "camera.json").readText(),
        )
        assertTrue(File(dir, "depth/1.066667.png").isFile)

        val s = StreamReader(dir)
        assertEquals(camera, s.camera)
        assertEquals(4, s.size)
        assertNull(s.groundtruth)
        assertEquals(listOf(1_000_000_000L, 1_033_333_000L, 1_066_667_000L, 2_000_000_000L), s.frames.map { it.timestampNs })
        for ((k, f) in s.withIndex()) {
            val (d, g) = frame(k)
            assertEquals(k, f.index)
            assertArrayEquals(d, f.depth)
            assertArrayEquals(g, f.intensity)
        }
        assertEquals(1.066667, s.frames[2].timestamp, 0.0)
        assertEquals("depth/2.000000.png", s.frames[3].depth)
    }

    @Test
    fun recorderRefusesBadInput() {
        val dir = TestSupport.tempDir()
        StreamRecorder(dir, camera).use { r ->
            val (d, g) = frame(0)
            r.writeFrame(5_000_000_000, d, g)
            // Not after the previous frame once rounded to microseconds.
            assertThrows<IllegalArgumentException> { r.writeFrame(5_000_000_400, d, g) }
            assertThrows<IllegalArgumentException> { r.writeFrame(6_000_000_000, ShortArray(10), g) }
            assertThrows<IllegalArgumentException> { r.writeFrame(6_000_000_000, d, ByteArray(10)) }
            r.writeFrame(5_000_001_000, d, g)
            assertEquals(2, r.framesWritten)
        }
        // A stream is never overwritten.
        assertThrows<IOException> { StreamRecorder(dir, camera) }
        assertThrows<IOException> { StreamRecorder(File(dir, "x"), camera.copy(fx = 0.0)) }
        // The cut-short-safe lists read back.
        assertEquals(2, StreamReader(dir).size)
    }

    @Test
    fun groundtruthRoundTrips() {
        val dir = TestSupport.tempDir()
        val poses = listOf(
            TimedPose(1.0, 0.1, -0.2, 0.3, 0.0, 0.0, 0.0, 1.0),
            TimedPose(1305031102.175304, 1e-7, 2.5, -3.0, 0.5, 0.5, 0.5, 0.5),
        )
        StreamRecorder(dir, camera).use { r ->
            r.writeFrame(1_000_000_000, frame(0).first, frame(0).second)
            r.writeGroundtruth(poses)
        }
        val text = File(dir, "groundtruth.txt").readText()
        assertTrue(text, text.startsWith("# timestamp tx ty tz qx qy qz qw\n1 0.1 -0.2 0.3 0 0 0 1\n1305031102.175304 0.0000001 2.5 -3 0.5 0.5 0.5 0.5\n"))
        assertEquals(poses, StreamReader(dir).groundtruth)
        // Quaternions are normalised on reading; bad lines name file and line.
        assertEquals(0.6, TumTrajectory.parse("5 0 0 0 0 0 3 4", "t")[0].qz, 1e-15)
        val e = assertThrows<IOException> { TumTrajectory.parse("# c\n1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", "gt.txt") }
        assertTrue(e.message!!, e.message!!.startsWith("gt.txt:3:"))
        assertThrows<IOException> { TumTrajectory.parse("1 0 0 0 0 0 0", "t") }
    }

    @Test
    fun cameraJsonIsParsedAndCheckedLikeTheHostTools() {
        val ok = """{"width": 640, "height": 480, "fx": 517.3, "fy": 516.5, "cx": 318.6, "cy": 255.3, "depth_scale": 5000.0, "note": [1, "a\"b", null, true]}"""
        assertEquals(CameraIntrinsics(640, 480, 517.3, 516.5, 318.6, 255.3, 5000.0), CameraIntrinsics.fromJson(ok))
        assertEquals(camera, CameraIntrinsics.fromJson(camera.toJson()))
        val missing = assertThrows<IOException> { CameraIntrinsics.fromJson(ok.replace("\"fx\": 517.3, ", ""), "/x/camera.json") }
        assertTrue(missing.message!!, missing.message!!.contains("/x/camera.json") && missing.message!!.contains("fx"))
        val zero = assertThrows<IOException> { CameraIntrinsics.fromJson(ok.replace("517.3", "0.0")) }
        assertTrue(zero.message!!, zero.message!!.contains("fx"))
        assertThrows<IOException> { CameraIntrinsics.fromJson(ok.replace("516.5", "NaN")) }
        assertThrows<IOException> { CameraIntrinsics.fromJson(ok.replace("640", "640.5")) }
        assertThrows<IOException> { CameraIntrinsics.fromJson("[1, 2]") }
        assertThrows<IOException> { CameraIntrinsics.fromJson(ok.dropLast(1)) }
    }

    @Test
    fun associationIsOneToOneAndGreedy() {
        // The same cases as ecvo-io's association test.
        assertEquals(
            listOf(0 to 0, 1 to 1, 2 to 2),
            StreamReader.associate(doubleArrayOf(1.0, 1.012, 2.0, 5.0), doubleArrayOf(1.005, 1.02, 1.99, 3.0), 0.02),
        )
        assertTrue(StreamReader.associate(doubleArrayOf(1.0), doubleArrayOf(1.5), 0.5).isEmpty())
        assertEquals(listOf(0 to 0), StreamReader.associate(doubleArrayOf(1.0), doubleArrayOf(1.25), 0.5))
        assertEquals(listOf(0 to 1, 1 to 0), StreamReader.associate(doubleArrayOf(1.0, 2.0), doubleArrayOf(2.001, 0.999), 0.02))
    }

    @Test
    fun readerNamesTheFileAndLineOfBadLists() {
        val dir = TestSupport.tempDir()
        StreamRecorder(dir, camera).use { r -> r.writeFrame(1_000_000_000, frame(0).first, frame(0).second) }
        File(dir, "depth.txt").appendText("0.5 depth/x.png\n")
        val e = assertThrows<IOException> { StreamReader(dir) }
        assertTrue(e.message!!, e.message!!.contains("depth.txt:5"))
        File(dir, "depth.txt").writeText("1.0 depth/1.000000.png extra\n")
        assertTrue(assertThrows<IOException> { StreamReader(dir) }.message!!.contains("depth.txt:1"))
        File(dir, "depth.txt").writeText("9.0 depth/1.000000.png\n")
        assertTrue(assertThrows<IOException> { StreamReader(dir) }.message!!.contains("no colour/depth image pair"))
        File(dir, "depth.txt").writeText("1.0 depth/1.000000.png\n")
        File(dir, "camera.json").writeText(camera.copy(width = 640).toJson())
        assertTrue(assertThrows<IOException> { StreamReader(dir) }.message!!.contains("expected 640x180"))
        File(dir, "camera.json").delete()
        assertThrows<IOException> { StreamReader(dir) }
    }

    @Test
    fun readsATumSequenceLikeTheHostTools() {
        val dir = File(TestSupport.datasets, "tum_fr1_xyz_half")
        assumeTrue("no TUM dataset at $dir", dir.isDirectory)
        val s = StreamReader(dir)
        assertEquals(CameraIntrinsics(320, 240, 258.65, 258.25, 159.05, 127.4, 5000.0), s.camera)
        // 798 depth and 798 colour images; pairs within 20 ms.
        assertTrue("${s.size} frames", s.size in 780..798)
        val f0 = s.frames[0]
        assertEquals(1305031102.175304, f0.timestamp, 0.0)
        assertEquals(1305031102.160407, f0.depthTimestamp, 0.0)
        assertEquals(1_305_031_102_175_304_000L, f0.timestampNs)
        assertTrue(s.frames.all { kotlin.math.abs(it.timestamp - it.depthTimestamp) < 0.02 })
        assertTrue(s.frames.zipWithNext().all { (a, b) -> b.timestampNs > a.timestampNs })
        val gt = s.groundtruth!!
        assertTrue(gt.size > 1000)
        val frame = s.readFrame(10)
        assertEquals(320 * 240, frame.depth.size)
        assertTrue(frame.depth.count { it.toInt() != 0 } > frame.depth.size / 2)
    }

    @Test
    fun readsAndReRecordsTheRustWrittenSampleStream() {
        // testdata/synth_phone_320x180 is written by ecvo-io's SequenceWriter (Rust); the app
        // bundles it. Reading it and recording it again must give the same lists and camera
        // file byte for byte, and the same pixels.
        val dir = File(TestSupport.repo, "testdata/synth_phone_320x180")
        assumeTrue("no sample stream at $dir yet", File(dir, "rgb.txt").isFile)
        val s = StreamReader(dir)
        assertEquals(CameraIntrinsics(320, 180, 250.0, 250.0, 159.5, 89.5, 1000.0), s.camera)
        assertEquals(s.size, s.groundtruth!!.size)
        assertEquals(s.frames[0].timestamp, s.groundtruth[0].timestamp, 0.0)
        val copy = File(TestSupport.tempDir(), "copy")
        StreamRecorder(copy, s.camera).use { r ->
            for (f in s) {
                // Every Rust-written PNG decodes to what an independent decoder sees.
                if (f.index % 15 == 0) {
                    val info = s.frames[f.index]
                    val ref = javax.imageio.ImageIO.read(File(dir, info.depth)).raster.dataBuffer as java.awt.image.DataBufferUShort
                    assertArrayEquals(ref.data, f.depth)
                    val g = javax.imageio.ImageIO.read(File(dir, info.rgb)).raster.dataBuffer as java.awt.image.DataBufferByte
                    assertArrayEquals(g.data, f.intensity)
                }
                assertTrue(f.depth.count { it.toInt() != 0 } > f.depth.size / 2)
                r.writeFrame(f.timestampNs, f.depth, f.intensity)
            }
        }
        for (name in listOf("rgb.txt", "depth.txt", "camera.json")) {
            assertEquals(name, File(dir, name).readText(), File(copy, name).readText())
        }
        val again = StreamReader(copy)
        for (k in intArrayOf(0, s.size / 2, s.size - 1)) {
            assertArrayEquals(s.readFrame(k).depth, again.readFrame(k).depth)
            assertArrayEquals(s.readFrame(k).intensity, again.readFrame(k).intensity)
        }
    }
}
