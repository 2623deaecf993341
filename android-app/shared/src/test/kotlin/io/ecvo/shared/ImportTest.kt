package io.ecvo.shared

import java.io.ByteArrayOutputStream
import java.io.File
import java.io.IOException
import java.util.zip.ZipEntry
import java.util.zip.ZipOutputStream
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertTrue
import org.junit.Test

/** Importing a stream from a zip into the recordings folder. */
class ImportTest {
    private val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)

    @Test
    fun anExportOfThisAppImportsAsARecordingThatReplays() {
        val dir = File(TestSupport.tempDir(), "rec")
        StreamRecorder(dir, cam).use { r -> for (i in 1..4) r.writeFrame(i * 1_000_000L, ShortArray(64) { i.toShort() }, ByteArray(64)) }
        val zip = ExportFiles.pack(ExportPlan(true, dir), File(TestSupport.tempDir(), "x"), "ecvo-1") { d -> File(d, "trajectory.txt").writeText("# t\n") }
        val recordings = TestSupport.tempDir()
        val a = zip.inputStream().use { StreamImport.fromZip(it, recordings, "imported") }
        assertEquals("imported", a.name)
        assertEquals(4, StreamReader(DirectoryFiles(a)).frames.size)
        assertEquals(1, Recordings.list(recordings).size)
        // Again: a second name, nothing left over from the unpacking.
        val b = zip.inputStream().use { StreamImport.fromZip(it, recordings, "imported") }
        assertEquals("imported-2", b.name)
        assertEquals(setOf("imported", "imported-2"), recordings.list()!!.toSet())
    }

    private fun zipOf(vararg entries: Pair<String, ByteArray>): ByteArray {
        val out = ByteArrayOutputStream()
        ZipOutputStream(out).use { z -> for ((n, b) in entries) { z.putNextEntry(ZipEntry(n)); z.write(b); z.closeEntry() } }
        return out.toByteArray()
    }

    @Test
    fun badZipsAreRefusedAndLeaveNothing() {
        val recordings = TestSupport.tempDir()
        // An entry escaping the folder.
        val evil = zipOf("../../evil.txt" to "x".toByteArray())
        val e1 = TestSupport.assertThrows<IOException> { StreamImport.fromZip(evil.inputStream(), recordings, "a") }
        assertTrue(e1.message!!, e1.message!!.contains("leaves"))
        // No stream in it.
        val none = zipOf("notes.txt" to "hello".toByteArray())
        TestSupport.assertThrows<IOException> { StreamImport.fromZip(none.inputStream(), recordings, "b") }
        // Too big once unpacked.
        val big = zipOf("s/camera.json" to ByteArray(2048))
        val e3 = TestSupport.assertThrows<IOException> { StreamImport.fromZip(big.inputStream(), recordings, "c", maxBytes = 1024) }
        assertTrue(e3.message!!, e3.message!!.contains("more than"))
        // A stream whose lists name missing images: refused at import, not at replay.
        val broken = zipOf("s/camera.json" to cam.toJson().toByteArray(), "s/rgb.txt" to "1.0 rgb/1.png\n".toByteArray(), "s/depth.txt" to "1.0 depth/1.png\n".toByteArray())
        TestSupport.assertThrows<IOException> { StreamImport.fromZip(broken.inputStream(), recordings, "d") }
        assertEquals(emptyList<String>(), recordings.list()!!.toList())
        assertFalse(File(recordings.parentFile, "evil.txt").exists())
    }
}
