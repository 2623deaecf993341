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

/** How a camera failed, from Camera2's callbacks and exceptions. */
enum class CameraFailure {
    /** `StateCallback.ERROR_CAMERA_IN_USE`: another client holds this camera. */
    IN_USE,

    /** `ERROR_MAX_CAMERAS_IN_USE`: the phone will not run one more camera. */
    MAX_CAMERAS_IN_USE,

    /** `ERROR_CAMERA_DISABLED`: a device policy disabled the camera. */
    DISABLED,

    /** `ERROR_CAMERA_DEVICE`: a fatal error of the camera device. */
    DEVICE,

    /** `ERROR_CAMERA_SERVICE`: the camera service failed. */
    SERVICE,

    /** `onDisconnected`: another open (ours, or a higher-priority app's) took the camera. */
    DISCONNECTED,

    /** `CameraCaptureSession.StateCallback.onConfigureFailed`: the stream was refused. */
    CONFIGURE_FAILED,

    /** A Camera2 call threw (`CameraAccessException`, `IllegalArgumentException`, ...). */
    EXCEPTION,

    /** An error code this app does not know. */
    OTHER,
    ;

    companion object {
        /** The failure of `CameraDevice.StateCallback.onError`'s [code] (the constants of API 21, values 1..5). */
        fun fromErrorCode(code: Int): CameraFailure = when (code) {
            1 -> IN_USE
            2 -> MAX_CAMERAS_IN_USE
            3 -> DISABLED
            4 -> DEVICE
            5 -> SERVICE
            else -> OTHER
        }
    }
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

/** The user's choice of live cameras (Settings → Live cameras). */
enum class LiveCameras(val label: String) {
    /** Depth + colour where the phone can, depth alone where it cannot (or failed before). */
    AUTO("auto"),

    /** Never open the colour camera. */
    DEPTH_ONLY("depth only"),
}

/**
 * Chooses between depth + colour and depth-only live tracking. Plain Kotlin: the camera
 * source copies what Camera2 says (the arguments of [start], its failures) into it.
 *
 * Opening the colour camera beside the depth camera needs the phone to stream both at
 * once. From API 30, `CameraManager.getConcurrentCameraIds` lists the combinations it
 * guarantees. A phone that lists combinations but not this pair is taken at its word
 * (depth alone). An empty list (many phones answer so, including ones that stream both)
 * or no answer (before API 30) is not a refusal: the source tries both, depth first, and
 * falls back on any failure of the pair ([onFailure]). A fallback is remembered for the
 * pair ([LiveFallbackMemory]), so the next Live on this phone starts with depth alone.
 */
object LiveModePolicy {
    /**
     * The starting mode for depth camera [depthId] and colour camera [colourId] (null: no
     * colour camera faces the same way, or it has no usable stream); [concurrent] is
     * `getConcurrentCameraIds` (null before API 30); [setting] the user's choice;
     * [remembered] whether this pair fell back to depth alone in an earlier session.
     */
    fun start(
        depthId: String,
        colourId: String?,
        concurrent: List<Set<String>>?,
        setting: LiveCameras = LiveCameras.AUTO,
        remembered: Boolean = false,
    ): LiveModeDecision = when {
        colourId == null -> depthOnly("no colour camera with a usable stream faces the same way as the depth camera")
        setting == LiveCameras.DEPTH_ONLY -> depthOnly("the setting Live cameras is \"depth only\"")
        guaranteed(depthId, colourId, concurrent) -> LiveModeDecision(LiveMode.DEPTH_AND_COLOUR, null)
        refused(depthId, colourId, concurrent) ->
            depthOnly("this phone does not list depth camera $depthId and colour camera $colourId among the cameras it streams at once")
        remembered -> depthOnly("depth and colour together failed on this phone before (Settings → Live cameras → auto tries again)")
        // Unknown (an empty list, or before API 30): tried, with the fallbacks of onFailure.
        else -> LiveModeDecision(LiveMode.DEPTH_AND_COLOUR, null)
    }

    private fun depthOnly(why: String) = LiveModeDecision(LiveMode.DEPTH_ONLY, fallbackNote(why))

    /** Whether the phone guarantees streaming both cameras at once (false also before API 30, where it cannot say). */
    fun guaranteed(depthId: String, colourId: String, concurrent: List<Set<String>>?): Boolean =
        concurrent != null && concurrent.any { depthId in it && colourId in it }

    /** Whether the phone lists the combinations it streams at once and this pair is not one of them. */
    fun refused(depthId: String, colourId: String, concurrent: List<Set<String>>?): Boolean =
        !concurrent.isNullOrEmpty() && !guaranteed(depthId, colourId, concurrent)

    /**
     * What to do after [camera] failed with [failure] while streaming in [mode]. With both
     * cameras open, any failure goes on with depth alone: the two opens race, so whichever
     * of them fails (in use, disconnected, device or service error, a stream
     * configuration refused) may have been pushed out by the other. A colour failure
     * keeps the depth camera; a depth failure reopens it alone. With depth alone, a depth
     * failure ends the session (no restart loop); a late colour failure changes nothing.
     */
    @Suppress("UNUSED_PARAMETER")
    fun onFailure(mode: LiveMode, camera: LiveCamera, failure: CameraFailure): FailureAction = when {
        camera == LiveCamera.COLOUR -> FailureAction.CONTINUE_DEPTH_ONLY
        mode == LiveMode.DEPTH_ONLY -> FailureAction.FAIL
        else -> FailureAction.RESTART_DEPTH_ONLY
    }

    /** Whether [action], taken in [mode], is a fallback of the pair that the next session should start with. */
    fun remembers(mode: LiveMode, action: FailureAction): Boolean =
        mode == LiveMode.DEPTH_AND_COLOUR && action != FailureAction.FAIL

    /** The sentence shown when a session falls back to depth alone. */
    fun fallbackNote(why: String): String = "Tracking on depth alone: $why."
}

/**
 * The camera pairs that fell back to depth alone on this phone (kept in the settings), so
 * that the next Live does not fail the same way. Choosing Live cameras → auto again
 * forgets them ([AppSettings.withLiveCameras]).
 */
object LiveFallbackMemory {
    /** The key of a depth + colour pair. */
    fun key(depthId: String, colourId: String): String = "$depthId+$colourId"

    /** The stored form of [pairs] (comma-separated keys; camera ids hold no commas). */
    fun encode(pairs: Set<String>): String = pairs.sorted().joinToString(",")

    /** [encode]'s inverse; blanks are skipped, never throws. */
    fun decode(text: String?): Set<String> =
        text?.split(',')?.map { it.trim() }?.filter { it.isNotEmpty() }?.toSet() ?: emptySet()
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
