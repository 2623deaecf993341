package io.ecvo.shared

import io.ecvo.PoseTracker
import io.ecvo.PushStatus
import io.ecvo.ReferenceFrame
import io.ecvo.TimedPose
import io.ecvo.Tracker
import io.ecvo.TrackerConfig
import io.ecvo.TrackerStats
import io.ecvo.TrackingState
import java.io.File
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNotNull
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** A tracker without native code: counts pushes, answers with [statuses], can be made to fail. */
/** Keeps the latest [window] poses, as the native tracker keeps Tracker.TRAJECTORY_WINDOW. */
class FakeTracker(private val window: Int = Int.MAX_VALUE, private val statuses: (Int) -> PushStatus = { PushStatus.ACCEPTED }) : PoseTracker {
    val pushed = ArrayList<Long>()
    var failWith: RuntimeException? = null
    /** Refuses a timestamp not after the previous accepted one, with the native side's message. */
    var refuseOldTimestamps = false
    @Volatile private var closed = false
    override fun pushFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray): PushStatus {
        check(!closed) { "Tracker is closed" }
        failWith?.let { throw it }
        if (refuseOldTimestamps && pushed.isNotEmpty() && timestampNs <= pushed.last()) {
            throw IllegalArgumentException("timestamp ${timestampNs / 1e9} is not after the previous frame's (${pushed.last() / 1e9})")
        }
        pushed += timestampNs
        return statuses(pushed.size - 1)
    }
    override fun getPose(out: FloatArray): Long { check(!closed); return if (pushed.isEmpty()) Tracker.NO_POSE else pushed.last() }
    /** Gyroscope samples pushed: (timestamp, wx, wy, wz). */
    val imu = ArrayList<DoubleArray>()
    override fun pushImu(timestampsNs: LongArray, rates: FloatArray, count: Int) {
        check(!closed) { "Tracker is closed" }
        for (i in 0 until count) imu += doubleArrayOf(timestampsNs[i].toDouble(), rates[3 * i].toDouble(), rates[3 * i + 1].toDouble(), rates[3 * i + 2].toDouble())
    }
    override val state: TrackingState get() = if (pushed.isEmpty()) TrackingState.INITIALISING else TrackingState.TRACKING
    private val start: Int get() = maxOf(0, pushed.size - window)
    override fun stats(): TrackerStats = TrackerStats.EMPTY.copy(
        framesPushed = pushed.size.toLong(), framesTracked = pushed.size.toLong(), trajectoryStart = start.toLong(),
    )
    override fun trajectorySince(from: Int): List<TimedPose> {
        check(!closed)
        require(from >= start) { "poses before index $start were discarded" }
        return pushed.drop(from).map { TimedPose(it / 1e9, it.toDouble(), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0) }
    }
    override fun references(): List<ReferenceFrame> = emptyList()
    override fun pointCloud(maxPoints: Int): FloatArray = FloatArray(0)
    override fun flush() = Unit
    override val isClosed: Boolean get() = closed
    override fun close() { closed = true }
}

class SessionTest {
    private val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)
    private val config = TrackerConfig(width = 8, height = 8, fx = 10.0, fy = 10.0, cx = 3.5, cy = 3.5)
    private val depth = ShortArray(64) { 1000 }
    private val gray = ByteArray(64) { 7 }

    private class Source : SourceHandle {
        var stopped = 0
        override fun stop() { stopped++ }
    }

    private fun controller(tracker: () -> PoseTracker = { FakeTracker() }, libError: String? = null, clock: LongArray = longArrayOf(0)) =
        SessionController(newTracker = { tracker() }, nativeLibraryError = { libError }, post = { it() }, nowNs = { clock[0] })

    @Test
    fun everyDeliveredFrameIsRecordedEvenWhenTheTrackerDropsAnOlderOne() {
        val fake = FakeTracker { i -> if (i % 2 == 1) PushStatus.DROPPED else PushStatus.ACCEPTED }
        val dir = File(TestSupport.tempDir(), "rec")
        TrackingSession(fake).use { s ->
            s.startRecording(StreamRecorder(dir, cam))
            for (i in 1..6) s.push(i * 33_000_000L, depth, gray)
            assertEquals(6, s.stopRecordingAndWait()!!.recorder.framesWritten)
        }
        assertEquals(6, StreamReader(DirectoryFiles(dir)).frames.size)
    }

    @Test
    fun aRecorderThatFailsStopsRecordingWithAMessageAndTrackingGoesOn() {
        val fake = FakeTracker()
        val messages = java.util.Collections.synchronizedList(ArrayList<String>())
        val dir = File(TestSupport.tempDir(), "rec")
        val s = TrackingSession(fake) { messages += it }
        s.startRecording(StreamRecorder(dir, cam))
        s.push(1_000_000L, depth, gray)
        // Written on the recorder's thread: wait for it.
        val written = System.nanoTime() + 5_000_000_000L
        while (File(dir, "rgb.txt").readLines().none { !it.startsWith("#") } && System.nanoTime() < written) Thread.sleep(5)
        // The disk "fills": the depth folder becomes a file, so the next PNG cannot be written.
        File(dir, "depth").deleteRecursively()
        File(dir, "depth").writeText("not a folder")
        assertEquals(PushStatus.ACCEPTED, s.push(2_000_000L, depth, gray))
        assertEquals(PushStatus.ACCEPTED, s.push(3_000_000L, depth, gray))
        // The recorder runs on its own thread: the failure arrives there.
        val deadline = System.nanoTime() + 5_000_000_000L
        while (s.recording && System.nanoTime() < deadline) Thread.sleep(5)
        Thread.sleep(30)
        assertFalse(s.recording)
        assertEquals(1, messages.size)
        assertTrue(messages[0], messages[0].startsWith("Recording stopped") && messages[0].contains("1 frames"))
        assertEquals(3, fake.pushed.size)
        // What was written before the failure is still a readable stream.
        assertEquals(1, File(dir, "rgb.txt").readLines().count { !it.startsWith("#") })
        s.close()
    }

    @Test
    fun aFrameInFlightDuringResetIsIgnored() {
        val fake = FakeTracker()
        val s = TrackingSession(fake)
        s.close()
        assertNull(s.push(1, depth, gray))
    }

    @Test
    fun aMissingNativeLibraryEndsInAMessage() {
        val c = controller(libError = "The tracking library (libecvo_jni) could not be loaded")
        var opened = false
        assertFalse(c.start(FrameSource.REPLAY, config) { opened = true; Source() })
        assertFalse(opened)
        assertEquals(StatusKind.ERROR, c.presenter.status.kind)
        assertTrue(c.presenter.status.message!!.contains("libecvo_jni"))
        // And a LinkageError thrown by the constructor itself is caught too.
        val d = controller(tracker = { throw UnsatisfiedLinkError("no ecvo_jni in java.library.path") })
        assertFalse(d.start(FrameSource.REPLAY, config) { Source() })
        assertTrue(d.presenter.status.message!!.contains("no ecvo_jni"))
    }

    @Test
    fun withoutTheLibraryOnThisJvmTheTrackerSaysSoInsteadOfThrowing() {
        if (System.getProperty("ecvo.native") != null) {
            assertNull(Tracker.nativeLibraryError())
            return
        }
        val msg = Tracker.nativeLibraryError()
        assertNotNull(msg)
        assertTrue(msg!!, msg.contains("libecvo_jni"))
        // Asking again (NativeBridge's class init has failed by now) gives a message, not an exception.
        assertNotNull(Tracker.nativeLibraryError())
        val c = SessionController(post = { it() })
        assertFalse(c.start(FrameSource.REPLAY, config) { Source() })
        assertEquals(StatusKind.ERROR, c.presenter.status.kind)
    }

    @Test
    fun badConfigAndFailingSourcesEndInMessages() {
        val c = controller(tracker = { throw IllegalArgumentException("fx: NaN is not finite") })
        assertFalse(c.start(FrameSource.LIVE, config) { Source() })
        assertTrue(c.presenter.status.message!!.contains("fx"))
        val d = controller()
        assertFalse(d.start(FrameSource.LIVE, config) { throw IllegalStateException("setRepeatingRequest: session closed") })
        assertEquals(StatusKind.ERROR, d.presenter.status.kind)
        assertTrue(d.presenter.status.message!!.contains("setRepeatingRequest"))
        assertEquals(FrameSource.NONE, d.running)
    }

    @Test
    fun aTrackerErrorOnTheFrameThreadStopsTheSourceWithAMessage() {
        val fake = FakeTracker()
        val c = controller(tracker = { fake })
        val src = Source()
        lateinit var cb: SourceCallbacks
        assertTrue(c.start(FrameSource.LIVE, config) { cb = it; src })
        cb.frame(1, depth, gray)
        fake.failWith = RuntimeException("stage panicked")
        cb.frame(2, depth, gray) // must not throw
        assertEquals(1, src.stopped)
        assertEquals(StatusKind.ERROR, c.presenter.status.kind)
        assertTrue(c.presenter.status.message!!.contains("stage panicked"))
    }

    @Test
    fun aRefusedTimestampSkipsTheFrameAndTheSessionGoesOn() {
        val fake = FakeTracker().apply { refuseOldTimestamps = true }
        val c = controller(tracker = { fake })
        val src = Source()
        lateinit var cb: SourceCallbacks
        assertTrue(c.start(FrameSource.LIVE, config) { cb = it; src })
        val dir = File(TestSupport.tempDir(), "rec")
        assertTrue(c.startRecording { StreamRecorder(dir, it) })
        for (ts in longArrayOf(10_000_000, 20_000_000, 20_000_000, 15_000_000, 30_000_000)) cb.frame(ts, depth, gray)
        c.poll(FloatArray(16))
        assertEquals(0, src.stopped)
        assertEquals(FrameSource.LIVE, c.running)
        assertTrue(c.presenter.status.kind != StatusKind.ERROR)
        assertEquals(listOf(10_000_000L, 20_000_000L, 30_000_000L), fake.pushed)
        assertEquals(2L, c.session!!.refusedTimestamps)
        assertTrue(c.presenter.status.frames, c.presenter.status.frames.contains("2 bad timestamps skipped"))
        // The refused frames are not recorded either (the recording stays a valid stream).
        // The recorder finishes on a thread of its own: wait for it before reading.
        assertNotNull(c.session!!.stopRecordingAndWait())
        c.stopSource()
        assertEquals(3, StreamReader(DirectoryFiles(dir)).frames.size)
    }

    @Test
    fun otherBadInputStaysFatal() {
        val fake = FakeTracker()
        val c = controller(tracker = { fake })
        val src = Source()
        lateinit var cb: SourceCallbacks
        assertTrue(c.start(FrameSource.LIVE, config) { cb = it; src })
        fake.failWith = IllegalArgumentException("depth: 63 values, expected 64")
        cb.frame(1, depth, gray)
        assertEquals(1, src.stopped)
        assertEquals(StatusKind.ERROR, c.presenter.status.kind)
        assertTrue(c.presenter.status.message!!.contains("63 values"))
        assertFalse(Tracker.isRefusedTimestamp(IllegalStateException("timestamp 1 is not after the previous frame's (2)")))
        assertTrue(Tracker.isRefusedTimestamp(IllegalArgumentException("timestamp 1 is not after the previous frame's (2)")))
    }

    @Test
    fun anOldSourcesLateDisconnectDoesNotStopTheNewOne() {
        val c = controller()
        val first = Source(); val second = Source()
        lateinit var old: SourceCallbacks
        lateinit var now: SourceCallbacks
        c.start(FrameSource.LIVE, config) { old = it; first }
        c.start(FrameSource.LIVE, config) { now = it; second } // restart
        assertEquals(1, first.stopped)
        old.failed("camera 0 was disconnected") // the old camera closing
        old.frame(5, depth, gray)
        assertFalse(old.isCurrent)
        assertTrue(now.isCurrent)
        assertEquals(0, second.stopped)
        assertEquals(FrameSource.LIVE, c.running)
        assertNull(c.presenter.status.message)
        val fake = c.session!!.tracker as FakeTracker
        assertTrue(fake.pushed.isEmpty())
        now.failed("camera 0 was disconnected")
        assertEquals(1, second.stopped)
        assertEquals("camera 0 was disconnected", c.presenter.status.message)
    }

    @Test
    fun resumeKeepsTheTrackerAndTheTrajectory() {
        val fake = FakeTracker()
        val c = controller(tracker = { fake })
        lateinit var cb: SourceCallbacks
        c.start(FrameSource.LIVE, config) { cb = it; Source() }
        for (i in 1..3) cb.frame(i * 10L, depth, gray)
        c.poll(FloatArray(16))
        assertEquals(3, c.trajectory.nextIndex)
        c.stopSource() // onPause
        assertTrue(c.resume(FrameSource.LIVE) { cb = it; Source() })
        cb.frame(40, depth, gray)
        c.poll(FloatArray(16))
        assertEquals(4, c.trajectory.nextIndex)
        assertEquals(listOf(10L, 20L, 30L, 40L), fake.pushed)
        c.reset()
        assertTrue(fake.isClosed)
        assertFalse(c.resume(FrameSource.LIVE) { Source() })
        assertEquals(Tracker.NO_POSE, c.poll(FloatArray(16)))
    }

    @Test
    fun aPollAfterTheTrackersWindowMovedOnReadsFromTheWindowsStart() {
        val fake = FakeTracker(window = 8)
        val c = controller(tracker = { fake })
        lateinit var cb: SourceCallbacks
        c.start(FrameSource.REPLAY, config) { cb = it; Source() }
        for (i in 1..5) cb.frame(i * 10L, depth, gray)
        c.poll(FloatArray(16))
        assertEquals(5, c.trajectory.nextIndex)
        // 20 more frames without a poll: the tracker keeps only the last 8 (17..24).
        for (i in 6..25) cb.frame(i * 10L, depth, gray)
        c.poll(FloatArray(16))
        assertEquals(25, c.trajectory.nextIndex)
        assertTrue(c.presenter.status.kind != StatusKind.ERROR)
        assertEquals(listOf(10L, 20L, 30L, 40L, 50L) + (18..25).map { it * 10L }, c.trajectory.poses.map { Math.round(it.tx) })
    }

    @Test
    fun pollReadsOnlyNewPosesAndTheWindowedRate() {
        val fake = FakeTracker()
        val clock = longArrayOf(0)
        val c = controller(tracker = { fake }, clock = clock)
        lateinit var cb: SourceCallbacks
        c.start(FrameSource.REPLAY, config) { cb = it; Source() }
        for (step in 0 until 10) {
            for (k in 0 until 3) cb.frame(step * 100L + k, depth, gray)
            clock[0] += 100_000_000L // 30 frames per second
            c.poll(FloatArray(16))
        }
        assertEquals(30, c.trajectory.nextIndex)
        assertEquals(30, c.trajectory.poses.size)
        val st = c.presenter.status
        assertTrue(st.stages, st.stages.startsWith("30.0 fps"))
        cb.finished()
        assertEquals(FrameSource.NONE, c.running)
        assertEquals("Stopped", c.presenter.status.state)
    }

    @Test
    fun recordingNeedsARunningSourceAndReportsFailures() {
        val c = controller()
        assertFalse(c.startRecording { StreamRecorder(File(TestSupport.tempDir(), "r"), it) })
        assertNotNull(c.presenter.status.message)
        lateinit var cb: SourceCallbacks
        c.start(FrameSource.REPLAY, config) { cb = it; Source() }
        val used = File(TestSupport.tempDir(), "used")
        StreamRecorder(used, cam).close()
        assertFalse(c.startRecording { StreamRecorder(used, it) }) // refuses to overwrite
        assertTrue(c.presenter.status.message!!.contains("Recording could not start"))
        val dir = File(TestSupport.tempDir(), "ok")
        assertTrue(c.startRecording { StreamRecorder(dir, it) })
        cb.frame(1_000_000, depth, gray)
        c.stopSource() // stopping the source finishes the recording, on the recorder's thread
        assertFalse(c.presenter.status.recording)
        val deadline = System.nanoTime() + 5_000_000_000L
        fun frames() = Recordings.list(dir.parentFile).first { it.dir == dir }.frames
        while (frames() < 1 && System.nanoTime() < deadline) Thread.sleep(5)
        assertEquals(1, frames())
    }

    @Test
    fun theOldTrackerIsClosedBeforeTheNewOneIsCreated() {
        val made = ArrayList<FakeTracker>()
        val openAtCreate = ArrayList<Int>()
        val c = SessionController(
            newTracker = { openAtCreate += made.count { !it.isClosed }; FakeTracker().also { made += it } },
            nativeLibraryError = { null }, post = { it() }, nowNs = { 0L },
        )
        repeat(3) { assertTrue(c.start(FrameSource.REPLAY, config) { Source() }) }
        assertEquals(listOf(0, 0, 0), openAtCreate)
        assertEquals(listOf(true, true, false), made.map { it.isClosed })
        // A start whose tracker fails leaves no session behind (Share has nothing of the previous one).
        val failing = SessionController(newTracker = { throw IllegalArgumentException("bad config") }, nativeLibraryError = { null }, post = { it() })
        assertFalse(failing.start(FrameSource.REPLAY, config) { Source() })
        assertNull(failing.session)
    }

    @Test
    fun aPollErrorStopsTheSourceAsWellAsShowingError() {
        val inner = FakeTracker()
        val failing = object : PoseTracker by inner {
            override fun stats(): TrackerStats = throw RuntimeException("native state corrupted")
        }
        val c = SessionController(newTracker = { failing }, nativeLibraryError = { null }, post = { it() }, nowNs = { 0L })
        val src = Source()
        assertTrue(c.start(FrameSource.LIVE, config) { src })
        assertEquals(Tracker.NO_POSE, c.poll(FloatArray(16)))
        assertEquals(StatusKind.ERROR, c.presenter.status.kind)
        assertTrue(c.presenter.status.message!!, c.presenter.status.message!!.contains("native state corrupted"))
        assertEquals(1, src.stopped)
        assertEquals(FrameSource.NONE, c.running)
    }
}
