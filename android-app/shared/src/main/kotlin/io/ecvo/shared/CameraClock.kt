package io.ecvo.shared

/**
 * Puts a camera's frame timestamps and the gyroscope's `SensorEvent.timestamp`s on one
 * clock: [offsetNs] is what to subtract from a sensor timestamp to get the camera's time
 * base (`t_camera = t_sensor - offsetNs`). `SensorEvent.timestamp` is
 * `SystemClock.elapsedRealtimeNanos` (CLOCK_BOOTTIME).
 *
 * - `SENSOR_INFO_TIMESTAMP_SOURCE` REALTIME: the camera stamps with the same clock, the
 *   offset is 0 ([Method.REALTIME]).
 * - UNKNOWN: Camera2 promises only a monotonic clock, in practice CLOCK_MONOTONIC
 *   (`System.nanoTime`), which stops in deep sleep while BOOTTIME does not. The offset
 *   is measured over the first [framesToMeasure] frames from each frame's arrival in the
 *   app, read on both clocks ([onFrame]):
 *   - if every frame arrived between 0 and [maxLatencyNs] after its timestamp read on
 *     CLOCK_MONOTONIC, the camera uses that clock, and the offset is BOOTTIME - MONOTONIC,
 *     read by [bracket] as the tightest of several back-to-back clock reads (error: the
 *     read's width, about a microsecond) ([Method.MONOTONIC]);
 *   - otherwise the camera's clock is unknown, and the offset is the smallest
 *     `arrival_boottime - timestamp` seen ([Method.ARRIVAL]): sensor samples then read a
 *     little late (by the camera's smallest delivery latency, a few milliseconds to a few
 *     tens), which the engine's prior tolerates as a time offset.
 *
 * Until the offset is known ([offsetNs] null) samples cannot be placed; callers drop them.
 * Thread-safe.
 */
class CameraClock(
    realtimeSource: Boolean,
    /** BOOTTIME - MONOTONIC in ns, read now (the app passes [bracket]'s result); used for UNKNOWN. */
    private val boottimeMinusMonotonicNs: Long,
    private val framesToMeasure: Int = 15,
    private val maxLatencyNs: Long = 300_000_000L,
) {
    /** How the offset was found. */
    enum class Method(val label: String) {
        REALTIME("realtime"), MONOTONIC("monotonic"), ARRIVAL("arrival")
    }

    private var frames = 0
    private var minMono = Long.MAX_VALUE
    private var maxMono = Long.MIN_VALUE
    private var minBoot = Long.MAX_VALUE
    private var offset: Long? = if (realtimeSource) 0L else null
    private var how: Method? = if (realtimeSource) Method.REALTIME else null

    init {
        require(framesToMeasure > 0) { "framesToMeasure: $framesToMeasure is not positive" }
    }

    /** Sensor-minus-camera clock offset in ns, or null until measured. */
    @get:Synchronized
    val offsetNs: Long? get() = offset

    /** How [offsetNs] was found, or null until measured. */
    @get:Synchronized
    val method: Method? get() = how

    /**
     * A frame stamped [cameraNs] arrived in the app when `elapsedRealtimeNanos` read
     * [arrivalBoottimeNs] and `System.nanoTime` read [arrivalMonotonicNs].
     */
    @Synchronized
    fun onFrame(cameraNs: Long, arrivalBoottimeNs: Long, arrivalMonotonicNs: Long) {
        if (offset != null) return
        val dm = arrivalMonotonicNs - cameraNs
        minMono = minOf(minMono, dm); maxMono = maxOf(maxMono, dm)
        minBoot = minOf(minBoot, arrivalBoottimeNs - cameraNs)
        if (++frames < framesToMeasure) return
        if (minMono >= 0 && maxMono <= maxLatencyNs) {
            offset = boottimeMinusMonotonicNs
            how = Method.MONOTONIC
        } else {
            offset = minBoot
            how = Method.ARRIVAL
        }
    }

    /** [sensorNs] on the camera's clock, or null while the offset is unknown. */
    @Synchronized
    fun toCamera(sensorNs: Long): Long? = offset?.let { sensorNs - it }

    companion object {
        /**
         * BOOTTIME - MONOTONIC from [tries] back-to-back reads `mono, boot, mono`: the
         * read whose two monotonic readings are closest brackets the boot reading best;
         * the estimate is its boot reading minus their midpoint.
         */
        fun bracket(boottime: () -> Long, monotonic: () -> Long, tries: Int = 16): Long {
            var best = Long.MAX_VALUE
            var result = 0L
            for (i in 0 until tries) {
                val a = monotonic(); val b = boottime(); val c = monotonic()
                if (c - a < best) {
                    best = c - a
                    result = b - (a + (c - a) / 2)
                }
            }
            return result
        }
    }
}
