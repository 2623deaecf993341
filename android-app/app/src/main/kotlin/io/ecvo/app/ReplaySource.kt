package io.ecvo.app

import android.os.SystemClock
import io.ecvo.shared.SourceCallbacks
import io.ecvo.shared.SourceHandle
import io.ecvo.shared.StreamReader

/**
 * Replays a recorded stream on a thread of its own, paced like the recording so that it
 * is drawn as it was taken. The tracker runs offline (never drops), so every frame is
 * tracked. [stop] interrupts the thread; a frame in flight is ignored by the controller.
 */
class ReplaySource(
    private val reader: StreamReader,
    private val callbacks: SourceCallbacks,
    /** Called with each frame handed to the tracker (for the preview). */
    private val onFrame: (ShortArray, ByteArray) -> Unit = { _, _ -> },
) : SourceHandle {
    private val thread = Thread({ run() }, "ecvo-replay")

    fun start(): ReplaySource = also { thread.start() }

    private fun run() {
        try {
            val t0 = SystemClock.elapsedRealtimeNanos()
            val first = reader.frames.firstOrNull()?.timestampNs ?: return callbacks.finished()
            for (frame in reader) {
                if (Thread.currentThread().isInterrupted || !callbacks.isCurrent) return
                val wait = (frame.timestampNs - first) - (SystemClock.elapsedRealtimeNanos() - t0)
                if (wait > 0) Thread.sleep(wait / 1_000_000, (wait % 1_000_000).toInt())
                onFrame(frame.depth, frame.intensity)
                callbacks.frame(frame.timestampNs, frame.depth, frame.intensity)
            }
            callbacks.finished()
        } catch (e: InterruptedException) {
            // Stopped.
        } catch (e: Exception) {
            callbacks.failed("Replay of ${reader.files.description} failed: ${e.message ?: e.javaClass.simpleName}")
        }
    }

    override fun stop() = thread.interrupt()
}
