package io.ecvo.shared

import io.ecvo.Mode
import io.ecvo.Preset

/** What the user can preview beside the trajectory. */
enum class PreviewKind { NONE, DEPTH, INTENSITY }

/**
 * The user's settings, kept across restarts as string pairs (Android's
 * `SharedPreferences`, or anything else): the paper's preset, the error-correction mode,
 * the DEPTH16 confidence policy, the preview, and whether to build the point cloud (for
 * export; it costs time per reference frame).
 */
data class AppSettings(
    val preset: Preset = Preset.PHONE,
    val mode: Mode = Mode.L2,
    val confidence: ConfidencePolicy = ConfidencePolicy.AUTO,
    val preview: PreviewKind = PreviewKind.NONE,
    val pointCloud: Boolean = false,
) {
    /** The settings as string pairs for storage. */
    fun toMap(): Map<String, String> = mapOf(
        KEY_PRESET to preset.name, KEY_MODE to mode.name, KEY_CONFIDENCE to confidence.label,
        KEY_PREVIEW to preview.name, KEY_CLOUD to pointCloud.toString(),
    )

    companion object {
        const val KEY_PRESET = "preset"
        const val KEY_MODE = "mode"
        const val KEY_CONFIDENCE = "confidence"
        const val KEY_PREVIEW = "preview"
        const val KEY_CLOUD = "point_cloud"

        /** Reads stored pairs; a missing or unknown value falls back to the default, never throws. */
        fun fromMap(m: Map<String, String?>): AppSettings {
            val d = AppSettings()
            return AppSettings(
                preset = Preset.entries.firstOrNull { it.name == m[KEY_PRESET] } ?: d.preset,
                mode = Mode.entries.firstOrNull { it.name == m[KEY_MODE] } ?: d.mode,
                confidence = ConfidencePolicy.fromLabel(m[KEY_CONFIDENCE]),
                preview = PreviewKind.entries.firstOrNull { it.name == m[KEY_PREVIEW] } ?: d.preview,
                pointCloud = m[KEY_CLOUD]?.toBooleanStrictOrNull() ?: d.pointCloud,
            )
        }
    }
}
