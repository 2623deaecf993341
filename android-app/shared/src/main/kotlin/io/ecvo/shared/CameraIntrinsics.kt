package io.ecvo.shared

import java.io.File
import java.io.IOException

/**
 * A pinhole camera as stored in a stream's `camera.json` (the fields of `ecvo-io`'s
 * `Camera`): image size, focal lengths and principal point in pixels (pixel centres at
 * integer coordinates), and raw depth units per metre (1000 for millimetres).
 */
data class CameraIntrinsics(
    val width: Int,
    val height: Int,
    val fx: Double,
    val fy: Double,
    val cx: Double,
    val cy: Double,
    val depthScale: Double = 1000.0,
) {
    /**
     * Throws IllegalArgumentException naming the first bad field, with the host tools'
     * rules: size 8..8192, finite non-zero focal lengths, finite principal point,
     * finite positive depth scale.
     */
    fun validate(): CameraIntrinsics {
        require(width in 8..8192 && height in 8..8192) { "width/height: ${width}x$height is outside 8x8..8192x8192" }
        require(fx.isFinite() && kotlin.math.abs(fx) >= 1e-6) { "fx: focal length must be finite and non-zero, got $fx" }
        require(fy.isFinite() && kotlin.math.abs(fy) >= 1e-6) { "fy: focal length must be finite and non-zero, got $fy" }
        require(cx.isFinite()) { "cx: principal point must be finite, got $cx" }
        require(cy.isFinite()) { "cy: principal point must be finite, got $cy" }
        require(depthScale.isFinite() && depthScale > 0) { "depth_scale: must be finite and positive, got $depthScale" }
        return this
    }

    /** Number of pixels. */
    val pixels: Int get() = width * height

    /**
     * The same camera with the image resampled to [newWidth] x [newHeight] (pixel
     * centres kept aligned: `c' = (c + 0.5) * s - 0.5`).
     */
    fun resized(newWidth: Int, newHeight: Int): CameraIntrinsics {
        val sx = newWidth.toDouble() / width
        val sy = newHeight.toDouble() / height
        return copy(width = newWidth, height = newHeight, fx = fx * sx, fy = fy * sy, cx = (cx + 0.5) * sx - 0.5, cy = (cy + 0.5) * sy - 0.5)
    }

    /**
     * The camera of an output stream of [outWidth] x [outHeight] made from this (full
     * sensor) image the way Camera2 does: the largest centred window with the output's
     * aspect ratio, scaled to the output size.
     */
    fun forOutput(outWidth: Int, outHeight: Int): CameraIntrinsics {
        val wider = outWidth.toLong() * height - outHeight.toLong() * width // > 0: output is wider
        val cw = if (wider < 0) height.toDouble() * outWidth / outHeight else width.toDouble()
        val ch = if (wider > 0) width.toDouble() * outHeight / outWidth else height.toDouble()
        val x0 = (width - cw) / 2
        val y0 = (height - ch) / 2
        val sx = outWidth / cw
        val sy = outHeight / ch
        return copy(
            width = outWidth, height = outHeight, fx = fx * sx, fy = fy * sy,
            cx = (cx - x0 + 0.5) * sx - 0.5, cy = (cy - y0 + 0.5) * sy - 0.5,
        )
    }

    /** The camera of the window of size [w] x [h] whose top-left pixel is ([x0], [y0]). */
    fun cropped(x0: Int, y0: Int, w: Int, h: Int): CameraIntrinsics =
        copy(width = w, height = h, cx = cx - x0, cy = cy - y0)

    /**
     * `camera.json` text in the layout the host tools write (pretty-printed, integers for
     * the size), with the IMU's calibration as its `imu` object when [imu] is given.
     */
    fun toJson(imu: ImuCalibration? = null): String {
        for ((k, v) in listOf("fx" to fx, "fy" to fy, "cx" to cx, "cy" to cy, "depth_scale" to depthScale)) {
            require(v.isFinite()) { "$k: $v cannot be written to JSON" }
        }
        return "{\n  \"width\": $width,\n  \"height\": $height,\n  \"fx\": $fx,\n  \"fy\": $fy,\n" +
            "  \"cx\": $cx,\n  \"cy\": $cy,\n  \"depth_scale\": $depthScale" +
            (imu?.let { ",\n  \"imu\": ${it.toJson()}" } ?: "") + "\n}\n"
    }

    companion object {
        /** Name of the camera file inside a stream folder. */
        const val FILE_NAME: String = "camera.json"

        /**
         * Parses and validates `camera.json` text; every field is required. [source] names
         * the file in error messages (IOException with the file and the field).
         */
        fun fromJson(text: String, source: String = FILE_NAME): CameraIntrinsics {
            val root = try {
                Json.parse(text)
            } catch (e: IllegalArgumentException) {
                throw IOException("$source: ${e.message}")
            }
            if (root !is Map<*, *>) throw IOException("$source: expected a JSON object")
            fun num(k: String): Double = when (val v = root[k]) {
                null -> throw IOException("$source: missing field `$k`")
                is Double -> v
                else -> throw IOException("$source: field `$k` is not a number")
            }
            fun int(k: String): Int {
                val v = num(k)
                if (v != Math.floor(v) || v < 0 || v > Int.MAX_VALUE) throw IOException("$source: field `$k` is not a whole number ($v)")
                return v.toInt()
            }
            val c = CameraIntrinsics(int("width"), int("height"), num("fx"), num("fy"), num("cx"), num("cy"), num("depth_scale"))
            try {
                c.validate()
            } catch (e: IllegalArgumentException) {
                throw IOException("$source: ${e.message}")
            }
            return c
        }

        /** Reads a `camera.json` file. */
        fun read(file: File): CameraIntrinsics = fromJson(file.readText(), file.path)
    }
}
