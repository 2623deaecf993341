package io.ecvo.shared

import io.ecvo.TrackerStats
import io.ecvo.TrackingState
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

class PresenterTest {
    private val sec = 1_000_000_000L

    private fun stats(tracked: Long, totalMs: Double, l1: Long = 0, l2: Long = 0, dropped: Long = 0, lost: Long = 0) =
        TrackerStats.EMPTY.copy(framesTracked = tracked, framesPushed = tracked + dropped, totalMs = totalMs, referencesL1 = l1, referencesL2 = l2, framesDropped = dropped, lostFrames = lost)

    @Test
    fun idleBeforeAnything() {
        val s = TrackingPresenter().status
        assertEquals("Stopped", s.state)
        assertEquals(StatusKind.IDLE, s.kind)
        assertEquals("– ms/frame", s.timing)
        assertEquals("0 frames", s.frames)
        assertNull(s.message)
        assertFalse(s.canStartLive) // not known yet whether there is a depth camera
    }

    @Test
    fun noDepthCameraIsSaidClearly() {
        val p = TrackingPresenter()
        p.onDepthCameraChecked(false)
        assertEquals(TrackingPresenter.NO_DEPTH_CAMERA, p.status.message)
        assertFalse(p.status.canStartLive)
        // Replay still runs, and the message stays.
        p.onStarted(FrameSource.REPLAY, 0)
        p.onTrackerUpdate(TrackingState.TRACKING, stats(10, 8.25), 100, sec / 10)
        assertEquals("Tracking", p.status.state)
        assertEquals(TrackingPresenter.NO_DEPTH_CAMERA, p.status.message)
    }

    @Test
    fun trackingShowsTimesAndReferences() {
        val p = TrackingPresenter()
        p.onDepthCameraChecked(true)
        p.onCameraPermission(true)
        assertTrue(p.status.canStartLive)
        p.onStarted(FrameSource.LIVE, 0)
        assertEquals("Initialising", p.status.state)
        p.onTrackerUpdate(TrackingState.TRACKING, stats(120, 12.345, l1 = 12, l2 = 3, dropped = 4, lost = 1), 5 * sec, sec)
        val s = p.status
        assertEquals(StatusKind.TRACKING, s.kind)
        assertEquals("12.3 ms/frame", s.timing)
        assertEquals("refs L1 12 · L2 3 · 0.00 m travelled", s.references)
        assertEquals("120 frames · 4 dropped · 1 lost", s.frames)
        assertNull(s.message)
        p.onTrackerUpdate(TrackingState.LOST, stats(121, 12.0), 5 * sec + 33, sec + 33)
        assertEquals("Lost", p.status.state)
        assertEquals(TrackingPresenter.LOST_HINT, p.status.message)
        p.onStopped()
        assertEquals("Stopped", p.status.state)
        assertEquals("121 frames", p.status.frames) // the last numbers stay visible
        assertNull(p.status.message)
    }

    @Test
    fun aStalledSourceIsReported() {
        val p = TrackingPresenter(stallAfterNs = 2 * sec)
        p.onStarted(FrameSource.LIVE, 10 * sec)
        p.onTrackerUpdate(TrackingState.TRACKING, stats(1, 5.0), 1000, 10 * sec + 1)
        p.onTrackerUpdate(TrackingState.TRACKING, stats(1, 5.0), 1000, 11 * sec)
        assertNull(p.status.message)
        p.onTrackerUpdate(TrackingState.TRACKING, stats(1, 5.0), 1000, 13 * sec)
        assertEquals(TrackingPresenter.STALLED, p.status.message)
        p.onTrackerUpdate(TrackingState.TRACKING, stats(2, 5.0), 2000, 13 * sec + 1)
        assertNull(p.status.message)
    }

    @Test
    fun permissionDenialAndErrors() {
        val p = TrackingPresenter()
        p.onDepthCameraChecked(true)
        p.onCameraPermission(false)
        assertEquals(TrackingPresenter.PERMISSION_DENIED, p.status.message)
        assertFalse(p.status.canStartLive)
        p.onStarted(FrameSource.REPLAY, 0) // replay is unaffected
        assertNull(p.status.message)
        p.onError("camera.json: missing field `fx`")
        assertEquals(StatusKind.ERROR, p.status.kind)
        assertEquals("camera.json: missing field `fx`", p.status.message)
        p.onStarted(FrameSource.REPLAY, 0)
        assertEquals("Initialising", p.status.state)
        p.onRecording(true)
        assertTrue(p.status.recording)
    }

    @Test
    fun theKeepScreenOnFlagChangesOnlyWhenTheStateDoes() {
        val sw = ScreenOnSwitch()
        // 20 polls a second: the window flag is touched at the first poll and at each change only.
        val live = listOf(false, false, true, true, true, true, false, false, true)
        val changes = live.map { sw.update(it) }
        assertEquals(listOf(false, null, true, null, null, null, false, null, true), changes)
        assertEquals(4, changes.count { it != null })
    }

    @Test
    fun theDistanceTravelledSumsEveryPoseAndIsShown() {
        val b = TrajectoryBuffer(maxPoints = 4)
        fun pose(x: Double, y: Double, z: Double) = io.ecvo.TimedPose(0.0, x, y, z, 0.0, 0.0, 0.0, 1.0)
        b.append(listOf(pose(0.0, 0.0, 0.0), pose(3.0, 4.0, 0.0)))
        b.append(listOf(pose(3.0, 4.0, 12.0)))
        assertEquals(17.0, b.distanceM, 1e-12)
        // Thinning the drawn path (8 more poses, 1 m apart) does not change the length.
        b.append((1..8).map { pose(3.0, 4.0, 12.0 + it) })
        assertTrue(b.poses.size <= 4)
        assertEquals(25.0, b.distanceM, 1e-12)
        val p = TrackingPresenter()
        p.onStarted(FrameSource.REPLAY, 0)
        p.onTrackerUpdate(TrackingState.TRACKING, TrackerStats.EMPTY.copy(framesTracked = 11, reanchors = 1), 1, 0)
        p.onDistance(b.distanceM)
        assertTrue(p.status.references, p.status.references.endsWith("25.00 m travelled"))
        assertTrue(p.status.frames, p.status.frames.contains("1 re-anchored"))
        b.clear()
        assertEquals(0.0, b.distanceM, 0.0)
    }
}
