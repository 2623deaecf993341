package io.ecvo

/**
 * How the depth samples handed to [Tracker.pushFrame] encode distance.
 *
 * The integer [code] is what crosses the JNI boundary (`depthFormat` of
 * `NativeBridge.nativeInit`); the Rust side (`rust/ecvo-jni`) uses the same table:
 *
 * | code | value          | meaning |
 * |------|----------------|---------|
 * | 0    | [MILLIMETRES]  | unsigned 16-bit millimetres, 0 = no measurement (depth_scale 1000) |
 * | 1    | [DEPTH16]      | Android `ImageFormat.DEPTH16`: low 13 bits millimetres, top 3 bits confidence |
 * | 2    | [CUSTOM_SCALE] | unsigned 16-bit, [TrackerConfig.depthScale] units per metre, 0 = no measurement |
 */
enum class DepthFormat(val code: Int) {
    /** Unsigned 16-bit millimetres; 0 means no measurement. */
    MILLIMETRES(0),

    /**
     * Android's DEPTH16: range in millimetres in the low 13 bits (0 = no measurement), a
     * 3-bit confidence in the top bits. Raw confidence 0 means 100 %, 1 means 0 %, and
     * `c` in 2..7 means `(c - 1) / 7`; as a level 0..7 (7 best) that is `0 -> 7`,
     * `c -> c - 1`. Pixels whose level is below [TrackerConfig.minConfidence] are dropped.
     */
    DEPTH16(1),

    /** Unsigned 16-bit in [TrackerConfig.depthScale] units per metre; 0 means no measurement. */
    CUSTOM_SCALE(2);

    companion object {
        /** The format with this [code]; throws IllegalArgumentException for an unknown code. */
        fun fromCode(code: Int): DepthFormat = entries.firstOrNull { it.code == code }
            ?: throw IllegalArgumentException("unknown depth format code $code")
    }
}

/**
 * Which of the paper's parameter sets the tracker starts from (JNI `preset`):
 *
 * | code | value     | thresholds |
 * |------|-----------|------------|
 * | 0    | [PC]      | Table 1: L1 (30 mm, 7°), L2 (120 mm, 12°), εn 28°, εg 7° |
 * | 1    | [PHONE]   | Table 2: L1 (30 mm, 3°), L2 (70 mm, 7°), εn 45°, εg 20° |
 */
enum class Preset(val code: Int) {
    /** The paper's PC values. */
    PC(0),

    /** The paper's phone values. */
    PHONE(1);

    companion object {
        /** The preset with this [code]; throws IllegalArgumentException for an unknown code. */
        fun fromCode(code: Int): Preset = entries.firstOrNull { it.code == code }
            ?: throw IllegalArgumentException("unknown preset code $code")
    }
}

/**
 * Which error-correction levels run, the columns of the paper's Table 1 (JNI `mode`):
 *
 * | code | value     | meaning |
 * |------|-----------|---------|
 * | 0    | [NAIVE]   | frame-to-frame only, no reference frames |
 * | 1    | [L1]      | level-one error correction |
 * | 2    | [L2]      | level-one and level-two error correction |
 */
enum class Mode(val code: Int) {
    /** Plain frame-to-frame tracking. */
    NAIVE(0),

    /** Level-one error correction only. */
    L1(1),

    /** Level-one and level-two error correction. */
    L2(2);

    companion object {
        /** The mode with this [code]; throws IllegalArgumentException for an unknown code. */
        fun fromCode(code: Int): Mode = entries.firstOrNull { it.code == code }
            ?: throw IllegalArgumentException("unknown mode code $code")
    }
}

/**
 * What the tracker does when frames arrive faster than it tracks them. It crosses the
 * JNI boundary as the boolean `live` of `nativeInit` ([live] is `true` for [LIVE]);
 * the codes exist for logs and settings:
 *
 * | code | value       | `live` | meaning |
 * |------|-------------|--------|---------|
 * | 0    | [LIVE]      | true   | a camera: when the tracker falls behind, the oldest waiting frame is dropped so latency stays bounded ([PushStatus.DROPPED]) |
 * | 1    | [OFFLINE]   | false  | a recording: pushFrame waits until the frame can be queued, nothing is dropped |
 */
enum class Admission(val code: Int) {
    /** Drop frames the tracker cannot keep up with (live camera). */
    LIVE(0),

    /** Never drop; pushFrame blocks instead (replaying a recording). */
    OFFLINE(1);

    /** The `live` flag of `nativeInit`. */
    val live: Boolean get() = this == LIVE

    companion object {
        /** The admission policy with this [code]; throws IllegalArgumentException for an unknown code. */
        fun fromCode(code: Int): Admission = entries.firstOrNull { it.code == code }
            ?: throw IllegalArgumentException("unknown admission code $code")
    }
}

/**
 * What became of a pushed frame (return value of `nativePushBuffers`/`nativePushArrays`):
 *
 * | code | value        | meaning |
 * |------|--------------|---------|
 * | 0    | [ACCEPTED]   | copied and queued for tracking |
 * | 1    | [DROPPED]    | this frame was queued, and to make room the oldest frame still waiting was dropped untracked ([Admission.LIVE] only) |
 */
enum class PushStatus(val code: Int) {
    /** The frame was copied and will be tracked. */
    ACCEPTED(0),

    /** This frame was queued; an older frame still waiting was dropped untracked to bound latency. */
    DROPPED(1),

    /**
     * This frame is bit-identical to the previous one (a frozen camera delivering the same
     * image again): not tracked, counted; the next new frame is tracked as usual.
     */
    REPEATED(2);

    companion object {
        /** The status with this [code]; an unknown code means the library and this class disagree. */
        fun fromCode(code: Int): PushStatus = entries.firstOrNull { it.code == code }
            ?: throw IllegalStateException("native library returned unknown push status $code")
    }
}

/**
 * Where the tracker stands (return value of `nativeState`):
 *
 * | code | value            | meaning |
 * |------|------------------|---------|
 * | 0    | [INITIALISING]   | no frame tracked yet |
 * | 1    | [TRACKING]       | the last frame registered |
 * | 2    | [LOST]           | the last frame did not register; the pose is the last good one |
 */
enum class TrackingState(val code: Int) {
    /** No frame tracked yet. */
    INITIALISING(0),

    /** The last frame registered. */
    TRACKING(1),

    /** The last frame did not register; the pose is the last good one. */
    LOST(2);

    companion object {
        /** The state with this [code]; an unknown code means the library and this class disagree. */
        fun fromCode(code: Int): TrackingState = entries.firstOrNull { it.code == code }
            ?: throw IllegalStateException("native library returned unknown tracking state $code")
    }
}

/**
 * Settings of one [Tracker]: the depth camera's pinhole intrinsics at the frame size,
 * how its depth is encoded, and which of the paper's variants to run.
 *
 * Nothing is checked here: the native side validates every field when the tracker is
 * created and throws IllegalArgumentException naming the bad one.
 *
 * @property width frame width in pixels (the phone sensors this targets give 320x180).
 * @property height frame height in pixels.
 * @property fx focal length in pixels, x.
 * @property fy focal length in pixels, y.
 * @property cx principal point x in pixels (pixel centres at integers).
 * @property cy principal point y in pixels.
 * @property depthFormat how the 16-bit depth samples encode distance.
 * @property depthScale raw depth units per metre; used by [DepthFormat.CUSTOM_SCALE]
 *   only (the millimetre formats imply 1000).
 * @property minConfidence 0..7: [DepthFormat.DEPTH16] pixels with a lower confidence
 *   level become "no measurement" (0 keeps every pixel); [AUTO_CONFIDENCE] (-1) keeps
 *   levels from 1 unless that drops more than half of a frame's ranged pixels (a sensor
 *   whose codes do not follow Android's documentation), then every ranged pixel for the
 *   tracker's life; ignored by the other formats.
 * @property preset the paper's PC or phone thresholds.
 * @property mode naive, L1 or L2 error correction.
 * @property admission drop frames when busy (live camera) or never (replay).
 * @property threads worker threads of the tracker.
 * @property pointCloud whether the reference frames' point cloud is built (a geometry
 *   stage that costs time per reference frame); off when nothing shows or exports it,
 *   and then [Tracker.pointCloud] returns no points.
 */
data class TrackerConfig(
    val width: Int = 320,
    val height: Int = 180,
    val fx: Double,
    val fy: Double,
    val cx: Double,
    val cy: Double,
    val depthFormat: DepthFormat = DepthFormat.MILLIMETRES,
    val depthScale: Double = 1000.0,
    val minConfidence: Int = 0,
    val preset: Preset = Preset.PHONE,
    val mode: Mode = Mode.L2,
    val admission: Admission = Admission.LIVE,
    val threads: Int = 2,
    val pointCloud: Boolean = false,
) {
    companion object {
        /** [minConfidence] value for the automatic rule (see the property). */
        const val AUTO_CONFIDENCE: Int = -1
    }
}
