package io.ecvo.shared

import io.ecvo.TrackerConfig
import java.util.concurrent.CountDownLatch
import java.util.concurrent.TimeUnit
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertTrue
import org.junit.Test

/** Replay pacing with pause, resume and speed; the controller pausing a replay with the activity. */
class ReplayPauseTest {
    private val ms = 1_000_000L

    @Test
    fun pausedTimeDoesNotCountAndSpeedKeepsThePosition() {
        val now = longArrayOf(1_000 * ms)
        val c = ReplayClock { now[0] }
        assertEquals(0L, c.waitNs(0)) // starts the clock
        assertEquals(100 * ms, c.waitNs(100 * ms))
        now[0] += 40 * ms
        assertEquals(60 * ms, c.waitNs(100 * ms))
        c.pause()
        assertTrue(c.paused)
        assertEquals(Long.MAX_VALUE, c.waitNs(100 * ms))
        now[0] += 10_000 * ms // 10 s in the background
        c.resume()
        assertFalse(c.paused)
        assertEquals(60 * ms, c.waitNs(100 * ms))
        // Twice as fast: 40 ms of stream played so far, so the 100 ms frame is 30 ms away.
        c.speed = 2.0
        assertEquals(30 * ms, c.waitNs(100 * ms))
        now[0] += 30 * ms
        assertEquals(0L, c.waitNs(100 * ms))
        TestSupport.assertThrows<IllegalArgumentException> { c.speed = 0.0 }
    }

    @Test
    fun aWaitingReplayThreadWaitsOutThePauseAndWakesOnResume() {
        val c = ReplayClock()
        c.waitNs(0)
        c.pause()
        val done = CountDownLatch(1)
        val t = Thread { c.awaitDue(0); done.countDown() }
        t.start()
        assertFalse("ran while paused", done.await(200, TimeUnit.MILLISECONDS))
        c.resume()
        assertTrue(done.await(5, TimeUnit.SECONDS))
        // Stopping a paused replay: the interrupt ends the wait.
        c.pause()
        val stopped = CountDownLatch(1)
        val t2 = Thread { try { c.awaitDue(0) } catch (e: InterruptedException) { stopped.countDown() } }
        t2.start()
        Thread.sleep(50)
        t2.interrupt()
        assertTrue(stopped.await(5, TimeUnit.SECONDS))
    }

    @Test
    fun theControllerPausesAReplayAndShowsIt() {
        class Replay : PausableSource {
            var pauses = 0
            var resumes = 0
            override fun pause() { pauses++ }
            override fun resume() { resumes++ }
            override fun stop() = Unit
        }
        val clock = longArrayOf(0)
        val c = SessionController(newTracker = { FakeTracker() }, nativeLibraryError = { null }, post = { it() }, nowNs = { clock[0] })
        val r = Replay()
        val config = TrackerConfig(width = 8, height = 8, fx = 10.0, fy = 10.0, cx = 3.5, cy = 3.5)
        assertTrue(c.start(FrameSource.REPLAY, config) { r })
        assertTrue(c.pause())
        assertTrue(c.pause()) // already paused: not paused twice
        assertEquals(1, r.pauses)
        assertEquals("Paused", c.presenter.status.state)
        // Long in the background: no "no new frames" message.
        clock[0] = 60_000 * ms
        c.poll(FloatArray(16))
        assertEquals(null, c.presenter.status.message)
        assertTrue(c.resumePaused())
        assertEquals(1, r.resumes)
        assertFalse(c.resumePaused())
        assertFalse(c.paused)
        // A source that cannot pause (live) is not paused.
        assertTrue(c.start(FrameSource.LIVE, config) { SourceHandle { } })
        assertFalse(c.pause())
    }
}
