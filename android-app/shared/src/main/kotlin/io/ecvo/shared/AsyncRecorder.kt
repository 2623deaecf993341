package io.ecvo.shared

import java.io.Closeable
import java.io.File
import java.util.concurrent.ArrayBlockingQueue
import java.util.concurrent.TimeUnit
import java.util.concurrent.atomic.AtomicLong

/** What [AsyncRecorder] writes frames to: a [StreamRecorder], or a fake in tests. */
interface FrameRecorder : Closeable {
    /** The stream folder. */
    val dir: File

    /** Frames written so far. */
    val framesWritten: Int

    /** Writes one frame (same contract as [StreamRecorder.writeFrame]). */
    fun writeFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray)
}

/**
 * Records on a thread of its own, so that the two PNG encodes of a frame (about 8 ms on
 * x86, more on a phone) never hold up the camera thread: [offer] copies the frame into a
 * bounded queue and returns at once; when the queue is full (the writer is behind, a slow
 * card) the frame is not recorded and counted in [framesDropped], which the screen shows.
 *
 * A write that fails (disk full) ends recording: the writer closes [recorder] (what it
 * wrote stays a readable stream), drops what is queued, and calls [onFailed] with a
 * sentence for the user, on the writer thread. [finish] writes what is queued, stops the
 * thread and closes [recorder]; [finishInBackground] does so without making the caller
 * wait.
 */
class AsyncRecorder<R : FrameRecorder>(
    val recorder: R,
    capacity: Int = DEFAULT_CAPACITY,
    private val onFailed: (AsyncRecorder<R>, String) -> Unit = { _, _ -> },
) {
    private class Frame(val timestampNs: Long, val depth: ShortArray, val intensity: ByteArray)

    private val queue = ArrayBlockingQueue<Frame>(capacity)
    private val dropped = AtomicLong()
    @Volatile private var stopping = false
    @Volatile private var failure: String? = null
    private val thread = Thread(Writer(), "ecvo-recorder")

    init {
        require(capacity > 0) { "capacity: $capacity is not positive" }
        thread.isDaemon = true
        thread.start()
    }

    /** Frames not recorded because the queue was full. */
    val framesDropped: Long get() = dropped.get()

    /** Why recording stopped by itself, or null. */
    val failed: String? get() = failure

    /**
     * Queues a copy of the frame (the caller may reuse its arrays at once); false if it
     * was dropped (queue full) or recording has ended.
     */
    fun offer(timestampNs: Long, depth: ShortArray, intensity: ByteArray): Boolean {
        if (stopping || failure != null) return false
        if (queue.remainingCapacity() == 0) {
            dropped.incrementAndGet()
            return false
        }
        if (!queue.offer(Frame(timestampNs, depth.copyOf(), intensity.copyOf()))) {
            dropped.incrementAndGet()
            return false
        }
        return true
    }

    /** Writes what is queued, stops the writer and closes [recorder]; returns it. Call once. */
    fun finish(): R {
        stopping = true
        var interrupted = false
        while (thread.isAlive) {
            try {
                thread.join()
            } catch (e: InterruptedException) {
                interrupted = true
            }
        }
        if (interrupted) Thread.currentThread().interrupt()
        recorder.close()
        return recorder
    }

    /**
     * [finish] on a thread of its own, so that the caller (the UI thread) never waits for
     * the queue to drain (up to a second at VGA); returns that thread at once. [onDone]
     * gets, on it, the closed recorder and what closing it threw (null if nothing).
     * Frames offered from now on are refused. Call once, instead of [finish].
     */
    fun finishInBackground(onDone: (R, Exception?) -> Unit): Thread {
        stopping = true
        val t = Thread(Finisher(onDone), "ecvo-recorder-finish")
        t.isDaemon = true
        t.start()
        return t
    }

    private inner class Finisher(private val onDone: (R, Exception?) -> Unit) : Runnable {
        override fun run() {
            val error = try {
                finish()
                null
            } catch (e: Exception) {
                e
            }
            onDone(recorder, error)
        }
    }

    /** The writer loop (a named class, not a lambda: the APK's dexer cannot desugar lambdas). */
    private inner class Writer : Runnable {
        override fun run() {
            while (true) {
                val f = try {
                    queue.poll(POLL_MS, TimeUnit.MILLISECONDS)
                } catch (e: InterruptedException) {
                    null
                }
                if (f == null) {
                    if (stopping) return
                    continue
                }
                try {
                    recorder.writeFrame(f.timestampNs, f.depth, f.intensity)
                } catch (e: Exception) {
                    // IOException (disk full, storage removed) or a frame the recorder refuses.
                    val message = "Recording stopped: ${e.message ?: e.javaClass.simpleName}. The ${recorder.framesWritten} frames before it are kept in ${recorder.dir.path}."
                    failure = message
                    runCatching { recorder.close() }
                    queue.clear()
                    onFailed(this@AsyncRecorder, message)
                    return
                }
            }
        }
    }

    companion object {
        /** Frames queued at most: about half a second at 30 Hz. */
        const val DEFAULT_CAPACITY: Int = 16
        private const val POLL_MS = 20L
    }
}
