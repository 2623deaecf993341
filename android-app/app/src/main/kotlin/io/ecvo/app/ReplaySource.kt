package io.ecvo.app

import android.os.SystemClock
import io.ecvo.shared.PausableSource
import io.ecvo.shared.ReplayClock
import io.ecvo.shared.SourceCallbacks
import io.ecvo.shared.StreamReader

/**
 * Replays a recorded stream on a thread of its own, paced like the recording (at
 * [ReplayClock.speed]) so that it is drawn as it was taken; [pause] holds it in place
 * (the activity pauses it when it leaves the screen), [resume] goes on. The tracker runs
 * offline (never drops), so every frame is tracked. [stop] interrupts the thread; a
 * frame in flight is ignored by the controller.
 */
class ReplaySource(
    private val reader: StreamReader,
    private val callbacks: SourceCallbacks,
    speed: Double = 1.0,
    /** Called with each frame handed to the tracker (for the preview). */
    private val onFrame: (ShortArray, ByteArray) -> Unit = { _, _ -> },
) : PausableSource {
    private val clock = ReplayClock(SystemClock::elapsedRealtimeNanos).also { it.speed = speed }
    private val thread = Thread({ run() }, "ecvo-replay")

    fun start(): ReplaySource = also { thread.start() }

    private fun run() {
        try {
            val first = reader.frames.firstOrNull()?.timestampNs ?: return callbacks.finished()
            for (frame in reader) {
                if (Thread.currentThread().isInterrupted || !callbacks.isCurrent) return
                clock.awaitDue(frame.timestampNs - first)
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

    override fun pause() = clock.pause()

    override fun resume() = clock.resume()

    /** Changes the replay speed (1 = as recorded), keeping the position. */
    fun setSpeed(speed: Double) { clock.speed = speed }

    override fun stop() = thread.interrupt()
}
