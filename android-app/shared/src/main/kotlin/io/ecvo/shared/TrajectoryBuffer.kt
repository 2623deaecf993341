package io.ecvo.shared

import io.ecvo.TimedPose

/**
 * The poses the UI draws, read incrementally: [nextIndex] is what to pass to
 * `Tracker.trajectorySince`, and [append] takes what it returned. To keep the drawing's
 * cost flat over a long session, at most [maxPoints] poses are kept: when full, every
 * second one is dropped and from then on only every `stride`-th new pose is kept (the
 * latest pose is always drawn separately, from `getPose`). The shape of a path of a few
 * thousand points is unchanged at screen resolution.
 */
class TrajectoryBuffer(val maxPoints: Int = 4096) {
    init { require(maxPoints >= 4) { "maxPoints $maxPoints is too small" } }

    private val kept = ArrayList<TimedPose>()
    private var stride = 1

    /** Poses of the whole session received so far (the next index to ask for). */
    var nextIndex: Int = 0
        private set

    /** The poses to draw (a thinned copy of the trajectory once it is long). */
    val poses: List<TimedPose> get() = kept

    /** Path length so far in metres: the sum of the distances between consecutive poses (every pose, not only those kept). */
    var distanceM: Double = 0.0
        private set
    private var last: TimedPose? = null

    /** Appends the poses from index [nextIndex] on. */
    fun append(newPoses: List<TimedPose>) {
        for (p in newPoses) {
            last?.let { q -> distanceM += kotlin.math.sqrt((p.tx - q.tx) * (p.tx - q.tx) + (p.ty - q.ty) * (p.ty - q.ty) + (p.tz - q.tz) * (p.tz - q.tz)) }
            last = p
            if (nextIndex % stride == 0) {
                if (kept.size >= maxPoints) thin()
                if (nextIndex % stride == 0) kept += p
            }
            nextIndex++
        }
    }

    private fun thin() {
        var w = 0
        for (r in kept.indices step 2) kept[w++] = kept[r]
        while (kept.size > w) kept.removeAt(kept.size - 1)
        stride *= 2
    }

    /**
     * Moves [nextIndex] forward to [index] (the tracker discarded the poses in between);
     * the poses kept so far stay.
     */
    fun skipTo(index: Long) {
        require(index >= nextIndex && index <= Int.MAX_VALUE) { "cannot skip from $nextIndex to $index" }
        nextIndex = index.toInt()
    }

    /** Forgets everything (a new session). */
    fun clear() {
        kept.clear()
        distanceM = 0.0
        last = null
        stride = 1
        nextIndex = 0
    }
}

/**
 * A frame rate over a sliding window of wall-clock time: fed with the tracker's
 * frames-tracked counter at each poll, it reports the frames tracked per second over the
 * last [windowNs] (not since the start, so it shows a slow-down at once).
 */
class FrameRateWindow(val windowNs: Long = 2_000_000_000L) {
    private val times = ArrayDeque<Long>()
    private val counts = ArrayDeque<Long>()

    /** Records that [count] frames had been tracked at wall-clock [nowNs]. */
    fun sample(nowNs: Long, count: Long) {
        if (counts.isNotEmpty() && count < counts.last()) clear()
        times.addLast(nowNs); counts.addLast(count)
        while (times.size > 2 && nowNs - times[1] >= windowNs) { times.removeFirst(); counts.removeFirst() }
    }

    /** Frames per second over the window; 0 before two samples. */
    val fps: Double
        get() {
            if (times.size < 2) return 0.0
            val dt = times.last() - times.first()
            return if (dt <= 0) 0.0 else (counts.last() - counts.first()) * 1e9 / dt
        }

    fun clear() { times.clear(); counts.clear() }
}
