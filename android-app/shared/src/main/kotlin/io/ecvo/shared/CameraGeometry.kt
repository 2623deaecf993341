package io.ecvo.shared

import kotlin.math.abs
import kotlin.math.floor

/** A rectangle in sensor pixel-array coordinates (Camera2's `Rect` without Android). */
data class SensorRect(val left: Int, val top: Int, val width: Int, val height: Int)

/**
 * What Camera2 says about one camera's optics, copied out of `CameraCharacteristics` so
 * that every decision about it can be tested on the JVM. Null means "not published"
 * (or: read before the CAMERA permission was granted).
 */
class CameraCalibration(
    /** `SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE`. */
    val preCorrectionArray: SensorRect?,
    /** `SENSOR_INFO_ACTIVE_ARRAY_SIZE`. */
    val activeArray: SensorRect?,
    /** `LENS_INTRINSIC_CALIBRATION`: fx, fy, cx, cy, skew (pre-correction array coordinates). */
    val intrinsic: FloatArray?,
    /** `LENS_DISTORTION`: kappa 1..5 (3 radial, 2 tangential). */
    val distortion: FloatArray?,
    /** `LENS_INFO_AVAILABLE_FOCAL_LENGTHS`' first value, millimetres. */
    val focalLengthMm: Float?,
    /** `SENSOR_INFO_PHYSICAL_SIZE`, millimetres. */
    val physicalWidthMm: Float?,
    val physicalHeightMm: Float?,
    /**
     * Whether outputs are distortion-corrected (`DISTORTION_CORRECTION_MODE` other than
     * OFF): they then cover [activeArray]; otherwise [preCorrectionArray].
     */
    val outputsCorrected: Boolean = false,
) {
    /** True when intrinsics come from `LENS_INTRINSIC_CALIBRATION` rather than being guessed. */
    val calibrated: Boolean get() = intrinsic != null && intrinsic.size >= 4 && intrinsic[0] > 0f && intrinsic[1] > 0f && preCorrectionArray != null

    /** The distortion to undo, or null if none is published, outputs are corrected, or all coefficients are 0. */
    val effectiveDistortion: LensDistortion?
        get() = if (outputsCorrected || distortion == null || distortion.size < 5 || distortion.all { it == 0f }) null else LensDistortion(distortion)

    /**
     * Pinhole intrinsics of the full sensor image an output stream is cut from (the
     * pre-correction array, or the active array when outputs are corrected).
     *
     * `LENS_INTRINSIC_CALIBRATION` is given in the pre-correction array's coordinates with
     * (0, 0) at that array's top-left corner, so the principal point needs no offset for
     * an uncorrected output; for a corrected output (cut from the active array) it moves
     * by the arrays' difference `pre.left - active.left`. Without a calibration: focal
     * length from the lens and the physical sensor size, principal point at the centre.
     */
    fun sensorIntrinsics(): CameraIntrinsics {
        val pre = preCorrectionArray
        val source = (if (outputsCorrected) activeArray else pre) ?: pre ?: activeArray
        val cal = intrinsic
        if (calibrated && cal != null && pre != null && source != null) {
            val dx = (pre.left - source.left).toDouble()
            val dy = (pre.top - source.top).toDouble()
            return CameraIntrinsics(source.width, source.height, cal[0].toDouble(), cal[1].toDouble(), cal[2] + dx, cal[3] + dy)
        }
        val w = source?.width ?: 640
        val h = source?.height ?: 480
        val f = focalLengthMm ?: 0f
        val pw = physicalWidthMm ?: 0f
        val ph = physicalHeightMm ?: 0f
        val fx = if (f > 0f && pw > 0f) f.toDouble() / pw * w else w * 0.8
        val fy = if (f > 0f && ph > 0f) f.toDouble() / ph * h else fx
        return CameraIntrinsics(w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0)
    }
}

/**
 * Camera2's `LENS_DISTORTION` model: for an ideal (undistorted) normalised point
 * (x, y), r² = x² + y², the point to sample in the camera's image is
 * `x_c = x (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 k4 x y + k5 (r² + 2 x²)`,
 * `y_c = y (1 + k1 r² + k2 r⁴ + k3 r⁶) + k4 (r² + 2 y²) + 2 k5 x y`
 * (Android's documentation of `LENS_DISTORTION`). Sampling this way needs no iteration.
 */
class LensDistortion(k: FloatArray) {
    init { require(k.size >= 5) { "LENS_DISTORTION needs 5 coefficients, got ${k.size}" } }
    private val k1 = k[0].toDouble(); private val k2 = k[1].toDouble(); private val k3 = k[2].toDouble()
    private val k4 = k[3].toDouble(); private val k5 = k[4].toDouble()

    /** The distorted normalised point seen at the ideal normalised point ([x], [y]). */
    fun distort(x: Double, y: Double): Pair<Double, Double> {
        val r2 = x * x + y * y
        val radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        return Pair(x * radial + 2 * k4 * x * y + k5 * (r2 + 2 * x * x), y * radial + k4 * (r2 + 2 * y * y) + 2 * k5 * x * y)
    }
}

/**
 * How a depth stream becomes the tracker's frame: a table giving, for each output pixel,
 * the source pixel it takes its depth from (nearest, never interpolated: depth is not
 * blended across edges), or -1 for none. It centre-crops the source to the output's
 * aspect ratio (a 4:3 sensor loses rows to become 16:9, it is never stretched), scales
 * uniformly, and optionally undoes lens distortion. [camera] is the output's pinhole
 * model (principal point shifted by the crop).
 */
class DepthRemap private constructor(
    val sourceWidth: Int,
    val sourceHeight: Int,
    val camera: CameraIntrinsics,
    private val table: IntArray,
    /** Whether lens distortion is undone. */
    val undistorts: Boolean,
) {
    /** Fills [out] (`camera.width * camera.height`) from [src] (`sourceWidth * sourceHeight`). */
    fun apply(src: ShortArray, out: ShortArray = ShortArray(table.size)): ShortArray {
        require(src.size == sourceWidth * sourceHeight) { "source has ${src.size} values, expected ${sourceWidth}x$sourceHeight" }
        require(out.size == table.size) { "output has ${out.size} values, expected ${table.size}" }
        for (i in table.indices) {
            val j = table[i]
            out[i] = if (j < 0) 0 else src[j]
        }
        return out
    }

    /** The source index output pixel [i] reads, or -1. */
    fun sourceIndex(i: Int): Int = table[i]

    companion object {
        /**
         * The remap from a [sourceWidth] x [sourceHeight] stream whose intrinsics are
         * [source] (already for that stream size) to [outWidth] x [outHeight]; with
         * [distortion], each output pixel reads the distorted position of its ideal ray.
         */
        fun create(source: CameraIntrinsics, outWidth: Int, outHeight: Int, distortion: LensDistortion? = null): DepthRemap {
            val out = source.forOutput(outWidth, outHeight)
            val w = source.width
            val h = source.height
            val table = IntArray(outWidth * outHeight)
            for (v in 0 until outHeight) for (u in 0 until outWidth) {
                // The ideal ray of output pixel (u, v), then where the source sees it.
                var x = (u - out.cx) / out.fx
                var y = (v - out.cy) / out.fy
                if (distortion != null) {
                    val d = distortion.distort(x, y)
                    x = d.first; y = d.second
                }
                val sx = floor(source.fx * x + source.cx + 0.5).toInt()
                val sy = floor(source.fy * y + source.cy + 0.5).toInt()
                table[v * outWidth + u] = if (sx in 0 until w && sy in 0 until h) sy * w + sx else -1
            }
            return DepthRemap(w, h, out, table, distortion != null)
        }
    }
}

/** A stream size, as Camera2's `Size`. */
data class StreamSize(val width: Int, val height: Int) {
    val aspect: Double get() = width.toDouble() / height
}

/** Choices of stream sizes for the tracker's frame. */
object StreamSizes {
    /**
     * The DEPTH16 size to stream for a [frameWidth] x [frameHeight] frame: the smallest
     * whose centred crop to the frame's aspect is at least the frame's size (no
     * upsampling), preferring sizes that lose less to the crop; if none is that large,
     * the one whose crop is largest. Null for an empty list.
     */
    fun depth(sizes: List<StreamSize>, frameWidth: Int, frameHeight: Int): StreamSize? {
        if (sizes.isEmpty()) return null
        val target = frameWidth.toDouble() / frameHeight
        fun cropWidth(s: StreamSize) = if (s.aspect > target) s.height * target else s.width.toDouble()
        val bigEnough = sizes.filter { cropWidth(it) >= frameWidth - 1e-9 }
        if (bigEnough.isNotEmpty()) {
            return bigEnough.minWith(compareBy<StreamSize>({ abs(it.aspect - target) > 0.01 }, { it.width.toLong() * it.height }))
        }
        return sizes.maxWith(compareBy<StreamSize>({ cropWidth(it) }, { -abs(it.aspect - target) }))
    }

    /**
     * The DEPTH16 size to track at its native resolution (the engine takes any size, so
     * a 240x180 ToF stream stays 240x180 with its own intrinsics: no crop, no upsampling):
     * the largest size at most [maxWidth] wide (the tracker's cost grows with the pixel
     * count), else the smallest. Null for an empty list.
     */
    fun nativeDepth(sizes: List<StreamSize>, maxWidth: Int = MAX_NATIVE_WIDTH): StreamSize? {
        if (sizes.isEmpty()) return null
        val fitting = sizes.filter { it.width <= maxWidth }
        return if (fitting.isNotEmpty()) fitting.maxBy { it.width.toLong() * it.height } else sizes.minBy { it.width.toLong() * it.height }
    }

    /** Widest depth stream tracked at its native size (VGA: the largest ToF sensors' size). */
    const val MAX_NATIVE_WIDTH: Int = 640

    /**
     * The YUV size for intensity: at least twice the frame's width when possible, with
     * the depth stream's aspect if possible, otherwise the closest aspect; the smallest
     * such (cheap to copy).
     */
    fun colour(sizes: List<StreamSize>, depth: StreamSize, frameWidth: Int): StreamSize? {
        if (sizes.isEmpty()) return null
        val wide = sizes.filter { it.width >= 2 * frameWidth }
        if (wide.isEmpty()) return sizes.maxBy { it.width.toLong() * it.height }
        return wide.minWith(compareBy<StreamSize>({ abs(it.aspect - depth.aspect) > 0.01 }, { abs(it.aspect - depth.aspect) }, { it.width }))
    }
}

/**
 * The size the tracker works at, relative to the depth stream's. The tracker's memory and
 * time grow with the pixel count (a VGA frame needs about 4x a QVGA one's), so a VGA ToF
 * stream is tracked halved unless the user asks for its native size.
 */
enum class TrackingResolution(val label: String) {
    /** Halved when the stream is wider than [AUTO_HALF_ABOVE_WIDTH] (VGA to QVGA), else native. */
    AUTO("auto"),

    /** The stream's own size. */
    NATIVE("native"),

    /** Half the stream's width and height (with intrinsics to match: `f / 2`, `(c + 0.5) / 2 - 0.5`). */
    HALF("halved"),
    ;

    /** The tracker's frame size for a depth stream of [stream] (never below 16 pixels a side by halving). */
    fun frameSize(stream: StreamSize): StreamSize {
        val half = when (this) {
            NATIVE -> false
            HALF -> true
            AUTO -> stream.width > AUTO_HALF_ABOVE_WIDTH
        }
        return if (half && stream.width >= 32 && stream.height >= 32) StreamSize(stream.width / 2, stream.height / 2) else stream
    }

    companion object {
        /** [AUTO] halves streams wider than this. */
        const val AUTO_HALF_ABOVE_WIDTH: Int = 320
    }
}
