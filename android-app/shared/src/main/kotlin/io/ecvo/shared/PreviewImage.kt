package io.ecvo.shared

/**
 * The small preview the app can show beside the trajectory, to spot registration trouble
 * (intensity that does not line up with depth edges): ARGB pixels for a bitmap.
 */
object PreviewImage {
    /** Depth as gray, near bright and far dark over [nearMm]..[farMm]; no measurement is dark red. */
    fun depth(depthMm: ShortArray, nearMm: Int = 300, farMm: Int = 4000, out: IntArray = IntArray(depthMm.size)): IntArray {
        require(out.size == depthMm.size) { "output has ${out.size} pixels, depth ${depthMm.size}" }
        require(farMm > nearMm) { "far $farMm must be beyond near $nearMm" }
        for (i in depthMm.indices) {
            val d = depthMm[i].toInt() and 0xFFFF
            out[i] = if (d == 0) {
                NO_DEPTH
            } else {
                val g = 255 - ((d - nearMm).coerceIn(0, farMm - nearMm) * 255 / (farMm - nearMm))
                (0xFF shl 24) or (g shl 16) or (g shl 8) or g
            }
        }
        return out
    }

    /** 8-bit intensity as gray. */
    fun intensity(gray: ByteArray, out: IntArray = IntArray(gray.size)): IntArray {
        require(out.size == gray.size) { "output has ${out.size} pixels, intensity ${gray.size}" }
        for (i in gray.indices) {
            val g = gray[i].toInt() and 0xFF
            out[i] = (0xFF shl 24) or (g shl 16) or (g shl 8) or g
        }
        return out
    }

    /** The colour of a pixel without depth. */
    const val NO_DEPTH: Int = 0xFF400000.toInt()
}

/** The latest frame handed to the tracker, kept for the preview (copied only when a preview is shown). */
class LatestFrame {
    private var depth: ShortArray? = null
    private var gray: ByteArray? = null
    private var fresh = false

    /** Copies a frame (source thread). */
    @Synchronized fun put(depthMm: ShortArray, intensity: ByteArray) {
        val d = depth?.takeIf { it.size == depthMm.size } ?: ShortArray(depthMm.size)
        val g = gray?.takeIf { it.size == intensity.size } ?: ByteArray(intensity.size)
        depthMm.copyInto(d); intensity.copyInto(g)
        depth = d; gray = g; fresh = true
    }

    /** ARGB pixels of the frame for [kind] if a new frame came since the last call, else null (UI thread). */
    @Synchronized fun takePreview(kind: PreviewKind): IntArray? {
        if (!fresh || kind == PreviewKind.NONE) return null
        fresh = false
        return when (kind) {
            PreviewKind.DEPTH -> depth?.let { PreviewImage.depth(it) }
            PreviewKind.INTENSITY -> gray?.let { PreviewImage.intensity(it) }
            PreviewKind.NONE -> null
        }
    }
}
