package io.ecvo.shared

import io.ecvo.Mode
import io.ecvo.Preset

/** The settings screen: one row per setting, each tap moves it to its next value. Plain Kotlin. */
object SettingsMenu {
    /** The rows, in screen order. */
    enum class Row {
        PRESET, MODE, CONFIDENCE, PREVIEW, POINT_CLOUD, LIVE_CAMERAS, RESOLUTION, REPLAY_SPEED;

        /** Whether a change shows at once (the others apply from the next start). */
        val appliesAtOnce: Boolean get() = this == PREVIEW || this == REPLAY_SPEED
    }

    /** The value [row] shows for [s]. */
    fun value(s: AppSettings, row: Row): String = when (row) {
        Row.PRESET -> s.preset.toString()
        Row.MODE -> s.mode.toString()
        Row.CONFIDENCE -> s.confidence.label
        Row.PREVIEW -> s.preview.name.lowercase()
        Row.POINT_CLOUD -> if (s.pointCloud) "on" else "off"
        Row.LIVE_CAMERAS -> s.liveCameras.label +
            if (s.depthOnlyPairs.isNotEmpty() && s.liveCameras == LiveCameras.AUTO) " (depth only remembered for ${s.depthOnlyPairs.sorted().joinToString()})" else ""
        Row.RESOLUTION -> s.trackingResolution.label
        Row.REPLAY_SPEED -> "${s.replaySpeed}x"
    }

    /** [s] with [row] moved to its next value (choosing Live cameras → auto forgets the remembered fallbacks). */
    fun step(s: AppSettings, row: Row): AppSettings = when (row) {
        Row.PRESET -> s.copy(preset = next(s.preset, Preset.entries))
        Row.MODE -> s.copy(mode = next(s.mode, Mode.entries))
        Row.CONFIDENCE -> s.copy(confidence = next(s.confidence, ConfidencePolicy.entries))
        Row.PREVIEW -> s.copy(preview = next(s.preview, PreviewKind.entries))
        Row.POINT_CLOUD -> s.copy(pointCloud = !s.pointCloud)
        Row.LIVE_CAMERAS -> s.withLiveCameras(next(s.liveCameras, LiveCameras.entries))
        Row.RESOLUTION -> s.copy(trackingResolution = next(s.trackingResolution, TrackingResolution.entries))
        Row.REPLAY_SPEED -> s.copy(replaySpeed = next(s.replaySpeed, AppSettings.REPLAY_SPEEDS))
    }

    private fun <T> next(v: T, all: List<T>): T = all[(all.indexOf(v) + 1) % all.size]
}
