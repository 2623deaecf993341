package io.ecvo.shared

import java.io.File
import java.util.zip.ZipFile
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNotEquals
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** Which recording an export attaches, unique zip names, deleting recordings. */
class ExportSelectionTest {
    private val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)

    private fun record(root: File, name: String, frames: Int = 2): File {
        val dir = File(root, name)
        StreamRecorder(dir, cam).use { r -> for (i in 1..frames) r.writeFrame(i * 1_000_000L, ShortArray(64), ByteArray(64)) }
        return dir
    }

    private fun entries(zip: File): List<String> = ZipFile(zip).use { z -> z.entries().toList().map { it.name }.sorted() }

    @Test
    fun theSessionsOwnStreamIsAttachedNeverAnEarlierSessionsRecording() {
        val root = TestSupport.tempDir()
        val old = record(root, "20260101-100000")
        val streams = SessionStreams()
        // Session 1 (live) records `old`; session 2 replays the sample: nothing attached.
        streams.onStarted(null)
        streams.onRecording(old)
        assertEquals(ExportPlan(true, old), ExportSelection.forSession(true, streams.stream))
        streams.onStarted(null)
        assertEquals(ExportPlan(true, null), ExportSelection.forSession(true, streams.stream))
        // Session 3 replays `old`: its stream is attached.
        streams.onStarted(old)
        assertEquals(ExportPlan(true, old), ExportSelection.forSession(true, streams.stream))
        assertNull(ExportSelection.forSession(false, streams.stream))
        // Deleted meanwhile: the session is exported without it.
        assertTrue(Recordings.delete(root, old))
        assertEquals(ExportPlan(true, null), ExportSelection.forSession(true, streams.stream))
        streams.onDeleted(old)
        assertNull(streams.stream)
    }

    @Test
    fun aChosenRecordingIsExportedWhateverSessionRuns() {
        val root = TestSupport.tempDir()
        val a = record(root, "20260101-100000")
        val b = record(root, "20260102-100000")
        // The session replays b; the user exports a (an earlier run's): a's stream, no results.
        assertEquals(ExportPlan(false, a), ExportSelection.forRecording(a, true, b))
        // Exporting b, the session's own: its stream with the results.
        val viaOtherPath = ExportSelection.forRecording(File(root, "./20260102-100000"), true, b)
        assertTrue(viaOtherPath.withSession)
        assertEquals(ExportPlan(true, b), ExportSelection.forRecording(b, true, b))
        assertEquals(ExportPlan(false, b), ExportSelection.forRecording(b, false, b))
        assertEquals(ExportPlan(false, a), ExportSelection.forRecording(a, true, null))
    }

    @Test
    fun eachExportKeepsItsOwnZipAndHoldsTheChosenStream() {
        val root = TestSupport.tempDir()
        val a = record(root, "20260101-100000", frames = 3)
        val exports = File(TestSupport.tempDir(), "exports")
        var sessionWrites = 0
        val write = { d: File -> sessionWrites++; File(d, "trajectory.txt").writeText("# t\n"); Unit }
        val z1 = ExportFiles.pack(ExportPlan(false, a), exports, "ecvo-20260103-120000", write)
        val z2 = ExportFiles.pack(ExportPlan(true, a), exports, "ecvo-20260103-120000", write)
        assertNotEquals(z1, z2)
        assertEquals("ecvo-20260103-120000-2.zip", z2.name)
        assertTrue("the first export is still there", z1.isFile)
        assertEquals(1, sessionWrites) // only the plan with the session wrote it
        val e1 = entries(z1)
        assertTrue(e1.toString(), e1.contains("ecvo-20260103-120000/stream/camera.json"))
        assertFalse(e1.any { it.endsWith("trajectory.txt") })
        assertEquals(3, e1.count { it.contains("/stream/depth/") })
        val e2 = entries(z2)
        assertTrue(e2.contains("ecvo-20260103-120000-2/trajectory.txt"))
        assertTrue(e2.contains("ecvo-20260103-120000-2/stream/depth.txt"))
        // No working folders left behind, only the zips.
        assertEquals(setOf(z1.name, z2.name), exports.list()!!.toSet())
        // A recording deleted before its export: an error, no zip.
        Recordings.delete(root, a)
        TestSupport.assertThrows<java.io.IOException> { ExportFiles.pack(ExportPlan(false, a), exports, "x", write) }
        assertEquals(setOf(z1.name, z2.name), exports.list()!!.toSet())
    }

    @Test
    fun onlyTheOldestZipsBeyondTheLimitArePruned() {
        val dir = TestSupport.tempDir()
        val zips = (1..5).map { i -> File(dir, "e$i.zip").also { it.writeText("$i"); it.setLastModified(1_000_000L * i) } }
        File(dir, "notes.txt").writeText("kept")
        val removed = ExportFiles.prune(dir, keep = 2, spare = zips[0])
        assertEquals(listOf("e3.zip", "e2.zip"), removed.map { it.name })
        assertEquals(setOf("e1.zip", "e4.zip", "e5.zip", "notes.txt"), dir.list()!!.toSet())
    }

    @Test
    fun deleteRemovesOnlyARecordingOfTheFolderThatIsNotInUse() {
        val root = TestSupport.tempDir()
        val a = record(root, "20260101-100000")
        val b = record(root, "20260102-100000")
        val elsewhere = record(TestSupport.tempDir(), "20260103-100000")
        File(root, "not-a-stream").mkdirs()
        assertFalse("in use", Recordings.delete(root, b, inUse = b))
        assertFalse("outside the recordings folder", Recordings.delete(root, elsewhere))
        assertFalse("not a stream", Recordings.delete(root, File(root, "not-a-stream")))
        assertTrue(elsewhere.isDirectory)
        assertTrue(Recordings.delete(root, a, inUse = b))
        assertEquals(listOf("20260102-100000"), Recordings.list(root).map { it.name })
    }

    /** Unzips [zip] into a new folder; returns it. */
    private fun unzip(zip: File): File {
        val out = TestSupport.tempDir()
        ZipFile(zip).use { z ->
            for (e in z.entries()) {
                val f = File(out, e.name)
                f.parentFile.mkdirs()
                z.getInputStream(e).use { i -> f.outputStream().use { o -> i.copyTo(o) } }
            }
        }
        return out
    }

    @Test
    fun aStreamBeingWrittenIsZippedAsItsListsSaidWithoutACopy() {
        val root = TestSupport.tempDir()
        val dir = File(root, "live")
        val rec = StreamRecorder(dir, cam)
        for (i in 1..3) rec.writeFrame(i * 1_000_000L, ShortArray(64) { i.toShort() }, ByteArray(64))
        // Mid-frame 4: its PNGs are on disk, its rgb.txt line is half written, depth.txt has none yet.
        File(dir, "rgb/0.004000.png").writeBytes(Png.encodeGray8(ByteArray(64), 8, 8))
        File(dir, "depth/0.004000.png").writeBytes(byteArrayOf(1, 2, 3)) // a PNG still being written
        File(dir, "rgb.txt").appendText("0.004000 rgb/0.0040")
        val exports = File(TestSupport.tempDir(), "exports")
        val zip = ExportFiles.pack(ExportPlan(false, dir), exports, "e") { }
        ZipFile(zip).use { z ->
            val names = z.entries().toList().map { it.name }
            assertEquals(3, names.count { it.startsWith("e/stream/depth/") })
            assertFalse(names.contains("e/stream/depth/0.004000.png"))
            assertFalse(names.contains("e/stream/rgb/0.004000.png"))
            // PNGs stored as they are, the lists deflated.
            assertEquals(java.util.zip.ZipEntry.STORED, z.getEntry("e/stream/depth/0.003000.png").method)
            assertEquals(java.util.zip.ZipEntry.DEFLATED, z.getEntry("e/stream/rgb.txt").method)
        }
        val stream = File(unzip(zip), "e/stream")
        assertFalse(File(stream, "rgb.txt").readText().contains("0.0040"))
        val r = StreamReader(DirectoryFiles(stream))
        assertEquals(3, r.frames.size)
        assertEquals(3, r.toList().last().depth[0].toInt())
        // Nothing but the zip is written beside it (no copy of the recording).
        assertEquals(listOf(zip.name), exports.list()!!.toList())
        rec.close()
    }

    @Test
    fun exportsTakenWhileARecorderWritesAreAlwaysReadableStreams() {
        val dir = File(TestSupport.tempDir(), "rec")
        val cam64 = CameraIntrinsics(64, 48, 60.0, 60.0, 31.5, 23.5)
        val rec = StreamRecorder(dir, cam64)
        rec.writeFrame(1_000_000L, ShortArray(64 * 48) { 1001 }, ByteArray(64 * 48) { 5 })
        val writing = Thread {
            for (i in 2..400) rec.writeFrame(i * 1_000_000L, ShortArray(64 * 48) { (1000 + i).toShort() }, ByteArray(64 * 48) { i.toByte() })
        }
        writing.start()
        val exports = File(TestSupport.tempDir(), "exports")
        val counts = ArrayList<Int>()
        while (writing.isAlive || counts.isEmpty()) {
            val zip = ExportFiles.pack(ExportPlan(false, dir), exports, "x") { }
            val frames = StreamReader(DirectoryFiles(File(unzip(zip), zip.name.removeSuffix(".zip") + "/stream"))).toList()
            // Every listed frame decodes, with the values its frame was written with.
            frames.forEachIndexed { k, f -> assertEquals(1000 + k + 1, f.depth[0].toInt()) }
            counts += frames.size
        }
        writing.join()
        rec.close()
        assertTrue(counts.toString(), counts.zipWithNext().all { (a, b) -> b >= a })
        assertTrue(counts.first() >= 1)
    }
}
