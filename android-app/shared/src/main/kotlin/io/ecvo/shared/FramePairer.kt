package io.ecvo.shared

/** Camera2's `SENSOR_INFO_TIMESTAMP_SOURCE`. */
enum class TimestampSource(val code: Int) {
    /** Monotonic, but not comparable with other cameras' timestamps. */
    UNKNOWN(0),

    /** `SystemClock.elapsedRealtimeNanos()`: comparable across cameras and sensors. */
    REALTIME(1);

    companion object {
        /** Unknown or missing codes read as [UNKNOWN], the cautious reading. */
        fun fromCode(code: Int?): TimestampSource = if (code == 1) REALTIME else UNKNOWN
    }
}

/** How depth frames are paired with colour frames. */
enum class Pairing {
    /** By capture timestamp: both cameras stamp with the same clock ([TimestampSource.REALTIME]). */
    CAPTURE_TIME,

    /** By arrival time (the app's `elapsedRealtimeNanos` when each image arrived): the timestamps are not comparable. */
    ARRIVAL_TIME;

    companion object {
        /** Capture time only when both sources are REALTIME; Camera2 says UNKNOWN timestamps of two cameras cannot be compared. */
        fun choose(depth: TimestampSource, colour: TimestampSource): Pairing =
            if (depth == TimestampSource.REALTIME && colour == TimestampSource.REALTIME) CAPTURE_TIME else ARRIVAL_TIME
    }
}

/**
 * Pairs each depth frame with the latest colour frame, if that colour frame is within
 * [maxDtNs] of it (capture or arrival time, per [pairing]); a depth frame without one is
 * dropped and counted in [droppedNoColour]. Thread-safe (both camera callbacks may call it).
 */
class FramePairer(val pairing: Pairing, val maxDtNs: Long = 50_000_000L) {
    private var colourNs = Long.MIN_VALUE

    /** Depth frames dropped for want of a colour frame close enough in time. */
    @Volatile var droppedNoColour: Long = 0
        private set

    /** Depth frames paired. */
    @Volatile var paired: Long = 0
        private set

    /** A colour frame arrived: [captureNs] its timestamp, [arrivalNs] the app's clock now. */
    @Synchronized fun onColour(captureNs: Long, arrivalNs: Long) {
        colourNs = if (pairing == Pairing.CAPTURE_TIME) captureNs else arrivalNs
    }

    /** A depth frame arrived; true if it has a colour frame to pair with, false if it is dropped (and counted). */
    @Synchronized fun onDepth(captureNs: Long, arrivalNs: Long): Boolean {
        val t = if (pairing == Pairing.CAPTURE_TIME) captureNs else arrivalNs
        val ok = colourNs != Long.MIN_VALUE && kotlin.math.abs(t - colourNs) <= maxDtNs
        if (ok) paired++ else droppedNoColour++
        return ok
    }
}
