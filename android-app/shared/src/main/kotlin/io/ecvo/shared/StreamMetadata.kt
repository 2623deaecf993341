package io.ecvo.shared

import java.io.File
import java.io.IOException
import java.util.Locale

/**
 * `metadata.json` beside a recording's lists and in a session's export: what a tester or
 * the host tools need to know about where a stream came from. The device and Android
 * version, the app's version, the settings it ran with (string pairs, as stored), the live
 * mode, the frames' intrinsics, how the gyroscope's clock was matched, and gravity: world up in the first camera's frame (the
 * tracker's world), so that a replay draws the same gravity-aligned top view as the live
 * session. Every field but [device] may be missing; readers ignore what they do not know.
 */
data class StreamMetadata(
    /** "manufacturer model" (Android's `Build.MANUFACTURER`, `Build.MODEL`). */
    val device: String,
    /** "Android 14 (API 34)". */
    val android: String? = null,
    /** The app's version name. */
    val app: String? = null,
    /** The settings, as [AppSettings.toMap] stores them. */
    val settings: Map<String, String> = emptyMap(),
    /** "depth + colour", "depth only", or null (a replay). */
    val liveMode: String? = null,
    /** The intrinsics of the frames (also in `camera.json` for a recording). */
    val camera: CameraIntrinsics? = null,
    /** World up as a unit vector in the first camera's frame, or null (not measured). */
    val gravityUp: DoubleArray? = null,
    /** How the gyroscope's clock was put on the frames' ([CameraClock.Method] label), or null (no gyroscope). */
    val imuClock: String? = null,
) {
    init {
        require(gravityUp == null || (gravityUp.size == 3 && gravityUp.all { it.isFinite() })) { "gravityUp must be 3 finite numbers" }
    }

    /** The JSON text (pretty-printed, keys in a fixed order). */
    fun toJson(): String = buildString {
        append("{\n  \"device\": ").append(quote(device))
        android?.let { append(",\n  \"android\": ").append(quote(it)) }
        app?.let { append(",\n  \"app\": ").append(quote(it)) }
        liveMode?.let { append(",\n  \"live_mode\": ").append(quote(it)) }
        imuClock?.let { append(",\n  \"imu_clock\": ").append(quote(it)) }
        gravityUp?.let { g -> append(",\n  \"gravity_up\": [").append(g.joinToString(", ") { String.format(Locale.ROOT, "%.6f", it) }).append(']') }
        camera?.let { c ->
            append(",\n  \"camera\": {\"width\": ${c.width}, \"height\": ${c.height}, \"fx\": ${c.fx}, \"fy\": ${c.fy}, \"cx\": ${c.cx}, \"cy\": ${c.cy}, \"depth_scale\": ${c.depthScale}}")
        }
        if (settings.isNotEmpty()) {
            append(",\n  \"settings\": {")
            append(settings.toSortedMap().entries.joinToString(", ") { (k, v) -> quote(k) + ": " + quote(v) })
            append('}')
        }
        append("\n}\n")
    }

    /** Writes `metadata.json` into [dir]. */
    fun write(dir: File): File = File(dir, FILE_NAME).also { it.writeText(toJson()) }

    override fun equals(other: Any?): Boolean = other is StreamMetadata && toJson() == other.toJson()

    override fun hashCode(): Int = toJson().hashCode()

    companion object {
        const val FILE_NAME: String = "metadata.json"

        /** Parses `metadata.json`; IOException naming [source] for text that is not such an object. */
        fun fromJson(text: String, source: String = FILE_NAME): StreamMetadata {
            val root = try {
                Json.parse(text)
            } catch (e: IllegalArgumentException) {
                throw IOException("$source: ${e.message}")
            } as? Map<*, *> ?: throw IOException("$source: not a JSON object")
            fun str(k: String) = root[k] as? String
            val g = (root["gravity_up"] as? List<*>)?.map { (it as? Double) ?: throw IOException("$source: gravity_up holds a non-number") }
            if (g != null && (g.size != 3 || !g.all { it.isFinite() })) throw IOException("$source: gravity_up must be 3 numbers")
            val cam = (root["camera"] as? Map<*, *>)?.let { c ->
                fun num(k: String) = (c[k] as? Double) ?: throw IOException("$source: camera.$k is missing")
                CameraIntrinsics(num("width").toInt(), num("height").toInt(), num("fx"), num("fy"), num("cx"), num("cy"), num("depth_scale"))
            }
            return StreamMetadata(
                device = str("device") ?: throw IOException("$source: no device"),
                android = str("android"), app = str("app"),
                settings = (root["settings"] as? Map<*, *>)?.entries?.mapNotNull { (k, v) -> if (k is String && v is String) k to v else null }?.toMap() ?: emptyMap(),
                liveMode = str("live_mode"),
                camera = cam,
                gravityUp = g?.toDoubleArray(),
                imuClock = str("imu_clock"),
            )
        }

        /** The metadata of the stream in [files], or null when it has none (or it cannot be read: a stream replays without it). */
        fun read(files: StreamFiles): StreamMetadata? = try {
            if (files.exists(FILE_NAME)) fromJson(String(files.readBytes(FILE_NAME), Charsets.UTF_8), "${files.description}/$FILE_NAME") else null
        } catch (e: IOException) {
            null
        }

        private fun quote(s: String): String = buildString {
            append('"')
            for (ch in s) {
                when {
                    ch == '"' -> append("\\\"")
                    ch == '\\' -> append("\\\\")
                    ch == '\n' -> append("\\n")
                    ch < ' ' -> append(String.format(Locale.ROOT, "\\u%04x", ch.code))
                    else -> append(ch)
                }
            }
            append('"')
        }
    }
}
