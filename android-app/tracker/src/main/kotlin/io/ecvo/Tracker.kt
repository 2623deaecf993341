package io.ecvo

import java.nio.ByteBuffer
import java.util.concurrent.locks.ReentrantReadWriteLock
import java.util.logging.Logger
import kotlin.concurrent.read
import kotlin.concurrent.write

/**
 * What the app needs from a tracker: implemented by [Tracker] over the native library,
 * and by fakes in tests of the app's session logic.
 */
interface PoseTracker : AutoCloseable {
    /** Pushes one frame (see [Tracker.pushFrame]). */
    fun pushFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray): PushStatus

    /** The latest pose into `out[0..16]`; its timestamp, or [Tracker.NO_POSE]. */
    fun getPose(out: FloatArray): Long

    /** Gyroscope samples `0 until count` for the frames pushed after the call (see [Tracker.pushImu]). */
    fun pushImu(timestampsNs: LongArray, rates: FloatArray, count: Int)

    /** The current tracking state. */
    val state: TrackingState

    /** Counters and per-stage times. */
    fun stats(): TrackerStats

    /** The poses from index [from] of the trajectory on. */
    fun trajectorySince(from: Int): List<TimedPose>

    /** The reference frames chosen so far. */
    fun references(): List<ReferenceFrame>

    /** Up to [maxPoints] points of the reference frames' cloud, 4 floats each. */
    fun pointCloud(maxPoints: Int): FloatArray

    /** Blocks until every accepted frame has been tracked. */
    fun flush()

    /** Whether [close] has been called. */
    val isClosed: Boolean
}

/**
 * An RGB-D camera tracker (An et al., WACV 2018) running in `libecvo_jni`; owns the
 * native handle.
 *
 * ```
 * Tracker(config).use { t ->
 *     t.pushFrame(timestampNs, depth, intensity)
 *     val m = FloatArray(16)
 *     if (t.getPose(m) != Tracker.NO_POSE) draw(m)
 * }
 * ```
 *
 * A process holds at most 16 live trackers (`MAX_LIVE_TRACKERS` in `libecvo_jni`); the
 * next one throws IllegalStateException until one is closed. `init` computes the
 * tracker's memory first and refuses above the budget (default 512 MiB,
 * `NativeBridge.nativeSetMemoryBudget`; ask with `NativeBridge.nativeMemoryNeeded`).
 *
 * Frames are copied before `pushFrame` returns, so the caller may reuse its buffers at
 * once. Methods may be called from several threads (a camera thread pushing, the UI
 * thread reading the pose); [close] waits for calls in progress and then releases the
 * native tracker. Every method of a closed tracker throws IllegalStateException; the
 * native side throws IllegalArgumentException for bad input and RuntimeException for
 * an internal error.
 *
 * Call [close] (or `use`) when done. A tracker that becomes unreachable without [close]
 * is released by a safety net, a phantom-reference queue drained on a daemon thread
 * (and at the 16-tracker cap, where a new Tracker asks for a garbage collection and
 * drains the queue before it refuses)
 * (`java.lang.ref.Cleaner` would need API 33; the app's minSdk is 26), which logs a
 * warning: that is a leak in the caller to fix, not a way to release trackers (the
 * native threads run until the garbage collector happens to notice).
 *
 * @throws IllegalArgumentException from the constructor if the native side rejects
 *   [config]; the message names the field.
 * @throws UnsatisfiedLinkError or NoClassDefFoundError if `libecvo_jni` cannot be loaded;
 *   [nativeLibraryError] turns that into a message first.
 */
class Tracker(val config: TrackerConfig) : PoseTracker {
    /** The native handle and its release, shared with the reaper (which must not reach this object). */
    private class Handle(var value: Long) : Runnable {
        /** Calls share the read lock; [run] takes the write lock, so it never frees a handle in use. */
        val lock = ReentrantReadWriteLock()
        @Volatile var closedExplicitly = false

        override fun run() = lock.write {
            val h = value
            if (h != 0L) {
                try {
                    if (!closedExplicitly) LOG.warning("ecvo: a Tracker was garbage-collected without close(); releasing its native tracker $h")
                    NativeBridge.nativeRelease(h)
                } finally {
                    value = 0L // after the release: 0 means released
                }
            }
        }
    }

    private val handle: Handle
    private val cleanable: NativeReaper.Cleanable

    init {
        val h = initNative(config)
        check(h != 0L) { "native tracker returned a null handle" }
        handle = Handle(h)
        cleanable = REAPER.register(this, handle)
    }

    private inline fun <T> withHandle(block: (Long) -> T): T = handle.lock.read {
        val h = handle.value
        check(h != 0L) { "Tracker is closed" }
        block(h)
    }

    override val isClosed: Boolean get() = handle.lock.read { handle.value == 0L }

    /**
     * Pushes one frame from direct buffers: [depth] holds `width * height` 16-bit samples
     * in the config's [DepthFormat], little-endian (`order(ByteOrder.LITTLE_ENDIAN)`;
     * `ImageReader` planes already are; a big-endian depth buffer is an
     * IllegalArgumentException), [intensity] `width * height` 8-bit gray values, both
     * row-major without padding. Each buffer is read from its `position()` up to its
     * `limit()`, which must hold the whole frame. Frames must come from memory the caller
     * owns: a direct buffer over a memory-mapped file that is truncated while it is read
     * makes the copy fault (SIGBUS), which no JNI code can catch.
     * [timestampNs] is the capture time (e.g. `Image.getTimestamp()`), increasing: a
     * timestamp not after the previous frame's is an IllegalArgumentException (the frame is
     * not tracked; later frames are). A frame bit-identical to the previous one is
     * [PushStatus.REPEATED] and not tracked.
     */
    fun pushFrame(timestampNs: Long, depth: ByteBuffer, intensity: ByteBuffer): PushStatus = withHandle { h ->
        PushStatus.fromCode(NativeBridge.nativePushBuffers(h, timestampNs, depth, intensity))
    }

    /**
     * Pushes one frame from direct buffers with padded rows, such as `ImageReader` planes:
     * row `y` of depth starts at byte `y * depthRowStride` (2 bytes per sample, pixel
     * stride 2), of intensity at `y * intensityRowStride` (pixel stride 1). A stride
     * smaller than a row, or a buffer too small for `(height - 1)` strides plus one row,
     * is an IllegalArgumentException naming the buffer.
     */
    fun pushFrame(timestampNs: Long, depth: ByteBuffer, depthRowStride: Int, intensity: ByteBuffer, intensityRowStride: Int): PushStatus =
        withHandle { h -> PushStatus.fromCode(NativeBridge.nativePushStrided(h, timestampNs, depth, depthRowStride, intensity, intensityRowStride)) }

    /** Pushes one frame from arrays; same contract as the ByteBuffer overload. */
    override fun pushFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray): PushStatus = withHandle { h ->
        PushStatus.fromCode(NativeBridge.nativePushArrays(h, timestampNs, depth, intensity))
    }

    /**
     * Gives the tracker one gyroscope sample (issue 47): [timestampNs] on the clock of the
     * frames' timestamps (an app puts `SensorEvent.timestamp` on it), angular rate in rad/s
     * in the **camera's axes** (x right, y down, z forward: rotate the device's sensor
     * axes first, e.g. with `ImuCalibration.cameraFromDevice` of `:shared`). Samples count
     * for the frames pushed after the call: push a frame's samples before the frame. Each
     * frame's registration then starts from the gyroscope's rotation over its interval,
     * with the bias estimated online. Samples in time order; one not after the last one
     * taken is dropped and counted ([TrackerStats.imuRefused]); late or missing samples
     * make frames track without the gyroscope, counted, never an error. A non-finite rate
     * is an IllegalArgumentException. Without any sample the poses are those of a tracker
     * without an IMU, bit for bit.
     */
    fun pushImu(timestampNs: Long, wx: Double, wy: Double, wz: Double): Unit =
        withHandle { h -> NativeBridge.nativePushImu(h, timestampNs, wx, wy, wz) }

    /**
     * Gives the tracker samples `0 until count` in one native call (a sensor callback's or
     * a frame's worth, at most [MAX_IMU_BATCH]): [timestampsNs][i] and the rates
     * [rates][3i], [rates][3i+1], [rates][3i+2], as [pushImu]. The arrays are read before
     * the call returns. A non-finite rate refuses the whole batch
     * (IllegalArgumentException, none taken), as do a short array or a bad [count].
     */
    override fun pushImu(timestampsNs: LongArray, rates: FloatArray, count: Int): Unit =
        withHandle { h -> NativeBridge.nativePushImuBatch(h, timestampsNs, rates, count) }

    /**
     * Writes the latest pose into `out[0..16]`: a 4x4 column-major camera-to-world matrix
     * (world = first camera; x right, y down, z forward), ready for OpenGL. Returns that
     * frame's timestamp in nanoseconds, or [NO_POSE] (leaving [out] untouched) before the
     * first frame is tracked.
     */
    override fun getPose(out: FloatArray): Long = withHandle { h -> NativeBridge.nativeGetPose(h, out) }

    /**
     * Writes the latest tracked frame with the quality of its registration into
     * `out[0..FrameQuality.SIZE]` (layout at [FrameQuality.SIZE]: index, state, lost
     * reason, pose, the 6x6 information matrix, residual scale, points used) and returns
     * its timestamp in nanoseconds, or [NO_POSE] (leaving [out] untouched) before the
     * first frame is tracked. Allocates nothing: a caller polling every frame reuses
     * [out]. The pose and the figures are of the same frame. Only the latest frame is
     * kept: a caller that polls less often than frames are tracked sees a gap in
     * `out[0]`, the frame index.
     */
    fun frameQuality(out: DoubleArray): Long = withHandle { h -> NativeBridge.nativeFrameQuality(h, out) }

    /** The latest tracked frame with its quality (see the overload above), or null before the first. */
    fun frameQuality(): FrameQuality? {
        val a = DoubleArray(FrameQuality.SIZE)
        return if (frameQuality(a) == NO_POSE) null else FrameQuality.fromArray(a)
    }

    /** The current tracking state. */
    override val state: TrackingState get() = withHandle { h -> TrackingState.fromCode(NativeBridge.nativeState(h)) }

    /** Blocks until every accepted frame has been tracked. */
    override fun flush(): Unit = withHandle { h -> NativeBridge.nativeFlush(h) }

    /**
     * New intrinsics, in pixels of the pushed frames, for the frames pushed from now on:
     * a zoom, a refocus, or a calibration the camera reports per frame
     * (`CaptureResult.LENS_INTRINSIC_CALIBRATION`). Tracking goes on across the change;
     * a zoom the tracker is not told about reads as the camera moving along its axis.
     * Throws IllegalArgumentException on values that are not finite or a zero focal
     * length.
     */
    fun setIntrinsics(fx: Double, fy: Double, cx: Double, cy: Double): Unit =
        withHandle { h -> NativeBridge.nativeSetIntrinsics(h, fx, fy, cx, cy) }

    /**
     * The estimated trajectory so far, one camera-to-world pose per tracked frame: the
     * latest [TRAJECTORY_WINDOW] of them ([TrackerStats.trajectoryStart] is the index of
     * the first).
     */
    fun trajectory(): List<TimedPose> = withHandle { h -> TimedPose.listFromArray(NativeBridge.nativeTrajectory(h)) }

    /**
     * The poses from index [from] (0-based, in tracking order) on: a UI that has `n`
     * poses asks for `trajectorySince(n)` and copies only what is new. The tracker keeps
     * the latest [TRAJECTORY_WINDOW] poses; asking from before
     * [TrackerStats.trajectoryStart] throws IllegalArgumentException.
     */
    override fun trajectorySince(from: Int): List<TimedPose> = withHandle { h ->
        require(from >= 0) { "from: $from is negative" }
        TimedPose.listFromArray(NativeBridge.nativeTrajectorySince(h, from))
    }

    /** The reference frames chosen so far, in time order. */
    override fun references(): List<ReferenceFrame> = withHandle { h -> ReferenceFrame.listFromArray(NativeBridge.nativeReferences(h)) }

    /** Counters and per-stage times. */
    override fun stats(): TrackerStats = withHandle { h -> TrackerStats.fromArray(NativeBridge.nativeStats(h)) }

    /**
     * A snapshot of the reference frames' points in world coordinates: 4 floats per point
     * (x, y, z, intensity 0..1), at most [maxPoints] points; none unless
     * [TrackerConfig.pointCloud].
     */
    override fun pointCloud(maxPoints: Int): FloatArray = withHandle { h -> NativeBridge.nativePointCloud(h, maxPoints) }

    /**
     * Releases the native tracker. Waits for calls in progress on other threads; calling it
     * again does nothing.
     */
    override fun close() {
        handle.closedExplicitly = true
        cleanable.clean()
    }

    companion object {
        /** What [getPose] returns when there is no pose yet. */
        const val NO_POSE: Long = Long.MIN_VALUE

        /** Most samples one [pushImu] batch takes (`ecvo_jni::imu::MAX_BATCH`). */
        const val MAX_IMU_BATCH: Int = 4096

        /**
         * Poses the native tracker keeps (the latest ones; about 18 minutes at 30 Hz), so
         * that its memory is constant over a session of any length.
         */
        const val TRAJECTORY_WINDOW: Int = 32_768

        private val LOG: Logger = Logger.getLogger("io.ecvo.Tracker")
        private val REAPER = NativeReaper("ecvo-tracker-reaper")

        /** The words of the native refusal at the live-tracker cap (`ecvo_jni::limits`). */
        private const val AT_CAP = "trackers are live"

        /** Collections asked for at the cap before refusing (pauses 1, 2, 4, ... ms: 255 ms in all). */
        private const val CAP_RETRIES = 8

        /**
         * `nativeInit`. At the live-tracker cap, what `java.nio` does for direct memory:
         * ask for a garbage collection, release the trackers it found unreachable (the
         * reaper's queue, drained here), and retry with growing pauses; only then refuse.
         * A Tracker dropped without [close] then does not hold its place until a
         * collection that may never come (the JVM does not see native memory).
         */
        private fun initNative(config: TrackerConfig): Long {
            var pauseMs = 1L
            var attempt = 0
            while (true) {
                try {
                    return NativeBridge.nativeInit(
                        config.width, config.height,
                        config.fx, config.fy, config.cx, config.cy,
                        config.depthFormat.code, config.depthScale, config.minConfidence,
                        config.preset.code, config.mode.code, config.admission.live, config.threads, config.pointCloud,
                    )
                } catch (e: IllegalStateException) {
                    if (attempt == CAP_RETRIES || e.message?.contains(AT_CAP) != true) throw e
                }
                REAPER.drain()
                System.gc()
                if (attempt > 0) {
                    Thread.sleep(pauseMs)
                    pauseMs *= 2
                }
                REAPER.drain()
                attempt++
            }
        }

        /**
         * Whether [e] is the native side refusing a frame for its timestamp (not after the
         * previous accepted frame's, the `TimestampNotIncreasing` error of `ecvo-pipeline`):
         * that frame is not tracked but later frames are, so a caller may skip it and go on.
         * Any other exception is not this.
         */
        fun isRefusedTimestamp(e: Throwable): Boolean =
            e is IllegalArgumentException && e.message?.contains(REFUSED_TIMESTAMP) == true

        /** The words of the native message for a refused timestamp (`ecvo-pipeline`'s `TimestampNotIncreasing`). */
        const val REFUSED_TIMESTAMP: String = "is not after the previous frame's"

        /**
         * Loads `libecvo_jni` if it is not loaded yet; null when it is usable, else a
         * sentence saying why not (missing for this ABI, or failed to initialise). Never
         * throws: the UI shows the message instead of crashing.
         */
        fun nativeLibraryError(): String? = try {
            NativeBridge.ensureLoaded()
            null
        } catch (e: LinkageError) {
            // UnsatisfiedLinkError the first time, then NoClassDefFoundError /
            // ExceptionInInitializerError for every later use of NativeBridge.
            "The tracking library (libecvo_jni) could not be loaded for this phone's CPU " +
                "(${System.getProperty("os.arch")}): ${e.message ?: e.javaClass.simpleName}. Reinstall the app built for this ABI."
        }
    }
}
