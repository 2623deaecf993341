package io.ecvo.shared

import kotlin.math.max

/**
 * Puts the frame timestamps of successive camera instances (the first open, a resume
 * after a pause, a depth-only restart) on one monotonic timeline for the one tracker they
 * feed. Camera2 promises nothing across instances for `SENSOR_INFO_TIMESTAMP_SOURCE`
 * UNKNOWN: a clock that restarts lower would make every later frame a refused timestamp,
 * a permanent, silent stall.
 *
 * - The first instance's timestamps are used as they are.
 * - A later instance with a REALTIME clock (`elapsedRealtimeNanos`, one clock for every
 *   instance) is used as it is, as long as it is ahead of the timeline.
 * - Any other later instance gets an offset, fixed at its first frame, that puts that
 *   frame after the last accepted one by the wall-clock time between their arrivals
 *   (at least [minGapNs]); its later frames keep their own spacing.
 * - When the tracker refuses [refusalsBeforeRebase] frames in a row (a clock that jumped
 *   back within an instance), [refused] re-bases the next frame the same way and says so.
 *
 * Thread-safe: the camera thread calls [newInstance] and [map], the frame's caller
 * [accepted] or [refused].
 */
class CameraTimeline(
    private val refusalsBeforeRebase: Int = 5,
    private val minGapNs: Long = 1_000_000L,
) {
    private var realtime = false
    private var pendingStart = true
    private var offset = 0L
    private var lastOut = Long.MIN_VALUE
    private var lastArrival = 0L
    private var refusedRun = 0

    init {
        require(refusalsBeforeRebase > 0) { "refusalsBeforeRebase: $refusalsBeforeRebase is not positive" }
        require(minGapNs > 0) { "minGapNs: $minGapNs is not positive" }
    }

    /** Times the timeline was re-based because refusals persisted. */
    @get:Synchronized
    var rebases: Int = 0
        private set

    /** The next frame comes from a new camera instance, whose clock is REALTIME if [realtimeClock]. */
    @Synchronized
    fun newInstance(realtimeClock: Boolean) {
        realtime = realtimeClock
        pendingStart = true
    }

    /** The timeline's timestamp for a frame stamped [rawNs] by its camera that arrived at wall-clock [arrivalNs]. */
    @Synchronized
    fun map(rawNs: Long, arrivalNs: Long): Long {
        if (pendingStart) {
            pendingStart = false
            offset = when {
                lastOut == Long.MIN_VALUE -> 0L
                realtime && rawNs > lastOut -> 0L
                else -> lastOut + max(minGapNs, arrivalNs - lastArrival) - rawNs
            }
        }
        return rawNs + offset
    }

    /**
     * A time [rawNs] on the current camera instance's clock (a gyroscope sample's, put on
     * that clock by [CameraClock]) on the timeline, with the offset [map] gave that
     * instance's frames; null before the instance's first frame (its offset is not fixed
     * yet).
     */
    @Synchronized
    fun mapInstant(rawNs: Long): Long? = if (pendingStart) null else rawNs + offset

    /** The tracker took the frame [map] gave [mappedNs], which arrived at [arrivalNs]. */
    @Synchronized
    fun accepted(mappedNs: Long, arrivalNs: Long) {
        lastOut = mappedNs
        lastArrival = arrivalNs
        refusedRun = 0
    }

    /**
     * The tracker refused the frame's timestamp. Returns true when refusals persisted: the
     * next frame is then re-based (on the wall clock, whatever the camera's clock).
     */
    @Synchronized
    fun refused(): Boolean {
        refusedRun++
        if (refusedRun < refusalsBeforeRebase || lastOut == Long.MIN_VALUE) return false
        refusedRun = 0
        realtime = false
        pendingStart = true
        rebases++
        return true
    }
}
