package io.ecvo.shared

/** Camera2's `LENS_POSE_REFERENCE`: what a camera's `LENS_POSE_*` are relative to. */
enum class PoseReference(val code: Int) {
    /** Relative to the primary camera facing the same way (the default before Android 9). */
    PRIMARY_CAMERA(0),

    /** Relative to the device's gyroscope (Android sensor axes). */
    GYROSCOPE(1),

    /** Not defined: the pose cannot be composed with another camera's. */
    UNDEFINED(2),

    /** Relative to the automotive sensor frame. */
    AUTOMOTIVE(3);

    companion object {
        /** The reference with this code; null (no key published) reads as [PRIMARY_CAMERA], as Camera2 documents; unknown codes as [UNDEFINED]. */
        fun fromCode(code: Int?): PoseReference = if (code == null) PRIMARY_CAMERA else entries.firstOrNull { it.code == code } ?: UNDEFINED
    }
}

/** One camera's `LENS_POSE_ROTATION` (quaternion x, y, z, w), `LENS_POSE_TRANSLATION` (metres) and `LENS_POSE_REFERENCE`. */
class CameraPose(val rotation: FloatArray?, val translation: FloatArray?, val reference: PoseReference) {
    /** Whether both rotation and translation are published and usable. */
    val published: Boolean
        get() = rotation != null && rotation.size == 4 && translation != null && translation.size == 3 &&
            (rotation[0] * rotation[0] + rotation[1] * rotation[1] + rotation[2] * rotation[2] + rotation[3] * rotation[3]) > 1e-6f
}

/** The depth-to-colour transform chosen for registration, and why. */
class PoseDecision(
    val depthToColour: RigidTransform,
    /** True when the lens poses were composed; false for the documented fallback. */
    val fromLensPoses: Boolean,
    /** A sentence for the user when the fallback was taken, else null. */
    val note: String?,
)

/**
 * Decides how the colour camera's image is registered to the depth camera's.
 *
 * - Both cameras publish a pose with the same [PoseReference] (not UNDEFINED): the poses
 *   are composed ([LensPose.depthToColour]).
 * - The colour camera publishes none, the depth camera's pose is relative to the
 *   primary camera, and the colour camera is that primary camera: the colour camera is
 *   the reference itself (identity at the origin), so the depth pose is composed with it.
 * - Anything else (no pose, different or undefined references): the **fallback**, that
 *   the two cameras share their optical centre and optical axis, their image axes turned
 *   by the difference of their `SENSOR_ORIENTATION`s ([orientationFallback]; identity
 *   when both sensors are mounted alike). The intensity is then off by the baseline's
 *   parallax (about `f * baseline / z` pixels: 2 px for 1 cm at 1 m and f = 200 px),
 *   which the tracker tolerates better than a wrong rotation.
 * - Whatever was composed must keep the depth camera's optical axis within
 *   [MAX_AXIS_ANGLE_DEG] of the colour camera's (the cameras face the same way): a
 *   rotation that turns it further (e.g. a gyroscope-referenced pose composed with an
 *   identity, a 180° turn about x) would put every point behind the colour camera and
 *   blank the intensity, so the fallback is used instead, and said.
 */
object PosePolicy {
    /** Largest angle between the cameras' optical axes accepted from lens poses. */
    const val MAX_AXIS_ANGLE_DEG: Double = 30.0

    /**
     * [depthOrientation] and [colourOrientation] are the cameras' `SENSOR_ORIENTATION`
     * (degrees clockwise that turn each image upright), used by the fallback.
     */
    fun decide(depth: CameraPose, colour: CameraPose, colourIsPrimary: Boolean, depthOrientation: Int = 0, colourOrientation: Int = 0): PoseDecision {
        val fallback = { why: String ->
            val turn = Math.floorMod(depthOrientation - colourOrientation, 360)
            val axes = if (turn == 0) "axes" else "optical axis, their images turned $turn° apart (SENSOR_ORIENTATION)"
            PoseDecision(orientationFallback(depthOrientation, colourOrientation), false, "$why; intensity assumes the depth and colour cameras share their centre and $axes (a small offset from their baseline).")
        }
        if (!depth.published) return fallback("the depth camera publishes no lens pose")
        if (depth.reference == PoseReference.UNDEFINED) return fallback("the depth camera's lens pose has no defined reference")
        val composed = when {
            colour.published && colour.reference == depth.reference ->
                LensPose.depthToColour(depth.rotation, depth.translation, colour.rotation, colour.translation)
            colour.published ->
                return fallback("the cameras' lens poses have different references (${depth.reference} and ${colour.reference})")
            depth.reference == PoseReference.PRIMARY_CAMERA && colourIsPrimary ->
                LensPose.depthToColour(depth.rotation, depth.translation, floatArrayOf(0f, 0f, 0f, 1f), FloatArray(3))
            else -> return fallback("the colour camera publishes no lens pose")
        }
        // Row 2 of R maps the depth camera's z axis: R[8] is the cosine between the optical axes.
        val cos = composed.rotation[8]
        if (cos < kotlin.math.cos(Math.toRadians(MAX_AXIS_ANGLE_DEG))) {
            val deg = Math.toDegrees(kotlin.math.acos(cos.coerceIn(-1.0, 1.0)))
            return fallback(String.format(java.util.Locale.ROOT, "the lens poses turn the depth camera %.0f° away from the colour camera", deg))
        }
        return PoseDecision(composed, true, null)
    }

    /**
     * The fallback's depth-to-colour transform for cameras facing the same way: no
     * translation, a rotation about the optical axis by `depthOrientation -
     * colourOrientation`. A depth image turned clockwise by `θd` is upright, so a
     * depth-camera direction `p` is `Rz(θd) p` upright and `Rz(θc)ᵀ Rz(θd) p` in the colour
     * camera (image x right, y down: `Rz(a)` turns x towards y).
     */
    fun orientationFallback(depthOrientation: Int, colourOrientation: Int): RigidTransform {
        val turn = Math.floorMod(depthOrientation - colourOrientation, 360)
        if (turn == 0) return RigidTransform.IDENTITY
        // Exact for the quarter turns Camera2 allows (0, 90, 180, 270).
        val (c, s) = when (turn) {
            90 -> 0.0 to 1.0
            180 -> -1.0 to 0.0
            270 -> 0.0 to -1.0
            else -> Math.cos(Math.toRadians(turn.toDouble())) to Math.sin(Math.toRadians(turn.toDouble()))
        }
        val ns = if (s == 0.0) 0.0 else -s // no -0.0 in the matrix
        return RigidTransform(doubleArrayOf(c, ns, 0.0, s, c, 0.0, 0.0, 0.0, 1.0), DoubleArray(3))
    }
}
