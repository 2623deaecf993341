package io.ecvo.shared

/** What live tracking streams. */
enum class LiveMode(val label: String) {
    /** Depth from the depth camera, intensity from a colour camera facing the same way. */
    DEPTH_AND_COLOUR("depth + colour"),

    /**
     * Depth alone, the intensity plane all zero: the engine registers such a frame on
     * depth alone (`MotionConfig::depth_only_texture_fraction`: a frame with too few
     * textured pixels adds no photometric terms and skips the photometric spread check).
     */
    DEPTH_ONLY("depth only"),
}

/** Which camera of a live session failed. */
enum class LiveCamera { DEPTH, COLOUR }

/** How a camera failed, from Camera2's callbacks. */
enum class CameraFailure {
    /** `ERROR_CAMERA_IN_USE`, `ERROR_MAX_CAMERAS_IN_USE`: the phone will not run one more camera. */
    IN_USE,

    /** `onDisconnected`: another open (ours, or a higher-priority app's) took the camera. */
    DISCONNECTED,

    /** Anything else (device, service, configuration failures). */
    OTHER,
}

/** What a live source does after a camera failed. */
enum class FailureAction {
    /** Close the colour camera and go on with depth alone. */
    CONTINUE_DEPTH_ONLY,

    /** Close both cameras and reopen the depth camera alone. */
    RESTART_DEPTH_ONLY,

    /** Stop with the failure's message. */
    FAIL,
}

/** The mode a live session starts in, and a sentence for the user when it is not the full one. */
class LiveModeDecision(val mode: LiveMode, val note: String?)

/**
 * Chooses between depth + colour and depth-only live tracking. Plain Kotlin: the camera
 * source copies what Camera2 says (the arguments of [start], its failures) into it.
 *
 * Opening the colour camera beside the depth camera needs the phone to stream both at
 * once. From API 30, `CameraManager.getConcurrentCameraIds` lists the combinations it
 * guarantees; a pair missing from it (or any phone before API 30) is not refused, only
 * not guaranteed, so the source tries both, depth first, and falls back on failure:
 * the colour camera failing leaves depth running ([FailureAction.CONTINUE_DEPTH_ONLY]);
 * the depth camera taken away while both were open (in use, disconnected) reopens it
 * alone ([FailureAction.RESTART_DEPTH_ONLY]); colour frames that never come do the same
 * as a colour failure ([ColourWatch]).
 */
object LiveModePolicy {
    /**
     * The starting mode for depth camera [depthId] and colour camera [colourId] (null: no
     * colour camera faces the same way, or it has no usable stream); [concurrent] is
     * `getConcurrentCameraIds` (null before API 30).
     */
    fun start(depthId: String, colourId: String?, concurrent: List<Set<String>>?): LiveModeDecision = when {
        colourId == null -> LiveModeDecision(LiveMode.DEPTH_ONLY, fallbackNote("no colour camera with a usable stream faces the same way as the depth camera"))
        guaranteed(depthId, colourId, concurrent) -> LiveModeDecision(LiveMode.DEPTH_AND_COLOUR, null)
        // Not guaranteed (not listed, or before API 30): tried, with the fallbacks of onFailure.
        else -> LiveModeDecision(LiveMode.DEPTH_AND_COLOUR, null)
    }

    /** Whether the phone guarantees streaming both cameras at once (false also before API 30, where it cannot say). */
    fun guaranteed(depthId: String, colourId: String, concurrent: List<Set<String>>?): Boolean =
        concurrent != null && concurrent.any { depthId in it && colourId in it }

    /** What to do after [camera] failed with [failure] while streaming in [mode]. */
    fun onFailure(mode: LiveMode, camera: LiveCamera, failure: CameraFailure): FailureAction = when {
        mode == LiveMode.DEPTH_ONLY -> if (camera == LiveCamera.COLOUR) FailureAction.CONTINUE_DEPTH_ONLY else FailureAction.FAIL
        camera == LiveCamera.COLOUR -> FailureAction.CONTINUE_DEPTH_ONLY
        failure == CameraFailure.OTHER -> FailureAction.FAIL
        else -> FailureAction.RESTART_DEPTH_ONLY
    }

    /** The sentence shown when a session falls back to depth alone. */
    fun fallbackNote(why: String): String = "Tracking on depth alone: $why."
}

/**
 * Notices a colour stream that never delivers: after [depthFrames] depth frames with no
 * colour frame at all since the start, [onDepth] says to fall back to depth alone (once).
 * Not thread-safe: call from the camera thread.
 */
class ColourWatch(private val depthFrames: Int = 45) {
    private var depth = 0
    private var colour = false
    private var fired = false

    /** A colour frame arrived. */
    fun onColour() { colour = true }

    /** A depth frame arrived; true exactly once, when the colour stream is to be given up. */
    fun onDepth(): Boolean {
        if (colour || fired) return false
        depth++
        if (depth < depthFrames) return false
        fired = true
        return true
    }
}
