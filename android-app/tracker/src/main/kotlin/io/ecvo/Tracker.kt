package io.ecvo

import java.nio.ByteBuffer
import java.util.concurrent.locks.ReentrantReadWriteLock
import kotlin.concurrent.read
import kotlin.concurrent.write

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
 * Frames are copied before `pushFrame` returns, so the caller may reuse its buffers at
 * once. Methods may be called from several threads (a camera thread pushing, the UI
 * thread reading the pose); [close] waits for calls in progress and then releases the
 * native tracker. Every method of a closed tracker throws IllegalStateException; the
 * native side throws IllegalArgumentException for bad input and RuntimeException for
 * an internal error.
 *
 * @throws IllegalArgumentException from the constructor if the native side rejects
 *   [config]; the message names the field.
 */
class Tracker(val config: TrackerConfig) : AutoCloseable {
    /** The native handle; 0 once closed. Guarded by [lock]. */
    private var handle: Long

    /** Calls share the read lock; [close] takes the write lock, so it never frees a handle in use. */
    private val lock = ReentrantReadWriteLock()

    init {
        handle = NativeBridge.nativeInit(
            config.width, config.height,
            config.fx, config.fy, config.cx, config.cy,
            config.depthFormat.code, config.depthScale, config.minConfidence,
            config.preset.code, config.mode.code, config.admission.live, config.threads,
        )
        check(handle != 0L) { "native tracker returned a null handle" }
    }

    private inline fun <T> withHandle(block: (Long) -> T): T = lock.read {
        val h = handle
        check(h != 0L) { "Tracker is closed" }
        block(h)
    }

    /** Whether [close] has been called. */
    val isClosed: Boolean get() = lock.read { handle == 0L }

    /**
     * Pushes one frame from direct buffers: [depth] holds `width * height` 16-bit samples
     * in native byte order in the config's [DepthFormat], [intensity] `width * height`
     * 8-bit gray values, both row-major without padding, read from position 0.
     * [timestampNs] is the capture time (e.g. `Image.getTimestamp()`), increasing.
     */
    fun pushFrame(timestampNs: Long, depth: ByteBuffer, intensity: ByteBuffer): PushStatus = withHandle { h ->
        PushStatus.fromCode(NativeBridge.nativePushBuffers(h, timestampNs, depth, intensity))
    }

    /** Pushes one frame from arrays; same contract as the ByteBuffer overload. */
    fun pushFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray): PushStatus = withHandle { h ->
        PushStatus.fromCode(NativeBridge.nativePushArrays(h, timestampNs, depth, intensity))
    }

    /**
     * Writes the latest pose into `out[0..16]`: a 4x4 column-major camera-to-world matrix
     * (world = first camera; x right, y down, z forward), ready for OpenGL. Returns that
     * frame's timestamp in nanoseconds, or [NO_POSE] (leaving [out] untouched) before the
     * first frame is tracked.
     */
    fun getPose(out: FloatArray): Long = withHandle { h -> NativeBridge.nativeGetPose(h, out) }

    /** The current tracking state. */
    val state: TrackingState get() = withHandle { h -> TrackingState.fromCode(NativeBridge.nativeState(h)) }

    /** Blocks until every accepted frame has been tracked. */
    fun flush(): Unit = withHandle { h -> NativeBridge.nativeFlush(h) }

    /** The estimated trajectory so far, one camera-to-world pose per tracked frame. */
    fun trajectory(): List<TimedPose> = withHandle { h -> TimedPose.listFromArray(NativeBridge.nativeTrajectory(h)) }

    /** The reference frames chosen so far, in time order. */
    fun references(): List<ReferenceFrame> = withHandle { h -> ReferenceFrame.listFromArray(NativeBridge.nativeReferences(h)) }

    /** Counters and per-stage times. */
    fun stats(): TrackerStats = withHandle { h -> TrackerStats.fromArray(NativeBridge.nativeStats(h)) }

    /**
     * A snapshot of the reference frames' points in world coordinates: 4 floats per point
     * (x, y, z, intensity 0..1), at most [maxPoints] points.
     */
    fun pointCloud(maxPoints: Int): FloatArray = withHandle { h -> NativeBridge.nativePointCloud(h, maxPoints) }

    /**
     * Releases the native tracker. Waits for calls in progress on other threads; calling it
     * again does nothing.
     */
    override fun close() = lock.write {
        val h = handle
        handle = 0L
        if (h != 0L) NativeBridge.nativeRelease(h)
    }

    companion object {
        /** What [getPose] returns when there is no pose yet. */
        const val NO_POSE: Long = Long.MIN_VALUE
    }
}
