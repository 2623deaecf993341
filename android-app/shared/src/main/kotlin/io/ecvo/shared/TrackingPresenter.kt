package io.ecvo.shared

import io.ecvo.TrackerStats
import io.ecvo.TrackingState
import java.util.Locale

/** Where frames come from. */
enum class FrameSource { NONE, REPLAY, LIVE }

/** Colour class of the state label. */
enum class StatusKind { IDLE, INITIALISING, TRACKING, LOST, ERROR }

/** What the status area shows, as ready-to-display English text. */
data class StatusText(
    /** "Stopped", "Paused", "Initialising", "Tracking", "Lost", "Error". */
    val state: String,
    val kind: StatusKind,
    /** "12.3 ms/frame" or "– ms/frame" before the first tracked frame. */
    val timing: String,
    /** "refs L1 12 · L2 3 · 1.25 m travelled" (the distance once a frame was tracked). */
    val references: String,
    /**
     * "120 frames · 3 dropped · 1 lost · 1 re-anchored" (started afresh after a loss; and "· 5 without colour" for live depth frames
     * dropped unpaired, "· 4 not recorded" for frames the recorder could not keep up
     * with, "· 2 bad timestamps skipped" for frames the tracker refused).
     */
    val frames: String,
    /** "28.4 fps · filter 4.1 · tracker 7.9 · latency 15.2 ms", or "" before the first tracked frame. */
    val stages: String,
    /** A sentence the user should read (no depth camera, permission denied, stalled, error), or null. */
    val message: String?,
    /** Whether the "live" start button should be enabled. */
    val canStartLive: Boolean,
    /** Whether frames are being recorded. */
    val recording: Boolean,
    /** What a live session streams ("depth + colour", "depth only"); "" otherwise. */
    val mode: String = "",
)

/**
 * Turns what the tracker and the camera say into what the UI shows. Plain state, no
 * Android: the activity forwards events and renders [status].
 *
 * Not thread-safe: call it from the UI thread.
 */
class TrackingPresenter(
    /** A running source with no new pose for this long (wall clock) is reported as stalled. */
    private val stallAfterNs: Long = 2_000_000_000L,
) {
    private var source = FrameSource.NONE
    private var depthCamera: Boolean? = null
    private var permissionDenied = false
    private var recording = false
    private var error: String? = null
    private var state = TrackingState.INITIALISING
    private var stats = TrackerStats.EMPTY
    private var lastPoseNs = Long.MIN_VALUE
    private var lastPoseChangeWallNs = 0L
    private var stalled = false
    private var fps = 0.0
    private var droppedNoColour = 0L
    private var skippedTimestamps = 0L
    private var recordingDropped = 0L
    private var liveMode: LiveMode? = null
    private var paused = false
    private var distanceM = 0.0
    private val notices = LinkedHashSet<String>()

    /** The result of looking for a camera with DEPTH_OUTPUT. */
    fun onDepthCameraChecked(available: Boolean) { depthCamera = available }

    /** The answer to the camera permission request. */
    fun onCameraPermission(granted: Boolean) { permissionDenied = !granted }

    /** A source started at wall-clock [nowNs]; clears the previous run's error, notices and numbers. */
    fun onStarted(src: FrameSource, nowNs: Long) {
        source = src
        paused = false
        error = null
        notices.clear()
        fps = 0.0
        droppedNoColour = 0
        skippedTimestamps = 0
        distanceM = 0.0
        liveMode = null
        state = TrackingState.INITIALISING
        stats = TrackerStats.EMPTY
        lastPoseNs = Long.MIN_VALUE
        lastPoseChangeWallNs = nowNs
        stalled = false
    }

    /** The source stopped (button, end of a replay); the last numbers stay visible. */
    fun onStopped() {
        source = FrameSource.NONE
        stalled = false
        paused = false
    }

    /** The source was paused or resumed at wall-clock [nowNs] (no stall is reported while paused). */
    fun onPaused(on: Boolean, nowNs: Long) {
        paused = on
        stalled = false
        lastPoseChangeWallNs = nowNs
    }

    /** Something failed (the message of an exception); shown until the next start. */
    fun onError(message: String) {
        error = message
        source = FrameSource.NONE
    }

    /**
     * Something the user should know that does not stop tracking (a recording that
     * failed, a camera-geometry fallback, confidence codes ignored); shown until the next
     * start, each sentence once.
     */
    fun onNotice(message: String) { notices += message }

    /** The windowed frame rate and the live depth frames dropped for want of a colour frame. */
    fun onRates(fps: Double, droppedNoColour: Long) {
        this.fps = fps
        this.droppedNoColour = droppedNoColour
    }

    /** The length of the tracked path so far, in metres. */
    fun onDistance(metres: Double) { distanceM = metres }

    /** The live source's mode (it may fall back to depth alone during the session). */
    fun onLiveMode(mode: LiveMode) { liveMode = mode }

    /** Frames skipped because the tracker refused their timestamp (the session went on). */
    fun onSkippedTimestamps(count: Long) { skippedTimestamps = count }

    /** Recording switched on or off; [dropped] frames the recorder's queue had no room for. */
    fun onRecording(on: Boolean, dropped: Long = recordingDropped) {
        recording = on
        recordingDropped = dropped
    }

    /**
     * A poll of the tracker at wall-clock [nowNs] (monotonic): its [state], [stats] and
     * the timestamp `getPose` returned ([poseTimestampNs], `Tracker.NO_POSE` if none).
     */
    fun onTrackerUpdate(state: TrackingState, stats: TrackerStats, poseTimestampNs: Long, nowNs: Long) {
        this.state = state
        this.stats = stats
        if (poseTimestampNs != lastPoseNs) {
            lastPoseNs = poseTimestampNs
            lastPoseChangeWallNs = nowNs
        }
        if (paused) lastPoseChangeWallNs = nowNs
        stalled = source != FrameSource.NONE && nowNs - lastPoseChangeWallNs > stallAfterNs
    }

    /** What to show now. */
    val status: StatusText
        get() {
            val (label, kind) = when {
                error != null -> "Error" to StatusKind.ERROR
                source == FrameSource.NONE -> "Stopped" to StatusKind.IDLE
                paused -> "Paused" to StatusKind.IDLE
                state == TrackingState.INITIALISING -> "Initialising" to StatusKind.INITIALISING
                state == TrackingState.TRACKING -> "Tracking" to StatusKind.TRACKING
                else -> "Lost" to StatusKind.LOST
            }
            val timing = if (stats.framesTracked > 0) String.format(Locale.ROOT, "%.1f ms/frame", stats.totalMs) else "– ms/frame"
            val refs = "refs L1 ${stats.referencesL1} · L2 ${stats.referencesL2}" +
                if (stats.framesTracked > 0) String.format(Locale.ROOT, " · %.2f m travelled", distanceM) else ""
            val frames = buildString {
                append(stats.framesTracked).append(" frames")
                if (stats.framesDropped > 0) append(" · ").append(stats.framesDropped).append(" dropped")
                if (droppedNoColour > 0) append(" · ").append(droppedNoColour).append(" without colour")
                if (recordingDropped > 0) append(" · ").append(recordingDropped).append(" not recorded")
                if (skippedTimestamps > 0) append(" · ").append(skippedTimestamps).append(" bad timestamps skipped")
                if (stats.lostFrames > 0) append(" · ").append(stats.lostFrames).append(" lost")
                if (stats.reanchors > 0) append(" · ").append(stats.reanchors).append(" re-anchored")
            }
            val stages = if (stats.framesTracked == 0L) "" else String.format(
                Locale.ROOT, "%.1f fps · filter %.1f · tracker %.1f · latency %.1f ms", fps, stats.filterMs, stats.trackerMs, stats.latencyMs,
            )
            val message = when {
                error != null -> error
                depthCamera == false -> NO_DEPTH_CAMERA
                permissionDenied && source != FrameSource.REPLAY -> PERMISSION_DENIED
                stalled -> STALLED
                source != FrameSource.NONE && state == TrackingState.LOST -> LOST_HINT
                notices.isNotEmpty() -> notices.joinToString("\n")
                else -> null
            }
            val mode = if (source == FrameSource.LIVE) liveMode?.label ?: "" else ""
            return StatusText(label, kind, timing, refs, frames, stages, message, depthCamera == true && !permissionDenied, recording, mode)
        }

    companion object {
        const val NO_DEPTH_CAMERA = "This phone has no depth camera, so live tracking is not available. You can still replay a recorded stream."
        const val PERMISSION_DENIED = "Camera access was denied, so live tracking is off. Replay still works; allow camera access in the system settings to track live."
        const val STALLED = "No new frames for a while."
        const val LOST_HINT = "Tracking lost: move back towards where tracking was last good, slowly."
    }
}
