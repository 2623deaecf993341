package io.ecvo.shared

import java.nio.ByteBuffer
import java.nio.ByteOrder

/**
 * What to do with DEPTH16's 3-bit confidence. Android documents raw code 0 as 100 % and
 * code 1 as 0 %, but real ToF sensors do not all follow it: one of the two real frames in
 * `phone_tof_samples` carries code 1 ("0 %") on 81 % of its pixels, all with plausible
 * ranges. Dropping them leaves too little depth to track.
 */
enum class ConfidencePolicy(val label: String) {
    /**
     * The default: follow the documentation (drop levels below the minimum) unless that
     * would drop more than half of the pixels that have a range, which marks a sensor
     * whose codes do not follow it; from then on (for the session) keep every ranged pixel.
     */
    AUTO("auto"),

    /** Follow the documentation: drop pixels whose level is below the minimum. */
    DOCUMENTED("documented"),

    /** Keep every pixel with a range. */
    IGNORE("ignore");

    companion object {
        fun fromLabel(s: String?): ConfidencePolicy = entries.firstOrNull { it.label == s } ?: AUTO
    }
}

/**
 * Decodes DEPTH16 planes into millimetres under a [ConfidencePolicy]. One per session
 * (AUTO's verdict sticks, so frames do not flicker between two rules). Not thread-safe.
 */
class DepthDecoder(val policy: ConfidencePolicy = ConfidencePolicy.AUTO, val minConfidence: Int = 1) {
    init { require(minConfidence in 0..7) { "minConfidence $minConfidence is not in 0..7" } }

    /** Whether AUTO found that this sensor's codes do not follow the documentation. */
    var codesIgnored: Boolean = policy == ConfidencePolicy.IGNORE
        private set

    /** Pixels with a range and pixels kept, in the last decoded frame. */
    var lastRanged: Int = 0
        private set
    var lastKept: Int = 0
        private set

    /** Decodes [raw] DEPTH16 samples into [out]. */
    fun decode(raw: ShortArray, out: ShortArray = ShortArray(raw.size)): ShortArray {
        require(out.size == raw.size) { "output has ${out.size} values, input ${raw.size}" }
        var ranged = 0
        var confident = 0
        for (s in raw) {
            if (Depth16.rangeMm(s) != 0) {
                ranged++
                if (Depth16.confidence(s) >= minConfidence) confident++
            }
        }
        if (policy == ConfidencePolicy.AUTO && !codesIgnored && ranged > 0 && confident * 2 < ranged) codesIgnored = true
        val min = if (codesIgnored) 0 else minConfidence
        Depth16.decode(raw, min, out)
        lastRanged = ranged
        lastKept = if (min == 0) ranged else confident
        return out
    }

    /** Reads an image plane ([rowStrideBytes] from row to row, native order) and decodes it. */
    fun decodePlane(plane: ByteBuffer, rowStrideBytes: Int, width: Int, height: Int, out: ShortArray = ShortArray(width * height), order: ByteOrder = ByteOrder.nativeOrder()): ShortArray {
        require(out.size == width * height) { "output has ${out.size} values, expected ${width * height}" }
        Depth16.readPlane(plane, rowStrideBytes, width, height, out, order)
        return decode(out, out)
    }
}
