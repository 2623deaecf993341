package io.ecvo.shared

/** Receives a batch of gyroscope samples: `0 until n` of [timestampsNs] and of [gyro] (3 per sample, rad/s). */
fun interface GyroSink {
    fun accept(timestampsNs: LongArray, gyro: FloatArray, n: Int)
}

/**
 * The gyroscope samples between sensor callbacks and their consumer, bounded: the sensor
 * thread [add]s each sample (or a callback's batch), the camera thread [drain]s them all
 * into one batch before each frame (one JNI call, one `imu.txt` write). At most
 * [capacity] samples wait (about 10 s at 400 Hz by default); when the consumer stops
 * draining (no frames: a paused camera), the oldest are dropped and counted in
 * [dropped]. Nothing is allocated after construction. Thread-safe; one consumer at a time.
 */
class GyroBuffer(val capacity: Int = DEFAULT_CAPACITY) {
    private val ts = LongArray(capacity)
    private val w = FloatArray(3 * capacity)
    private val outTs = LongArray(capacity)
    private val outW = FloatArray(3 * capacity)
    private var head = 0 // index of the oldest sample
    private var size = 0
    private var droppedCount = 0L
    private val drainLock = Any()

    init {
        require(capacity > 0) { "capacity: $capacity is not positive" }
    }

    /** Samples dropped because the buffer was full. */
    @get:Synchronized
    val dropped: Long get() = droppedCount

    /** Samples waiting. */
    @get:Synchronized
    val waiting: Int get() = size

    /** Adds one sample; drops the oldest waiting one when full. */
    @Synchronized
    fun add(timestampNs: Long, wx: Float, wy: Float, wz: Float) {
        if (size == capacity) {
            head = (head + 1) % capacity
            size--
            droppedCount++
        }
        val i = (head + size) % capacity
        ts[i] = timestampNs
        w[3 * i] = wx; w[3 * i + 1] = wy; w[3 * i + 2] = wz
        size++
    }

    /** Forgets the waiting samples (a new session, a camera restart). */
    @Synchronized
    fun clear() {
        head = 0
        size = 0
    }

    /**
     * Hands every waiting sample, oldest first, to [sink] in one batch and returns how
     * many. The sink runs outside the buffer's lock (the sensor thread keeps adding) and
     * must not keep the arrays: they are reused by the next drain.
     */
    fun drain(sink: GyroSink): Int = synchronized(drainLock) {
        val n: Int
        synchronized(this) {
            n = size
            for (k in 0 until n) {
                val i = (head + k) % capacity
                outTs[k] = ts[i]
                outW[3 * k] = w[3 * i]; outW[3 * k + 1] = w[3 * i + 1]; outW[3 * k + 2] = w[3 * i + 2]
            }
            head = 0
            size = 0
        }
        if (n > 0) sink.accept(outTs, outW, n)
        n
    }

    companion object {
        /** About 10 s at 400 Hz. */
        const val DEFAULT_CAPACITY: Int = 4096
    }
}
