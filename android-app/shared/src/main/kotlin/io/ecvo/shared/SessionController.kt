package io.ecvo.shared

import io.ecvo.Admission
import io.ecvo.PoseTracker
import io.ecvo.Tracker
import io.ecvo.TrackerConfig
import java.util.concurrent.atomic.AtomicLong

/** A running frame source (camera, replay thread), as the controller sees it. */
fun interface SourceHandle {
    /** Stops delivering frames; may return before the last callback has run (those are then ignored). */
    fun stop()
}

/**
 * What a frame source calls, bound to one start of a source: once the controller has
 * moved on (stopped, restarted), calls through an old instance are ignored. So a camera
 * being closed for a restart may still report `onDisconnected` without stopping the new one.
 */
class SourceCallbacks internal constructor(private val controller: SessionController, val token: Long) {
    /** A frame (any thread). */
    fun frame(timestampNs: Long, depthMm: ShortArray, intensity: ByteArray) = controller.onFrame(token, timestampNs, depthMm, intensity)

    /** The source failed (any thread): stops it and shows [message]. */
    fun failed(message: String) = controller.onSourceFailed(token, message)

    /** Something the user should know that does not stop the source (any thread). */
    fun notice(message: String) = controller.onSourceNotice(token, message)

    /**
     * A camera instance was opened (camera thread, before its first frame): its frames go
     * on the session's timeline after the earlier instances' ([CameraTimeline]);
     * [realtimeClock]: `SENSOR_INFO_TIMESTAMP_SOURCE` is REALTIME.
     */
    fun cameraStarted(realtimeClock: Boolean) = controller.onCameraStarted(token, realtimeClock)

    /** The live source's mode, shown on screen (any thread). */
    fun mode(mode: LiveMode) = controller.onSourceMode(token, mode)

    /** The source ended normally (end of a replay; any thread). */
    fun finished() = controller.onSourceFinished(token)

    /** Whether this source is still the current one. */
    val isCurrent: Boolean get() = controller.isCurrent(token)
}

/**
 * The session behind the screen, kept outside any activity (a process-wide holder keeps
 * it across rotation): the tracker, the source feeding it, recording, the incremental
 * trajectory and the status. Plain Kotlin, so every path (including each failure) runs
 * in JVM tests with a fake tracker.
 *
 * Threads: [start], [stopSource], [reset], [poll] and recording are called on the UI
 * thread; sources call their [SourceCallbacks] from any thread, and failures are handed
 * to the UI thread through [post]. No failure escapes as an exception: each ends as a
 * message in [presenter]'s status.
 */
class SessionController(
    private val newTracker: (TrackerConfig) -> PoseTracker = ::Tracker,
    private val nativeLibraryError: () -> String? = { Tracker.nativeLibraryError() },
    private val post: (() -> Unit) -> Unit,
    private val nowNs: () -> Long = System::nanoTime,
    /**
     * CLOCK_MONOTONIC (`System.nanoTime`), read beside [nowNs] (in the app
     * `elapsedRealtimeNanos`, the sensors' clock) to find which clock a camera with an
     * UNKNOWN timestamp source uses ([CameraClock]).
     */
    private val monotonicNs: () -> Long = System::nanoTime,
) {
    val presenter = TrackingPresenter()
    val trajectory = TrajectoryBuffer()
    private val rate = FrameRateWindow()
    private val token = AtomicLong(0)

    @Volatile var session: TrackingSession? = null
        private set
    private var source: SourceHandle? = null
    @Volatile private var kind = FrameSource.NONE
    private var frameCamera: CameraIntrinsics? = null

    /** What is running now. */
    val running: FrameSource get() = kind

    internal fun isCurrent(t: Long) = t == token.get()

    /**
     * Starts a fresh session: a new tracker for [config] (whose intrinsics describe the
     * frames) and the source [open] starts with the callbacks it must use. Returns false
     * (with the reason in the status) when the library, the tracker or the source failed.
     */
    fun start(kind: FrameSource, config: TrackerConfig, open: (SourceCallbacks) -> SourceHandle): Boolean {
        stopSource()
        // The old tracker goes before the new one is made: two at once would need twice
        // the memory (about 260 MB each at VGA).
        session?.close()
        session = null
        trajectory.clear()
        val tracker = newTrackerOrError(config) ?: return false
        session = TrackingSession(tracker) { msg -> post { presenter.onNotice(msg) } }
        frameCamera = CameraIntrinsics(config.width, config.height, config.fx, config.fy, config.cx, config.cy, if (config.depthScale > 0) config.depthScale else 1000.0)
        trajectory.clear()
        return openSource(kind, open)
    }

    /** Starts a new source feeding the current session's tracker (resume after a pause); false if there is none. */
    fun resume(kind: FrameSource, open: (SourceCallbacks) -> SourceHandle): Boolean {
        val s = session
        if (s == null || s.tracker.isClosed) return false
        stopSource()
        return openSource(kind, open)
    }

    private fun openSource(kind: FrameSource, open: (SourceCallbacks) -> SourceHandle): Boolean {
        val t = token.incrementAndGet()
        rate.clear()
        paused = false
        presenter.onStarted(kind, nowNs())
        this.kind = kind
        return try {
            source = open(SourceCallbacks(this, t))
            true
        } catch (e: Exception) {
            fail(t, describe("could not start the ${kind.name.lowercase()} source", e))
            false
        }
    }

    private fun newTrackerOrError(config: TrackerConfig): PoseTracker? {
        nativeLibraryError()?.let { presenter.onError(it); return null }
        return try {
            newTracker(config)
        } catch (e: LinkageError) {
            presenter.onError("The tracking library could not be loaded: ${e.message ?: e.javaClass.simpleName}")
            null
        } catch (e: Exception) {
            presenter.onError(describe("The tracker could not start", e))
            null
        }
    }

    internal fun onFrame(t: Long, timestampNs: Long, depthMm: ShortArray, intensity: ByteArray) {
        if (!isCurrent(t)) return
        val s = session ?: return
        try {
            if (kind == FrameSource.LIVE) {
                val arrival = nowNs()
                s.push(timestampNs, depthMm, intensity, arrival, monotonicNs())
            } else {
                s.push(timestampNs, depthMm, intensity, timestampNs)
            }
        } catch (e: Exception) {
            onSourceFailed(t, describe("Tracking stopped", e))
        }
    }

    internal fun onCameraStarted(t: Long, realtimeClock: Boolean) {
        if (!isCurrent(t)) return
        val s = session ?: return
        s.timeline.newInstance(realtimeClock)
        // Each camera instance's clock is matched to the sensors' afresh; samples
        // waiting from before it cannot be placed on its timeline.
        s.gyro.clear()
        s.cameraClock = CameraClock(realtimeClock, CameraClock.bracket(nowNs, monotonicNs))
    }

    internal fun onSourceFailed(t: Long, message: String) = post { fail(t, message) }

    internal fun onSourceNotice(t: Long, message: String) = post {
        if (isCurrent(t)) presenter.onNotice(message)
    }

    internal fun onSourceMode(t: Long, mode: LiveMode) = post {
        if (isCurrent(t)) presenter.onLiveMode(mode)
    }

    internal fun onSourceFinished(t: Long) = post {
        if (isCurrent(t)) stopSource()
    }

    private fun fail(t: Long, message: String) {
        if (!isCurrent(t)) return
        stopSource()
        presenter.onError(message)
    }

    /** Stops the source (the session and its trajectory stay); stops recording. */
    fun stopSource() {
        token.incrementAndGet()
        val s = source
        source = null
        kind = FrameSource.NONE
        paused = false
        if (s != null) {
            try {
                s.stop()
            } catch (e: Exception) {
                presenter.onNotice(describe("Stopping the source failed", e))
            }
        }
        stopRecording()
        presenter.onStopped()
    }

    /** Whether the running source is paused ([pause]). */
    var paused: Boolean = false
        private set

    /** Pauses the running source in place, if it can (a replay); true if it did. */
    fun pause(): Boolean {
        val s = source as? PausableSource ?: return false
        if (paused) return true
        s.pause()
        paused = true
        presenter.onPaused(true, nowNs())
        return true
    }

    /** Resumes a [pause]d source; true if it did. */
    fun resumePaused(): Boolean {
        val s = source as? PausableSource ?: return false
        if (!paused) return false
        s.resume()
        paused = false
        presenter.onPaused(false, nowNs())
        return true
    }

    /** Stops everything and releases the tracker. */
    fun reset() {
        stopSource()
        session?.close()
        session = null
        trajectory.clear()
        rate.clear()
    }

    /**
     * Reads the tracker (UI thread, every poll): state, stats, the latest pose into
     * [pose] and only the poses added since the last poll. Returns the pose's timestamp
     * or `Tracker.NO_POSE`.
     */
    fun poll(pose: FloatArray, extraDroppedNoColour: Long = 0): Long {
        val s = session ?: return Tracker.NO_POSE
        return try {
            val t = s.tracker
            val ts = t.getPose(pose)
            val stats = t.stats()
            val now = nowNs()
            rate.sample(now, stats.framesTracked)
            presenter.onTrackerUpdate(t.state, stats, ts, now)
            presenter.onRates(rate.fps, extraDroppedNoColour)
            presenter.onRecording(s.recording, s.recordingDropped)
            presenter.onSkippedTimestamps(s.refusedTimestamps)
            // Poses older than the tracker's window are gone (a UI that did not poll for
            // that long); draw on from the window's start.
            if (trajectory.nextIndex < stats.trajectoryStart) trajectory.skipTo(stats.trajectoryStart)
            trajectory.append(t.trajectorySince(trajectory.nextIndex))
            presenter.onDistance(trajectory.distanceM)
            ts
        } catch (e: IllegalStateException) {
            Tracker.NO_POSE // closed between the check and the calls
        } catch (e: RuntimeException) {
            // The screen says "Error": the source stops too, rather than feed a tracker that fails.
            stopSource()
            presenter.onError(describe("Reading the tracker failed", e))
            Tracker.NO_POSE
        }
    }

    /** Starts recording with the recorder [make] builds for the frames' camera; false (and a message) if it could not. */
    fun startRecording(make: (CameraIntrinsics) -> StreamRecorder): Boolean {
        val s = session
        val cam = frameCamera
        if (s == null || cam == null || kind == FrameSource.NONE) {
            presenter.onNotice("Start a replay or live tracking before recording.")
            return false
        }
        return try {
            s.startRecording(make(cam))
            presenter.onRecording(true, 0)
            true
        } catch (e: Exception) {
            presenter.onNotice(describe("Recording could not start", e))
            false
        }
    }

    /** Frames the current session's running or last recording had no room for (its queue was full). */
    val recordingDropped: Long get() = session?.recordingDropped ?: 0L

    /**
     * Stops recording and returns at once (never waits for the queue to drain on the
     * calling UI thread): false if none was running. When the recorder is written and
     * closed, [onFinished] runs through [post] with the result (a failure also becomes a
     * notice).
     */
    fun stopRecording(onFinished: (RecordingResult) -> Unit = {}): Boolean {
        val stopped = session?.stopRecording { res ->
            post {
                res.error?.let { presenter.onNotice(it) }
                onFinished(res)
            }
        } ?: false
        presenter.onRecording(false)
        return stopped
    }

    companion object {
        /** Admission for a source: a camera drops frames when busy, a replay never does. */
        fun admissionFor(kind: FrameSource): Admission = if (kind == FrameSource.LIVE) Admission.LIVE else Admission.OFFLINE

        internal fun describe(what: String, e: Throwable): String = "$what: ${e.message ?: e.javaClass.simpleName}"
    }
}
