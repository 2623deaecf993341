package io.ecvo.shared

import java.nio.ByteBuffer
import java.nio.ByteOrder

/**
 * Android's `ImageFormat.DEPTH16` samples: the range in millimetres in the low 13 bits
 * (0 = no measurement, so at most 8191 mm) and a confidence in the top 3 bits.
 *
 * Confidence, as Android documents it: raw 0 means 100 %, raw 1 means 0 %, raw `c` in
 * 2..7 means `(c - 1) / 7`. This helper (and the native tracker, for
 * `DepthFormat.DEPTH16`) uses the level `0..7` with 7 the best: raw 0 -> 7, raw `c` ->
 * `c - 1`. A pixel whose level is below `minConfidence` becomes 0 (no measurement);
 * `minConfidence = 0` keeps every pixel with a range.
 */
object Depth16 {
    /** Largest range DEPTH16 can hold, in millimetres. */
    const val MAX_RANGE_MM: Int = 0x1FFF

    /** Range of a raw sample in millimetres (low 13 bits). */
    fun rangeMm(sample: Short): Int = sample.toInt() and 0x1FFF

    /** Confidence level 0..7 (7 = 100 %) of a raw sample, from its top 3 bits. */
    fun confidence(sample: Short): Int {
        val raw = (sample.toInt() ushr 13) and 0x7
        return if (raw == 0) 7 else raw - 1
    }

    /** Confidence of a raw sample as a fraction 0..1 (Android's definition). */
    fun confidenceFraction(sample: Short): Float = confidence(sample) / 7f

    /** The raw sample for [rangeMm] with confidence [level] (0..7); the inverse of [rangeMm] and [confidence]. */
    fun encode(rangeMm: Int, level: Int): Short {
        require(rangeMm in 0..MAX_RANGE_MM) { "range $rangeMm mm does not fit in 13 bits" }
        require(level in 0..7) { "confidence level $level is not in 0..7" }
        val raw = if (level == 7) 0 else level + 1
        return ((raw shl 13) or rangeMm).toShort()
    }

    /** Millimetres of one raw sample, or 0 if it has no range or its confidence is below [minConfidence]. */
    fun decode(sample: Short, minConfidence: Int): Short {
        val mm = sample.toInt() and 0x1FFF
        return if (mm == 0 || confidence(sample) < minConfidence) 0 else mm.toShort()
    }

    /** Decodes [raw] DEPTH16 samples into millimetres in [out] (same size; may be [raw] itself). */
    fun decode(raw: ShortArray, minConfidence: Int, out: ShortArray = ShortArray(raw.size)): ShortArray {
        require(minConfidence in 0..7) { "minConfidence $minConfidence is not in 0..7" }
        require(out.size == raw.size) { "output has ${out.size} values, input ${raw.size}" }
        for (i in raw.indices) out[i] = decode(raw[i], minConfidence)
        return out
    }

    /**
     * Copies a DEPTH16 image plane (an `Image.Plane` buffer: 2-byte samples in [order],
     * [rowStrideBytes] bytes from row to row, read with absolute indexing from 0) of
     * [width] x [height] into [out], raw and row-major without padding.
     */
    fun readPlane(
        plane: ByteBuffer, rowStrideBytes: Int, width: Int, height: Int,
        out: ShortArray = ShortArray(width * height),
        order: ByteOrder = ByteOrder.nativeOrder(),
    ): ShortArray {
        require(width > 0 && height > 0) { "plane size ${width}x$height" }
        require(out.size == width * height) { "output has ${out.size} values, expected ${width * height}" }
        require(rowStrideBytes >= 2 * width) { "row stride $rowStrideBytes is less than 2 * width" }
        require(plane.capacity() >= rowStrideBytes * (height - 1) + 2 * width) { "plane of ${plane.capacity()} bytes is too small for ${width}x$height" }
        val b = plane.duplicate().order(order)
        for (y in 0 until height) {
            val row = y * rowStrideBytes
            val o = y * width
            for (x in 0 until width) out[o + x] = b.getShort(row + 2 * x)
        }
        return out
    }

    /**
     * Decodes a DEPTH16 image plane (an `Image.Plane` buffer: 2-byte samples in native
     * order, [rowStrideBytes] bytes from row to row, read with absolute indexing from 0)
     * of [width] x [height] into millimetres, row-major without padding.
     */
    fun decodePlane(
        plane: ByteBuffer, rowStrideBytes: Int, width: Int, height: Int, minConfidence: Int,
        out: ShortArray = ShortArray(width * height),
        order: ByteOrder = ByteOrder.nativeOrder(),
    ): ShortArray {
        require(minConfidence in 0..7) { "minConfidence $minConfidence is not in 0..7" }
        require(out.size == width * height) { "output has ${out.size} values, expected ${width * height}" }
        require(rowStrideBytes >= 2 * width) { "row stride $rowStrideBytes is less than 2 * width" }
        require(plane.capacity() >= rowStrideBytes * (height - 1) + 2 * width) { "plane of ${plane.capacity()} bytes is too small for ${width}x$height" }
        val b = plane.duplicate().order(order)
        for (y in 0 until height) {
            val row = y * rowStrideBytes
            val o = y * width
            for (x in 0 until width) out[o + x] = decode(b.getShort(row + 2 * x), minConfidence)
        }
        return out
    }
}
