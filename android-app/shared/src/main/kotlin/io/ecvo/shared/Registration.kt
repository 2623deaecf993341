package io.ecvo.shared

import java.nio.ByteBuffer
import kotlin.math.floor

/**
 * An 8-bit gray image with a row stride, such as the Y plane of an Android
 * `YUV_420_888` image (pixel stride 1); read with absolute indexing from 0.
 */
class GrayPlane(val buffer: ByteBuffer, val width: Int, val height: Int, val rowStride: Int = width) {
    init {
        require(width > 0 && height > 0) { "plane size ${width}x$height" }
        require(rowStride >= width) { "row stride $rowStride is less than the width $width" }
        require(buffer.capacity() >= rowStride * (height - 1) + width) { "plane of ${buffer.capacity()} bytes is too small for ${width}x$height" }
    }

    /** Wraps a packed row-major array. */
    constructor(pixels: ByteArray, width: Int, height: Int) : this(ByteBuffer.wrap(pixels), width, height, width)

    /** The value at integer pixel ([x], [y]), 0..255. */
    fun at(x: Int, y: Int): Int = buffer.get(y * rowStride + x).toInt() and 0xFF

    /** Bilinear value at ([x], [y]) (pixel centres at integers), clamped to the border; -1 outside by more than half a pixel. */
    fun bilinear(x: Float, y: Float): Float {
        if (x < -0.5f || y < -0.5f || x > width - 0.5f || y > height - 0.5f) return -1f
        val xc = x.coerceIn(0f, (width - 1).toFloat())
        val yc = y.coerceIn(0f, (height - 1).toFloat())
        val x0 = floor(xc).toInt().coerceAtMost(width - 2).coerceAtLeast(0)
        val y0 = floor(yc).toInt().coerceAtMost(height - 2).coerceAtLeast(0)
        val x1 = (x0 + 1).coerceAtMost(width - 1)
        val y1 = (y0 + 1).coerceAtMost(height - 1)
        val ax = xc - x0
        val ay = yc - y0
        val top = at(x0, y0) * (1 - ax) + at(x1, y0) * ax
        val bottom = at(x0, y1) * (1 - ax) + at(x1, y1) * ax
        return top * (1 - ay) + bottom * ay
    }

    /** Nearest value at ([x], [y]); -1 outside the image. */
    fun nearest(x: Float, y: Float): Int {
        val xi = floor(x + 0.5f).toInt()
        val yi = floor(y + 0.5f).toInt()
        return if (xi in 0 until width && yi in 0 until height) at(xi, yi) else -1
    }
}

/** How [IntensityRegistration] samples the gray image. */
enum class Sampling { NEAREST, BILINEAR }

/**
 * A rigid transform from the depth camera's frame to the colour camera's frame:
 * `p_colour = R * p_depth + t`, [rotation] row-major 3x3, [translation] in metres
 * (Camera2's `LENS_POSE_*` give each camera's pose; compose them to get this).
 */
class RigidTransform(val rotation: DoubleArray, val translation: DoubleArray) {
    init {
        require(rotation.size == 9 && translation.size == 3) { "rotation needs 9 values, translation 3" }
    }

    companion object {
        /** The cameras share their optical centre and axes. */
        val IDENTITY: RigidTransform = RigidTransform(doubleArrayOf(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), DoubleArray(3))
    }
}

/**
 * Resamples a colour camera's gray (Y) plane into the depth frame, so that intensity
 * pixel `i` sees what depth pixel `i` measures.
 *
 * For each depth pixel (u, v) with depth z (metres), the point `z * Kd⁻¹ (u, v, 1)` is
 * moved into the colour camera with [depthToColour] and projected with [colour]; the
 * gray value there (nearest or bilinear) becomes the intensity. Pixels without depth
 * use [fallbackDepthM] (the parallax then is only approximately right; with a zero
 * baseline it does not matter). Pixels that fall outside the gray image get 0.
 *
 * Rays are precomputed once, so [register] costs a few multiply-adds per pixel.
 */
class IntensityRegistration(
    val depth: CameraIntrinsics,
    val colour: CameraIntrinsics,
    val depthToColour: RigidTransform = RigidTransform.IDENTITY,
    val sampling: Sampling = Sampling.BILINEAR,
    val fallbackDepthM: Double = 1.5,
) {
    /** Per depth pixel, `R * Kd⁻¹ (u, v, 1)`: 3 floats. */
    private val rays = FloatArray(depth.pixels * 3)
    private val t = FloatArray(3) { depthToColour.translation[it].toFloat() }

    init {
        require(fallbackDepthM > 0) { "fallback depth must be positive" }
        val r = depthToColour.rotation
        var k = 0
        for (v in 0 until depth.height) for (u in 0 until depth.width) {
            val x = (u - depth.cx) / depth.fx
            val y = (v - depth.cy) / depth.fy
            rays[k++] = (r[0] * x + r[1] * y + r[2]).toFloat()
            rays[k++] = (r[3] * x + r[4] * y + r[5]).toFloat()
            rays[k++] = (r[6] * x + r[7] * y + r[8]).toFloat()
        }
    }

    /**
     * Fills [out] (`depth.width * depth.height`) with the gray value seen by each depth
     * pixel. [depthRaw] holds the depth frame in `depth.depthScale` units per metre
     * (0 = none); [plane] must be `colour.width` x `colour.height`.
     */
    fun register(depthRaw: ShortArray, plane: GrayPlane, out: ByteArray = ByteArray(depth.pixels)): ByteArray {
        require(depthRaw.size == depth.pixels && out.size == depth.pixels) { "depth and output need ${depth.pixels} values" }
        require(plane.width == colour.width && plane.height == colour.height) {
            "gray plane is ${plane.width}x${plane.height}, colour camera ${colour.width}x${colour.height}"
        }
        val toMetres = (1.0 / depth.depthScale).toFloat()
        val fb = fallbackDepthM.toFloat()
        val fx = colour.fx.toFloat(); val fy = colour.fy.toFloat()
        val cx = colour.cx.toFloat(); val cy = colour.cy.toFloat()
        for (i in 0 until depth.pixels) {
            val raw = depthRaw[i].toInt() and 0xFFFF
            val z = if (raw == 0) fb else raw * toMetres
            val X = z * rays[3 * i] + t[0]
            val Y = z * rays[3 * i + 1] + t[1]
            val Z = z * rays[3 * i + 2] + t[2]
            if (Z <= 1e-6f) { out[i] = 0; continue }
            val x = fx * X / Z + cx
            val y = fy * Y / Z + cy
            val g = when (sampling) {
                Sampling.NEAREST -> plane.nearest(x, y).toFloat()
                Sampling.BILINEAR -> plane.bilinear(x, y)
            }
            out[i] = if (g < 0f) 0 else (g + 0.5f).toInt().coerceIn(0, 255).toByte()
        }
        return out
    }
}

/**
 * The simple case: the gray plane covers the depth camera's field of view up to a scale
 * and a crop, so depth pixel (u, v) sees gray pixel `((u + 0.5) * scaleX - 0.5 + offsetX,
 * (v + 0.5) * scaleY - 0.5 + offsetY)` (pixel centres aligned). [fit] builds the usual
 * "same field of view, centred, aspect cropped" mapping.
 */
class ScaledCrop(
    val outWidth: Int,
    val outHeight: Int,
    val scaleX: Double,
    val scaleY: Double,
    val offsetX: Double = 0.0,
    val offsetY: Double = 0.0,
    val sampling: Sampling = Sampling.BILINEAR,
) {
    /** Resamples [plane] into [out] (`outWidth * outHeight`); pixels mapped outside the plane get 0. */
    fun resample(plane: GrayPlane, out: ByteArray = ByteArray(outWidth * outHeight)): ByteArray {
        require(out.size == outWidth * outHeight) { "output has ${out.size} values, expected ${outWidth * outHeight}" }
        for (v in 0 until outHeight) {
            val y = ((v + 0.5) * scaleY - 0.5 + offsetY).toFloat()
            for (u in 0 until outWidth) {
                val x = ((u + 0.5) * scaleX - 0.5 + offsetX).toFloat()
                val g = when (sampling) {
                    Sampling.NEAREST -> plane.nearest(x, y).toFloat()
                    Sampling.BILINEAR -> plane.bilinear(x, y)
                }
                out[v * outWidth + u] = if (g < 0f) 0 else (g + 0.5f).toInt().coerceIn(0, 255).toByte()
            }
        }
        return out
    }

    companion object {
        /**
         * Maps a [srcWidth] x [srcHeight] plane onto [outWidth] x [outHeight] with one scale
         * for both axes, cropping the longer side of the source equally on both ends (a 4:3
         * Y plane into a 16:9 depth frame loses rows at top and bottom).
         */
        fun fit(srcWidth: Int, srcHeight: Int, outWidth: Int, outHeight: Int, sampling: Sampling = Sampling.BILINEAR): ScaledCrop {
            val s = minOf(srcWidth.toDouble() / outWidth, srcHeight.toDouble() / outHeight)
            val ox = (srcWidth - outWidth * s) / 2
            val oy = (srcHeight - outHeight * s) / 2
            return ScaledCrop(outWidth, outHeight, s, s, ox, oy, sampling)
        }
    }
}

/** Resampling of depth maps: nearest only, so that no depth is ever interpolated across an edge or hole. */
object DepthResample {
    /** Resamples [src] ([srcWidth] x [srcHeight]) to [outWidth] x [outHeight] by nearest pixel, centres aligned. */
    fun nearest(src: ShortArray, srcWidth: Int, srcHeight: Int, outWidth: Int, outHeight: Int, out: ShortArray = ShortArray(outWidth * outHeight)): ShortArray {
        require(src.size == srcWidth * srcHeight) { "source has ${src.size} values, expected ${srcWidth * srcHeight}" }
        require(out.size == outWidth * outHeight) { "output has ${out.size} values, expected ${outWidth * outHeight}" }
        val sx = srcWidth.toDouble() / outWidth
        val sy = srcHeight.toDouble() / outHeight
        for (v in 0 until outHeight) {
            val y = floor((v + 0.5) * sy).toInt().coerceIn(0, srcHeight - 1)
            for (u in 0 until outWidth) {
                val x = floor((u + 0.5) * sx).toInt().coerceIn(0, srcWidth - 1)
                out[v * outWidth + u] = src[y * srcWidth + x]
            }
        }
        return out
    }
}

/**
 * Camera2 lens poses (`LENS_POSE_ROTATION`, a quaternion x, y, z, w, and
 * `LENS_POSE_TRANSLATION`, metres), which place each camera in a common reference frame:
 * a reference point `p` is `R (p - t)` in the camera's frame, as Android's
 * `LENS_INTRINSIC_CALIBRATION` documentation composes them.
 */
object LensPose {
    /** Row-major rotation matrix of a unit quaternion given as (x, y, z, w). */
    fun rotation(q: FloatArray): DoubleArray {
        require(q.size == 4) { "quaternion needs 4 values (x, y, z, w)" }
        val n = kotlin.math.sqrt((q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).toDouble())
        require(n > 1e-6) { "quaternion is (near) zero" }
        val x = q[0] / n; val y = q[1] / n; val z = q[2] / n; val w = q[3] / n
        return doubleArrayOf(
            1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
            2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
            2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y),
        )
    }

    /**
     * The transform from the depth camera's frame to the colour camera's:
     * `p_c = R_c R_dᵀ p_d + R_c (t_d - t_c)`. Missing poses (null) count as identity at
     * the origin, so two cameras without pose data are treated as one.
     */
    fun depthToColour(depthRotation: FloatArray?, depthTranslation: FloatArray?, colourRotation: FloatArray?, colourTranslation: FloatArray?): RigidTransform {
        val id = floatArrayOf(0f, 0f, 0f, 1f)
        val rd = rotation(depthRotation ?: id)
        val rc = rotation(colourRotation ?: id)
        val td = depthTranslation ?: FloatArray(3)
        val tc = colourTranslation ?: FloatArray(3)
        require(td.size == 3 && tc.size == 3) { "translations need 3 values" }
        val r = DoubleArray(9)
        for (i in 0..2) for (j in 0..2) {
            var s = 0.0
            for (k in 0..2) s += rc[3 * i + k] * rd[3 * j + k] // (R_c R_dᵀ)_ij
            r[3 * i + j] = s
        }
        val d = DoubleArray(3) { (td[it] - tc[it]).toDouble() }
        val t = DoubleArray(3) { i -> rc[3 * i] * d[0] + rc[3 * i + 1] * d[1] + rc[3 * i + 2] * d[2] }
        return RigidTransform(r, t)
    }
}
