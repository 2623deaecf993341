package io.ecvo.shared

import io.ecvo.PushStatus
import org.junit.Assert.assertEquals
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** One monotonic timeline for the frames of successive camera instances. */
class TimelineTest {
    private val depth = ShortArray(64) { 1000 }
    private val gray = ByteArray(64) { 7 }
    private val ms = 1_000_000L

    @Test
    fun aSecondCameraInstanceWhoseClockRestartsLowerContinuesTheTimeline() {
        val fake = FakeTracker().apply { refuseOldTimestamps = true }
        val s = TrackingSession(fake)
        // Instance 1 (UNKNOWN clock): raw 5.000 s.. every 33 ms, arriving at wall 100 s...
        s.timeline.newInstance(realtimeClock = false)
        for (i in 0 until 10) assertEquals(PushStatus.ACCEPTED, s.push(5_000 * ms + i * 33 * ms, depth, gray, 100_000 * ms + i * 33 * ms))
        // A pause of 4 s; instance 2's clock restarted at 0.2 s.
        s.timeline.newInstance(realtimeClock = false)
        for (i in 0 until 10) assertEquals(PushStatus.ACCEPTED, s.push(200 * ms + i * 33 * ms, depth, gray, 104_297 * ms + i * 33 * ms))
        // Instance 3 restarts lower again, after 1 s.
        s.timeline.newInstance(realtimeClock = false)
        for (i in 0 until 5) assertEquals(PushStatus.ACCEPTED, s.push(10 * ms + i * 33 * ms, depth, gray, 105_594 * ms + i * 33 * ms))
        assertEquals(0L, s.refusedTimestamps)
        val t = fake.pushed
        assertEquals(25, t.size)
        for (i in 1 until t.size) assertTrue("not increasing at $i", t[i] > t[i - 1])
        // Instance 1 as it was; instance 2 starts 4 s (the wall-clock gap) after instance 1's last frame.
        assertEquals(5_000 * ms, t[0])
        assertEquals(5_297 * ms, t[9])
        assertEquals(5_297 * ms + 4_000 * ms, t[10])
        assertEquals(33 * ms, t[11] - t[10]) // its own spacing kept
        assertEquals(t[19] + 1_000 * ms, t[20])
    }

    @Test
    fun realtimeClocksAreUsedAsTheyAre() {
        val tl = CameraTimeline()
        tl.newInstance(realtimeClock = true)
        tl.accepted(tl.map(50_000 * ms, 50_010 * ms), 50_010 * ms)
        tl.newInstance(realtimeClock = true)
        assertEquals(53_000 * ms, tl.map(53_000 * ms, 53_010 * ms))
        // A REALTIME instance behind the timeline (should not happen) is still put after it.
        tl.accepted(53_000 * ms, 53_010 * ms)
        tl.newInstance(realtimeClock = true)
        assertEquals(53_000 * ms + 500 * ms, tl.map(1_000 * ms, 53_510 * ms))
    }

    @Test
    fun persistentRefusalsReBaseTheTimelineAndSaySo() {
        val fake = FakeTracker().apply { refuseOldTimestamps = true }
        val notices = ArrayList<String>()
        val s = TrackingSession(fake, onNotice = { notices += it })
        for (i in 0 until 5) s.push(9_000 * ms + i * 33 * ms, depth, gray, 1_000 * ms + i * 33 * ms)
        // The clock jumps back within the instance (no new instance reported): refused ...
        for (i in 0 until 4) assertNull(s.push(100 * ms + i * 33 * ms, depth, gray, 1_165 * ms + i * 33 * ms))
        assertTrue(notices.isEmpty())
        assertNull(s.push(100 * ms + 4 * 33 * ms, depth, gray, 1_165 * ms + 4 * 33 * ms))
        // ... five in a row: re-based, said once, and the next frames are taken.
        assertEquals(1, notices.size)
        assertTrue(notices[0], notices[0].contains("re-based"))
        assertEquals(1, s.timeline.rebases)
        assertEquals(5L, s.refusedTimestamps)
        for (i in 5 until 10) assertEquals(PushStatus.ACCEPTED, s.push(100 * ms + i * 33 * ms, depth, gray, 1_165 * ms + i * 33 * ms))
        val t = fake.pushed
        assertEquals(10, t.size)
        for (i in 1 until t.size) assertTrue(t[i] > t[i - 1])
        // The first re-based frame comes the wall-clock gap after the last accepted one.
        assertEquals(t[4] + (1_165 + 5 * 33 - 1_132) * ms, t[5])
    }

    @Test
    fun theControllerPutsEachCameraStartOnTheTimeline() {
        val fake = FakeTracker().apply { refuseOldTimestamps = true }
        val clock = longArrayOf(0)
        val c = SessionController(newTracker = { fake }, nativeLibraryError = { null }, post = { it() }, nowNs = { clock[0] })
        var cb = SourceCallbacks(c, -1)
        val config = io.ecvo.TrackerConfig(width = 8, height = 8, fx = 10.0, fy = 10.0, cx = 3.5, cy = 3.5)
        c.start(FrameSource.LIVE, config) { cb = it; SourceHandle { } }
        cb.cameraStarted(false)
        for (i in 0 until 3) { clock[0] = 10_000 * ms + i * 33 * ms; cb.frame(7_000 * ms + i * 33 * ms, depth, gray) }
        // onPause / onResume: a new source, whose camera clock restarted at 0.
        c.stopSource()
        assertTrue(c.resume(FrameSource.LIVE) { cb = it; SourceHandle { } })
        cb.cameraStarted(false)
        for (i in 0 until 3) { clock[0] = 12_000 * ms + i * 33 * ms; cb.frame(40 * ms + i * 33 * ms, depth, gray) }
        assertEquals(6, fake.pushed.size)
        assertEquals(0L, c.session!!.refusedTimestamps)
        assertEquals(fake.pushed[2] + (12_000 - 10_066) * ms, fake.pushed[3])
    }
}
