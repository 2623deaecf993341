package io.ecvo.shared

import java.io.File
import java.io.IOException
import java.util.zip.ZipFile
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** metadata.json: device, versions, settings, intrinsics and gravity of a recording or an export. */
class MetadataTest {
    private val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)

    @Test
    fun metadataRoundTripsAndTravelsWithTheRecordingIntoAnExport() {
        val m = StreamMetadata(
            device = "samsung SM-G977N \"5G\"", android = "Android 12 (API 31)", app = "0.1.0",
            settings = AppSettings().rememberDepthOnly("0+1").toMap(), liveMode = "depth only", camera = cam,
            gravityUp = doubleArrayOf(0.0, -0.994522, 0.104528), imuClock = "monotonic",
        )
        val back = StreamMetadata.fromJson(m.toJson())
        assertEquals(m, back)
        assertEquals("monotonic", back.imuClock)
        assertArrayEquals(doubleArrayOf(0.0, -0.994522, 0.104528), back.gravityUp, 1e-9)
        assertEquals("0+1", AppSettings.fromMap(back.settings).depthOnlyPairs.single())
        assertEquals(cam, back.camera)
        // In a recording: replay finds it, an export carries it.
        val dir = File(TestSupport.tempDir(), "rec")
        StreamRecorder(dir, cam).use { r -> r.writeFrame(1_000_000L, ShortArray(64), ByteArray(64)) }
        m.write(dir)
        assertEquals(m, StreamMetadata.read(DirectoryFiles(dir)))
        val zip = ExportFiles.pack(ExportPlan(false, dir), File(TestSupport.tempDir(), "x"), "e") { }
        ZipFile(zip).use { z -> assertTrue(z.getEntry("e/stream/metadata.json") != null) }
        // None, or a broken one: the stream still replays, without metadata.
        val plain = File(TestSupport.tempDir(), "plain")
        StreamRecorder(plain, cam).use { r -> r.writeFrame(1_000_000L, ShortArray(64), ByteArray(64)) }
        assertNull(StreamMetadata.read(DirectoryFiles(plain)))
        File(plain, StreamMetadata.FILE_NAME).writeText("{\"device\": 3")
        assertNull(StreamMetadata.read(DirectoryFiles(plain)))
        TestSupport.assertThrows<IOException> { StreamMetadata.fromJson("{\"device\": \"x\", \"gravity_up\": [1, 2]}") }
        TestSupport.assertThrows<IOException> { StreamMetadata.fromJson("[]") }
    }
}
