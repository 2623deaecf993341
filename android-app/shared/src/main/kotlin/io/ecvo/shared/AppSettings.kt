package io.ecvo.shared

import io.ecvo.DepthFormat
import io.ecvo.Mode
import io.ecvo.Preset
import io.ecvo.TrackerConfig

/** What the user can preview beside the trajectory. */
enum class PreviewKind { NONE, DEPTH, INTENSITY }

/**
 * The user's settings, kept across restarts as string pairs (Android's
 * `SharedPreferences`, or anything else): the paper's preset, the error-correction mode,
 * the DEPTH16 confidence policy, the preview, whether to build the point cloud (for
 * export; it costs time per reference frame), the live cameras (with the pairs that fell
 * back to depth alone before) and the tracking resolution.
 */
data class AppSettings(
    val preset: Preset = Preset.PHONE,
    val mode: Mode = Mode.L2,
    val confidence: ConfidencePolicy = ConfidencePolicy.AUTO,
    val preview: PreviewKind = PreviewKind.NONE,
    val pointCloud: Boolean = false,
    /** Depth + colour where possible, or depth alone always. */
    val liveCameras: LiveCameras = LiveCameras.AUTO,
    /** Camera pairs that fell back to depth alone before ([LiveFallbackMemory] keys). */
    val depthOnlyPairs: Set<String> = emptySet(),
    /** The depth stream's size for the tracker: native, halved, or halved above QVGA. */
    val trackingResolution: TrackingResolution = TrackingResolution.AUTO,
    /** Replay speed, one of [REPLAY_SPEEDS] (1 = as recorded). */
    val replaySpeed: Double = 1.0,
) {
    /** These settings with the user's choice of live cameras; choosing auto forgets the remembered fallbacks (it tries again). */
    fun withLiveCameras(c: LiveCameras): AppSettings = copy(liveCameras = c, depthOnlyPairs = if (c == LiveCameras.AUTO) emptySet() else depthOnlyPairs)

    /** The tracker's configuration for frames of [camera] from a [kind] source, with these settings. */
    fun trackerConfig(camera: CameraIntrinsics, kind: FrameSource): TrackerConfig = TrackerConfig(
        width = camera.width, height = camera.height,
        fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy,
        depthFormat = if (camera.depthScale == 1000.0) DepthFormat.MILLIMETRES else DepthFormat.CUSTOM_SCALE,
        depthScale = camera.depthScale,
        preset = preset, mode = mode,
        admission = SessionController.admissionFor(kind),
        pointCloud = pointCloud,
    )

    /** These settings remembering that the pair [key] fell back to depth alone. */
    fun rememberDepthOnly(key: String): AppSettings = copy(depthOnlyPairs = depthOnlyPairs + key)

    /** The settings as string pairs for storage. */
    fun toMap(): Map<String, String> = mapOf(
        KEY_PRESET to preset.name, KEY_MODE to mode.name, KEY_CONFIDENCE to confidence.label,
        KEY_PREVIEW to preview.name, KEY_CLOUD to pointCloud.toString(),
        KEY_LIVE_CAMERAS to liveCameras.name, KEY_DEPTH_ONLY_PAIRS to LiveFallbackMemory.encode(depthOnlyPairs),
        KEY_RESOLUTION to trackingResolution.name, KEY_REPLAY_SPEED to replaySpeed.toString(),
    )

    companion object {
        const val KEY_PRESET = "preset"
        const val KEY_MODE = "mode"
        const val KEY_CONFIDENCE = "confidence"
        const val KEY_PREVIEW = "preview"
        const val KEY_CLOUD = "point_cloud"
        const val KEY_LIVE_CAMERAS = "live_cameras"
        const val KEY_DEPTH_ONLY_PAIRS = "depth_only_pairs"
        const val KEY_RESOLUTION = "tracking_resolution"
        const val KEY_REPLAY_SPEED = "replay_speed"

        /** The replay speeds offered. */
        val REPLAY_SPEEDS: List<Double> = listOf(0.5, 1.0, 2.0, 4.0)

        /** Reads stored pairs; a missing or unknown value falls back to the default, never throws. */
        fun fromMap(m: Map<String, String?>): AppSettings {
            val d = AppSettings()
            return AppSettings(
                preset = Preset.entries.firstOrNull { it.name == m[KEY_PRESET] } ?: d.preset,
                mode = Mode.entries.firstOrNull { it.name == m[KEY_MODE] } ?: d.mode,
                confidence = ConfidencePolicy.fromLabel(m[KEY_CONFIDENCE]),
                preview = PreviewKind.entries.firstOrNull { it.name == m[KEY_PREVIEW] } ?: d.preview,
                pointCloud = m[KEY_CLOUD]?.toBooleanStrictOrNull() ?: d.pointCloud,
                liveCameras = LiveCameras.entries.firstOrNull { it.name == m[KEY_LIVE_CAMERAS] } ?: d.liveCameras,
                depthOnlyPairs = LiveFallbackMemory.decode(m[KEY_DEPTH_ONLY_PAIRS]),
                trackingResolution = TrackingResolution.entries.firstOrNull { it.name == m[KEY_RESOLUTION] } ?: d.trackingResolution,
                replaySpeed = m[KEY_REPLAY_SPEED]?.toDoubleOrNull()?.takeIf { it in REPLAY_SPEEDS } ?: d.replaySpeed,
            )
        }
    }
}
