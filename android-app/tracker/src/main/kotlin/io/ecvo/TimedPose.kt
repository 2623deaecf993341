package io.ecvo

/**
 * A camera-to-world pose at a time, as in a TUM trajectory line: translation in
 * metres and a unit quaternion (x, y, z, w). The world is the first camera's frame
 * (x right, y down, z forward).
 */
data class TimedPose(
    /** Capture time in seconds. */
    val timestamp: Double,
    val tx: Double,
    val ty: Double,
    val tz: Double,
    val qx: Double,
    val qy: Double,
    val qz: Double,
    val qw: Double,
) {
    /** Column `col` (0..2) of the rotation matrix: where the camera's x, y or z axis points in the world. */
    fun axis(col: Int): DoubleArray {
        val (x, y, z, w) = listOf(qx, qy, qz, qw)
        return when (col) {
            0 -> doubleArrayOf(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w))
            1 -> doubleArrayOf(2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w))
            2 -> doubleArrayOf(2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y))
            else -> throw IllegalArgumentException("axis $col is not 0, 1 or 2")
        }
    }

    /** The pose as a 4x4 column-major matrix (OpenGL order), like [Tracker.getPose] writes. */
    fun toMatrix(out: FloatArray = FloatArray(16)): FloatArray {
        require(out.size >= 16) { "matrix needs 16 floats, got ${out.size}" }
        for (c in 0..2) {
            val a = axis(c)
            out[4 * c] = a[0].toFloat(); out[4 * c + 1] = a[1].toFloat(); out[4 * c + 2] = a[2].toFloat(); out[4 * c + 3] = 0f
        }
        out[12] = tx.toFloat(); out[13] = ty.toFloat(); out[14] = tz.toFloat(); out[15] = 1f
        return out
    }

    companion object {
        /** Doubles per pose in the arrays of `nativeTrajectory`: t, tx, ty, tz, qx, qy, qz, qw. */
        const val STRIDE: Int = 8

        /** Splits `nativeTrajectory`'s array ([STRIDE] doubles per pose) into poses. */
        fun listFromArray(a: DoubleArray): List<TimedPose> {
            require(a.size % STRIDE == 0) { "trajectory array has ${a.size} values, not a multiple of $STRIDE" }
            return List(a.size / STRIDE) { i -> at(a, i * STRIDE) }
        }

        internal fun at(a: DoubleArray, o: Int) =
            TimedPose(a[o], a[o + 1], a[o + 2], a[o + 3], a[o + 4], a[o + 5], a[o + 6], a[o + 7])
    }
}

/** A frame the tracker chose as reference, with the highest level it became the reference at (1 or 2). */
data class ReferenceFrame(val pose: TimedPose, val level: Int) {
    companion object {
        /** Doubles per reference in `nativeReferences`: the 8 of [TimedPose.STRIDE], then the level. */
        const val STRIDE: Int = 9

        /** Splits `nativeReferences`'s array ([STRIDE] doubles per reference). */
        fun listFromArray(a: DoubleArray): List<ReferenceFrame> {
            require(a.size % STRIDE == 0) { "references array has ${a.size} values, not a multiple of $STRIDE" }
            return List(a.size / STRIDE) { i -> ReferenceFrame(TimedPose.at(a, i * STRIDE), a[i * STRIDE + 8].toInt()) }
        }
    }
}
