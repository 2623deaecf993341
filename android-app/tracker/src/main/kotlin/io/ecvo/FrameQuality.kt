package io.ecvo

/** Why the tracker lost a frame (`ecvo_core::LostReason`); [reasonName] as the Rust and Python side spell it. */
enum class LostReason(val code: Int, val reasonName: String) {
    /** The frame has no valid depth pixel (a covered lens, a sensor dropout). */
    NO_VALID_DEPTH(1, "no_valid_depth"),

    /** Too few template points landed on valid pixels of the other frame (too little overlap or depth). */
    TOO_FEW_POINTS(2, "too_few_points"),

    /** The normal equations are singular or nearly so (flat, featureless input). */
    DEGENERATE(3, "degenerate"),

    /** The solve diverged: a non-finite estimate, or a motion larger than a frame-to-frame motion can be. */
    DIVERGED(4, "diverged"),

    /** The residuals at the result spread too widely: the frames do not show the same scene there. */
    INCONSISTENT(5, "inconsistent"),

    /** The registration converged but implies a camera faster than the tracker believes (4 m/s). */
    IMPLAUSIBLE_SPEED(6, "implausible_speed"),

    /** The registration converged but its residuals spread far wider than the recent frames'. */
    SPREAD_JUMP(7, "spread_jump"),
    ;

    companion object {
        /** The reason with this code; null for 0 (not lost). */
        fun fromCode(code: Int): LostReason? = if (code == 0) null else entries.firstOrNull { it.code == code }
            ?: throw IllegalStateException("native library returned unknown lost reason $code")
    }
}

/**
 * The latest tracked frame with the quality of the registration its pose came from, read
 * with [Tracker.frameQuality]: what a pose graph or a fusion filter weighs the frame by,
 * and why it was lost when it was. The same figures as Rust's `FrameOutput::registration`
 * and `lost_reason` and Python's `FrameResult`.
 */
class FrameQuality(
    /** The frame's position in tracking order, from 0. */
    val index: Long,
    /** Its camera-to-world pose (a lost frame keeps the last good pose). */
    val pose: TimedPose,
    /** The tracker's state after it. */
    val state: TrackingState,
    /** Why it was lost; null unless [state] is [TrackingState.LOST]. */
    val lostReason: LostReason?,
    /**
     * The 6x6 information matrix of the registration, row-major (36 values): the normal
     * equations' JᵀWJ at the solution, whitened by the fitted residual scale, in the
     * tangent space of the motion from the frame registered against to this one,
     * ordered (rx, ry, rz, tx, ty, tz) as Open3D returns it. Its inverse approximates
     * the motion's covariance (radians, metres). All zeros on the first frame, a
     * re-anchored one and a lost one (no constraint).
     */
    val information: DoubleArray,
    /**
     * The fitted residual scale Σ of that registration as (Σ_II, Σ_IZ, Σ_ZZ), over
     * (intensity in [0, 1], depth residual times its gain); null without a registration.
     */
    val residualScale: DoubleArray?,
    /** Template points that landed on valid pixels at the finest step. */
    val validPoints: Int,
    /** Template points of the finest step. */
    val templatePoints: Int,
    /** The frame became the reference at levels 1..referenceLevels (0: none). */
    val referenceLevels: Int,
) {
    /** Whether the pose came from a registration (false for the first, a re-anchored and a lost frame). */
    val hasRegistration: Boolean get() = templatePoints > 0

    /** validPoints / templatePoints: the fraction of the template used (0 without a registration). */
    val pointFraction: Double get() = if (templatePoints == 0) 0.0 else validPoints.toDouble() / templatePoints

    /** Entry ([row], [col]) of [information]. */
    fun information(row: Int, col: Int): Double {
        require(row in 0..5 && col in 0..5) { "information($row, $col): indices are 0..5" }
        return information[6 * row + col]
    }

    override fun toString(): String =
        "FrameQuality(index=$index, t=${pose.timestamp}, state=$state" +
            (lostReason?.let { ", reason=${it.reasonName}" } ?: "") +
            ", points=$validPoints/$templatePoints)"

    companion object {
        /**
         * Doubles in the array of `nativeFrameQuality` ([Tracker.frameQuality]). Layout
         * (counts and codes are doubles holding whole numbers):
         *
         * | index | value |
         * |-------|-------|
         * | 0      | [index] |
         * | 1      | [state] code ([TrackingState]) |
         * | 2      | [lostReason] code (0: not lost; [LostReason.code]) |
         * | 3..10  | [pose]: t (s), tx, ty, tz, qx, qy, qz, qw ([TimedPose.STRIDE] values) |
         * | 11..46 | [information], row-major |
         * | 47..49 | [residualScale] (NaN without one) |
         * | 50     | [validPoints] |
         * | 51     | [templatePoints] |
         * | 52     | [referenceLevels] |
         */
        const val SIZE: Int = 53

        /** Offset of [information] in the array. */
        const val INFORMATION: Int = 11

        /** Reads the layout documented at [SIZE]; IllegalArgumentException if [a] has fewer values. */
        fun fromArray(a: DoubleArray): FrameQuality {
            require(a.size >= SIZE) { "frame quality array has ${a.size} values, expected at least $SIZE" }
            val scale = if (a[47].isNaN()) null else a.copyOfRange(47, 50)
            return FrameQuality(
                index = a[0].toLong(),
                pose = TimedPose.at(a, 3),
                state = TrackingState.fromCode(a[1].toInt()),
                lostReason = LostReason.fromCode(a[2].toInt()),
                information = a.copyOfRange(INFORMATION, INFORMATION + 36),
                residualScale = scale,
                validPoints = a[50].toInt(),
                templatePoints = a[51].toInt(),
                referenceLevels = a[52].toInt(),
            )
        }
    }
}
