package io.ecvo

import java.nio.ByteBuffer

/**
 * The native methods of libecvo_jni, declared once. Only [Tracker] calls them; the Rust
 * side (`rust/ecvo-jni`) registers the same names and signatures, and a test checks that
 * the two agree. Every method throws IllegalArgumentException for bad input,
 * IllegalStateException for a released handle and RuntimeException for a caught panic.
 */
internal object NativeBridge {
    init {
        // The one place the library is loaded.
        System.loadLibrary("ecvo_jni")
    }

    /** Does nothing; calling it runs the `init` above (loading the library) or throws its LinkageError. */
    fun ensureLoaded() = Unit

    /** Creates a tracker; returns its handle (never 0). Codes: see [TrackerConfig]. */
    @JvmStatic external fun nativeInit(
        width: Int, height: Int,
        fx: Double, fy: Double, cx: Double, cy: Double,
        depthFormat: Int, depthScale: Double, minConfidence: Int,
        preset: Int, mode: Int, live: Boolean, threads: Int, pointCloud: Boolean,
    ): Long

    /** Copies one frame from direct buffers; returns a [PushStatus] code. */
    @JvmStatic external fun nativePushBuffers(handle: Long, timestampNs: Long, depth: ByteBuffer?, intensity: ByteBuffer?): Int

    /**
     * Copies one frame from direct buffers whose rows are [depthRowStride] and
     * [intensityRowStride] bytes apart (an `ImageReader` plane with padding); returns a
     * [PushStatus] code.
     */
    @JvmStatic external fun nativePushStrided(
        handle: Long, timestampNs: Long,
        depth: ByteBuffer?, depthRowStride: Int, intensity: ByteBuffer?, intensityRowStride: Int,
    ): Int

    /** Copies one frame from arrays; returns a [PushStatus] code. */
    @JvmStatic external fun nativePushArrays(handle: Long, timestampNs: Long, depth: ShortArray?, intensity: ByteArray?): Int

    /** Writes the latest pose (4x4 column-major, camera to world) into out[0..16]; returns its timestamp or Long.MIN_VALUE. */
    @JvmStatic external fun nativeGetPose(handle: Long, out: FloatArray?): Long

    /**
     * Takes one gyroscope sample: [timestampNs] on the frames' clock, rates in rad/s in the
     * camera's axes (x right, y down, z forward). IllegalArgumentException for a
     * non-finite rate.
     */
    @JvmStatic external fun nativePushImu(handle: Long, timestampNs: Long, wx: Double, wy: Double, wz: Double)

    /**
     * Takes samples `0 until count`: [timestampsNs][i] and [rates][3i..3i+2] (as
     * [nativePushImu]), in one crossing. IllegalArgumentException (none taken) for a null
     * or short array, a negative count or more than 4096, or a non-finite rate.
     */
    @JvmStatic external fun nativePushImuBatch(handle: Long, timestampsNs: LongArray?, rates: FloatArray?, count: Int)

    /**
     * Writes the latest frame, its pose and its registration's quality into
     * out[0..FrameQuality.SIZE] (layout at [FrameQuality.SIZE]); returns its timestamp or
     * Long.MIN_VALUE, as [nativeGetPose].
     */
    @JvmStatic external fun nativeFrameQuality(handle: Long, out: DoubleArray?): Long

    /** The tracking state code: 0 initialising, 1 tracking, 2 lost. */
    @JvmStatic external fun nativeState(handle: Long): Int

    /** Blocks until every accepted frame has been tracked. */
    @JvmStatic external fun nativeFlush(handle: Long)

    /** New intrinsics (pixels of the pushed frames) for the frames pushed from now on. */
    @JvmStatic external fun nativeSetIntrinsics(handle: Long, fx: Double, fy: Double, cx: Double, cy: Double)

    /** The trajectory so far: 8 doubles per frame (t seconds, tx, ty, tz, qx, qy, qz, qw). */
    @JvmStatic external fun nativeTrajectory(handle: Long): DoubleArray

    /** The poses from trajectory index [from] on (same layout); empty when there are none. */
    @JvmStatic external fun nativeTrajectorySince(handle: Long, from: Int): DoubleArray

    /** The reference frames chosen so far, same layout plus the level: 9 doubles each. */
    @JvmStatic external fun nativeReferences(handle: Long): DoubleArray

    /** Statistics, see [TrackerStats.fromArray] for the layout. */
    @JvmStatic external fun nativeStats(handle: Long): DoubleArray

    /** A snapshot of the reference frames' point cloud: 4 floats per point (x, y, z, intensity 0..1), at most maxPoints. */
    @JvmStatic external fun nativePointCloud(handle: Long, maxPoints: Int): FloatArray

    /** Releases the tracker; idempotent on the Kotlin side, which zeroes the handle first. */
    @JvmStatic external fun nativeRelease(handle: Long)

    /**
     * The bytes [nativeInit] with the same arguments would allocate, computed without
     * allocating; init refuses (IllegalArgumentException naming both) above the budget.
     */
    @JvmStatic external fun nativeMemoryNeeded(
        width: Int, height: Int,
        fx: Double, fy: Double, cx: Double, cy: Double,
        depthFormat: Int, depthScale: Double, minConfidence: Int,
        preset: Int, mode: Int, live: Boolean, threads: Int, pointCloud: Boolean,
    ): Long

    /** Sets the memory budget (bytes, > 0; default 512 MiB) of the trackers created from now on; returns the previous one. */
    @JvmStatic external fun nativeSetMemoryBudget(bytes: Long): Long
}
