package io.ecvo.shared

import java.util.concurrent.locks.ReentrantLock
import kotlin.concurrent.withLock

/**
 * Paces a replay like its recording: the frame [offsetNs] after the first is due
 * `offsetNs / speed` after the start, not counting time spent paused. Changing the
 * speed keeps the position. Thread-safe: the replay thread waits in [awaitDue], the UI
 * thread calls [pause], [resume] and [speed]; a waiting thread wakes at once.
 */
class ReplayClock(private val nowNs: () -> Long = System::nanoTime) {
    private val lock = ReentrantLock()
    private val changed = lock.newCondition()
    private var startNs = Long.MIN_VALUE
    private var pausedAtNs: Long? = null
    private var rate = 1.0

    /** Whether the replay is paused. */
    val paused: Boolean get() = lock.withLock { pausedAtNs != null }

    /** Replay speed (1 = as recorded; 2 = twice as fast); setting it keeps the position. */
    var speed: Double
        get() = lock.withLock { rate }
        set(v) {
            require(v.isFinite() && v > 0) { "speed: $v is not a positive number" }
            lock.withLock {
                if (startNs != Long.MIN_VALUE) {
                    val now = pausedAtNs ?: nowNs()
                    val position = (now - startNs) * rate // stream ns played so far
                    startNs = now - (position / v).toLong()
                }
                rate = v
                changed.signalAll()
            }
        }

    /** Pauses (the next [awaitDue] waits until [resume]). */
    fun pause() = lock.withLock {
        if (pausedAtNs == null) pausedAtNs = nowNs()
        changed.signalAll()
    }

    /** Resumes; the paused time does not count. */
    fun resume() = lock.withLock {
        val p = pausedAtNs ?: return@withLock
        if (startNs != Long.MIN_VALUE) startNs += nowNs() - p
        pausedAtNs = null
        changed.signalAll()
    }

    /**
     * How long until the frame [offsetNs] after the first is due (<= 0: due now), or
     * [Long.MAX_VALUE] while paused. The first call starts the clock.
     */
    fun waitNs(offsetNs: Long): Long = lock.withLock {
        if (pausedAtNs != null) return Long.MAX_VALUE
        val now = nowNs()
        if (startNs == Long.MIN_VALUE) startNs = now
        (offsetNs / rate).toLong() - (now - startNs)
    }

    /** Waits until the frame [offsetNs] after the first is due (waiting out pauses); throws InterruptedException when interrupted. */
    fun awaitDue(offsetNs: Long) = lock.withLock {
        while (true) {
            val w = waitNs(offsetNs)
            if (w <= 0) return@withLock
            if (w == Long.MAX_VALUE) changed.await() else changed.awaitNanos(w)
        }
    }
}

/** A source that can pause and resume in place (a replay): the controller pauses it with the activity. */
interface PausableSource : SourceHandle {
    fun pause()
    fun resume()
}
