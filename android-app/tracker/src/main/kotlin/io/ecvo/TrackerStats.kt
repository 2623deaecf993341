package io.ecvo

/**
 * The tracker's counters (the paper's Table 1) and per-stage times (its Table 2),
 * read with [Tracker.stats].
 *
 * Times are in milliseconds of wall-clock time, 0 before the first frame; the stages are
 * those of the native pipeline (`ecvo-pipeline`'s `PipelineStats`), which run concurrently,
 * so [totalMs] is not their sum.
 */
data class TrackerStats(
    /** Frames handed to pushFrame and accepted (tracked or dropped later). */
    val framesPushed: Long,
    /** Frames dropped because the tracker was busy ([Admission.LIVE]), at any queue. */
    val framesDropped: Long,
    /** Frames fully tracked so far. */
    val framesTracked: Long,
    /** MOTION calls (frame-to-frame plus corrections): "motion estimations" in Table 1. */
    val motionEstimations: Long,
    /** Reference frames chosen at level 1 (the first frame is not counted). */
    val referencesL1: Long,
    /** Reference frames chosen at level 2. */
    val referencesL2: Long,
    /** Frames that did not register against the previous frame. */
    val lostFrames: Long,
    /** Corrections that failed; the frame kept its uncorrected pose. */
    val failedCorrections: Long,
    /** Times the tracker started afresh after a run of lost frames. */
    val reanchors: Long,
    /** Filter stage (frame preparation: depth filter, pyramid, gradients, points), mean ms per frame. */
    val filterMs: Double,
    /** Tracker stage (motion estimation and error correction), mean ms per frame. */
    val trackerMs: Double,
    /** Geometry stage (adding a reference frame to the point cloud), mean ms per reference. */
    val geometryMs: Double,
    /** Mean time from pushFrame to the frame's pose being available, ms. */
    val latencyMs: Double,
    /** Wall time from the first push to the last tracked frame divided by the frames tracked: the paper's "Total", ms. */
    val totalMs: Double,
    /**
     * Index of the first pose the tracker still keeps: 0 until a session passes
     * [Tracker.TRAJECTORY_WINDOW] poses, then the number of poses discarded (ask
     * [Tracker.trajectorySince] from here on).
     */
    val trajectoryStart: Long = 0,
    /** Gyroscope samples the tracker took ([Tracker.pushImu]). */
    val imuSamples: Long = 0,
    /** Gyroscope samples dropped because they were not after the last one taken. */
    val imuRefused: Long = 0,
    /** Gyroscope samples lost before the tracker read them (it was far behind). */
    val imuDropped: Long = 0,
    /** Frames whose frame-to-frame registration started from the gyroscope's rotation. */
    val imuPriors: Long = 0,
    /** Frames tracked without the gyroscope because its samples were late. */
    val imuLate: Long = 0,
    /** Frames tracked without the gyroscope because samples were missing over the frame's interval. */
    val imuMissing: Long = 0,
) {
    companion object {
        /**
         * Number of doubles in the array of `nativeStats`. Indices (counts are stored as
         * doubles holding whole numbers):
         *
         * | index | field |
         * |-------|-------|
         * | 0  | [framesPushed] |
         * | 1  | [framesDropped] |
         * | 2  | [framesTracked] |
         * | 3  | [motionEstimations] |
         * | 4  | [referencesL1] |
         * | 5  | [referencesL2] |
         * | 6  | [lostFrames] |
         * | 7  | [failedCorrections] |
         * | 8  | [reanchors] |
         * | 9  | [filterMs] |
         * | 10 | [trackerMs] |
         * | 11 | [geometryMs] |
         * | 12 | [latencyMs] |
         * | 13 | [totalMs] |
         * | 14 | [trajectoryStart] |
         * | 15 | [imuSamples] |
         * | 16 | [imuRefused] |
         * | 17 | [imuDropped] |
         * | 18 | [imuPriors] |
         * | 19 | [imuLate] |
         * | 20 | [imuMissing] |
         *
         * Later versions may append fields; [fromArray] ignores what it does not know.
         */
        const val SIZE: Int = 21

        /** All zeros: what a fresh tracker reports. */
        val EMPTY: TrackerStats = fromArray(DoubleArray(SIZE))

        /**
         * Reads the layout documented at [SIZE]. Throws IllegalArgumentException if
         * [a] has fewer than [SIZE] values.
         */
        fun fromArray(a: DoubleArray): TrackerStats {
            require(a.size >= SIZE) { "stats array has ${a.size} values, expected at least $SIZE" }
            return TrackerStats(
                framesPushed = a[0].toLong(),
                framesDropped = a[1].toLong(),
                framesTracked = a[2].toLong(),
                motionEstimations = a[3].toLong(),
                referencesL1 = a[4].toLong(),
                referencesL2 = a[5].toLong(),
                lostFrames = a[6].toLong(),
                failedCorrections = a[7].toLong(),
                reanchors = a[8].toLong(),
                filterMs = a[9],
                trackerMs = a[10],
                geometryMs = a[11],
                latencyMs = a[12],
                totalMs = a[13],
                trajectoryStart = a[14].toLong(),
                imuSamples = a[15].toLong(),
                imuRefused = a[16].toLong(),
                imuDropped = a[17].toLong(),
                imuPriors = a[18].toLong(),
                imuLate = a[19].toLong(),
                imuMissing = a[20].toLong(),
            )
        }
    }

    /** The inverse of [fromArray]: the documented layout, [SIZE] values. */
    fun toArray(): DoubleArray = doubleArrayOf(
        framesPushed.toDouble(), framesDropped.toDouble(), framesTracked.toDouble(),
        motionEstimations.toDouble(), referencesL1.toDouble(), referencesL2.toDouble(),
        lostFrames.toDouble(), failedCorrections.toDouble(), reanchors.toDouble(),
        filterMs, trackerMs, geometryMs, latencyMs, totalMs, trajectoryStart.toDouble(),
        imuSamples.toDouble(), imuRefused.toDouble(), imuDropped.toDouble(),
        imuPriors.toDouble(), imuLate.toDouble(), imuMissing.toDouble(),
    )
}
