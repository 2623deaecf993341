package io.ecvo.shared

import io.ecvo.Mode
import io.ecvo.Preset
import io.ecvo.ReferenceFrame
import io.ecvo.TimedPose
import java.io.File
import java.util.zip.ZipFile
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Test

class ExportAndSettingsTest {
    private fun pose(t: Double, x: Double) = TimedPose(t, x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)

    @Test
    fun settingsSurviveARoundTripAndGarbageFallsBackToDefaults() {
        val s = AppSettings(Preset.PC, Mode.L1, ConfidencePolicy.IGNORE, PreviewKind.DEPTH, pointCloud = true)
        assertEquals(s, AppSettings.fromMap(s.toMap()))
        assertEquals(AppSettings(), AppSettings.fromMap(emptyMap()))
        assertEquals(AppSettings(), AppSettings.fromMap(mapOf("preset" to "TABLET", "mode" to null, "confidence" to "x", "point_cloud" to "yes")))
    }

    @Test
    fun trajectoryBufferStaysSmallAndKeepsTheEnds() {
        val b = TrajectoryBuffer(maxPoints = 64)
        var i = 0
        repeat(100) { b.append(List(100) { pose((i++).toDouble(), 0.0) }) }
        assertEquals(10_000, b.nextIndex)
        assertTrue(b.poses.size in 32..64)
        assertEquals(0.0, b.poses.first().timestamp, 0.0)
        assertTrue(b.poses.last().timestamp > 9_000)
        // Kept poses stay in order, evenly spaced.
        val gaps = b.poses.zipWithNext { a, c -> c.timestamp - a.timestamp }.toSet()
        assertEquals(1, gaps.size)
        b.clear()
        assertEquals(0, b.nextIndex)
    }

    @Test
    fun exportWritesWhatTheHostToolsRead() {
        val dir = File(TestSupport.tempDir(), "session")
        val traj = listOf(pose(1.0, 0.0), pose(1.5, 0.1), pose(2.0, 0.2))
        val refs = listOf(ReferenceFrame(traj[0], 2), ReferenceFrame(traj[2], 1))
        val cloud = floatArrayOf(1f, 2f, 3f, 0.5f, 4f, 5f, 6f, 1f)
        val files = SessionExport.write(dir, traj, refs, cloud)
        assertEquals(listOf("trajectory.txt", "references.txt", "cloud.ply"), files.map { it.name })
        assertEquals(traj, TumTrajectory.read(File(dir, "trajectory.txt")))
        val refLines = File(dir, "references.txt").readLines().filter { !it.startsWith("#") }
        assertEquals(listOf("2 0.2 0 0 0 0 0 1 1 2"), refLines) // the first frame is not listed, as ecvo run does
        val ply = File(dir, "cloud.ply").readBytes()
        val header = String(ply, Charsets.US_ASCII).substringBefore("end_header\n") + "end_header\n"
        assertTrue(header.contains("element vertex 2") && header.contains("binary_little_endian"))
        assertEquals(header.length + 2 * 15, ply.size)
        assertEquals(128.toByte(), ply[header.length + 12])
        val zip = File(TestSupport.tempDir(), "s.zip")
        SessionExport.zip(dir, zip)
        ZipFile(zip).use { z ->
            assertEquals(setOf("session/trajectory.txt", "session/references.txt", "session/cloud.ply"), z.entries().toList().map { it.name }.toSet())
        }
    }

    @Test
    fun recordingsAreListedNewestFirstAndOtherFoldersSkipped() {
        val root = TestSupport.tempDir()
        val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)
        for (name in listOf("20260101-100000", "20260102-090000")) {
            StreamRecorder(File(root, name), cam).use { r -> for (i in 1..3) r.writeFrame(i * 1_000_000L, ShortArray(64), ByteArray(64)) }
        }
        File(root, "not-a-stream").mkdirs()
        val list = Recordings.list(root)
        assertEquals(listOf("20260102-090000", "20260101-100000"), list.map { it.name })
        assertEquals(3, list[0].frames)
        assertTrue(list[0].bytes > 0)
        assertEquals(emptyList<RecordingEntry>(), Recordings.list(File(root, "missing")))
    }
}

class PreviewTest {
    @Test
    fun previewShowsNearBrightFarDarkAndHolesApart() {
        val px = PreviewImage.depth(shortArrayOf(300, 4000, 0, 2150))
        assertEquals(0xFFFFFFFF.toInt(), px[0])
        assertEquals(0xFF000000.toInt(), px[1])
        assertEquals(PreviewImage.NO_DEPTH, px[2])
        assertEquals(0x80, px[3] and 0xFF) // half way: 255 - 127
        assertEquals(0xFF808080.toInt(), PreviewImage.intensity(byteArrayOf(0x80.toByte()))[0])
        val f = LatestFrame()
        assertEquals(null, f.takePreview(PreviewKind.DEPTH))
        f.put(shortArrayOf(300), byteArrayOf(1))
        assertEquals(null, f.takePreview(PreviewKind.NONE))
        assertEquals(0xFF010101.toInt(), f.takePreview(PreviewKind.INTENSITY)!![0])
        assertEquals(null, f.takePreview(PreviewKind.INTENSITY)) // nothing new since
    }

    @Test
    fun eachSettingsRowStepsThroughItsValuesAndSurvivesARestart() {
        var s = AppSettings()
        for (row in SettingsMenu.Row.entries) {
            val before = SettingsMenu.value(s, row)
            val stepped = SettingsMenu.step(s, row)
            assertTrue(row.name, SettingsMenu.value(stepped, row) != before)
            assertEquals(stepped, AppSettings.fromMap(stepped.toMap()))
            s = stepped
        }
        // Tracking resolution cycles auto -> native -> halved -> auto; replay speed 1 -> 2 -> 4 -> 0.5 -> 1.
        val r = SettingsMenu.Row.RESOLUTION
        assertEquals(listOf("native", "halved", "auto"), generateSequence(AppSettings()) { SettingsMenu.step(it, r) }.drop(1).take(3).map { it.trackingResolution.label }.toList())
        val sp = SettingsMenu.Row.REPLAY_SPEED
        assertEquals(listOf(2.0, 4.0, 0.5, 1.0), generateSequence(AppSettings()) { SettingsMenu.step(it, sp) }.drop(1).take(4).map { it.replaySpeed }.toList())
        // A stored speed that is not offered falls back to 1.
        assertEquals(1.0, AppSettings.fromMap(mapOf(AppSettings.KEY_REPLAY_SPEED to "3.0")).replaySpeed, 0.0)
        // The remembered fallbacks are shown, and Live cameras: depth only -> auto forgets them.
        val remembered = AppSettings().rememberDepthOnly("5+0")
        assertTrue(SettingsMenu.value(remembered, SettingsMenu.Row.LIVE_CAMERAS).contains("5+0"))
        val toDepthOnly = SettingsMenu.step(remembered, SettingsMenu.Row.LIVE_CAMERAS)
        assertEquals(LiveCameras.DEPTH_ONLY, toDepthOnly.liveCameras)
        assertTrue(SettingsMenu.step(toDepthOnly, SettingsMenu.Row.LIVE_CAMERAS).depthOnlyPairs.isEmpty())
        // The tracker's configuration follows the frames' camera and the settings.
        val c = AppSettings(pointCloud = true).trackerConfig(CameraIntrinsics(320, 240, 250.0, 250.0, 159.5, 119.5), FrameSource.LIVE)
        assertEquals(320, c.width); assertEquals(250.0, c.fx, 0.0); assertTrue(c.pointCloud)
        assertEquals(io.ecvo.Admission.LIVE, c.admission)
    }
}
