package io.ecvo.shared

import io.ecvo.PoseTracker
import io.ecvo.PushStatus
import io.ecvo.Tracker

/**
 * One run of the tracker: owns the [PoseTracker] and the optional [StreamRecorder].
 * Frames come in on a source's thread ([push]); the UI thread reads the tracker and
 * switches recording on and off.
 *
 * Every frame the source delivered is recorded, whatever became of it in the tracker
 * (a [PushStatus.DROPPED] frame was queued too: the one dropped was an older one), so
 * that replaying a recording offline sees every frame the camera gave. A recorder that
 * fails (disk full) is closed, what it wrote stays a readable stream, and
 * [onRecordingFailed] is told; tracking goes on.
 */
class TrackingSession(
    val tracker: PoseTracker,
    private val onRecordingFailed: (String) -> Unit = {},
) : AutoCloseable {
    private val recorderLock = Any()
    private var recorder: StreamRecorder? = null

    /** Whether a recorder is running. */
    val recording: Boolean get() = synchronized(recorderLock) { recorder != null }

    private val refused = java.util.concurrent.atomic.AtomicLong()

    /** Frames the tracker refused for their timestamp ([Tracker.isRefusedTimestamp]), skipped. */
    val refusedTimestamps: Long get() = refused.get()

    /**
     * Pushes the frame to the tracker and records it (if recording). Returns null when
     * the tracker is already closed (a reset while a frame was in flight) or refused the
     * frame's timestamp (not after the previous frame's: a camera glitch, a clock jump);
     * such a frame is skipped, counted in [refusedTimestamps] and not recorded, and the
     * session goes on. Other tracker errors are thrown.
     */
    fun push(timestampNs: Long, depthMm: ShortArray, intensity: ByteArray): PushStatus? {
        val status = try {
            tracker.pushFrame(timestampNs, depthMm, intensity)
        } catch (e: IllegalStateException) {
            if (tracker.isClosed) return null else throw e
        } catch (e: IllegalArgumentException) {
            if (!Tracker.isRefusedTimestamp(e)) throw e
            refused.incrementAndGet()
            return null
        }
        // The tracker copied the frame; recording it afterwards keeps refused frames out.
        record(timestampNs, depthMm, intensity)
        return status
    }

    private fun record(timestampNs: Long, depthMm: ShortArray, intensity: ByteArray) {
        val failed: String? = synchronized(recorderLock) {
            val r = recorder ?: return
            try {
                r.writeFrame(timestampNs, depthMm, intensity)
                null
            } catch (e: Exception) {
                // IOException (disk full, storage removed) or a frame the recorder refuses.
                recorder = null
                runCatching { r.close() }
                "Recording stopped: ${e.message ?: e.javaClass.simpleName}. The ${r.framesWritten} frames before it are kept in ${r.dir.path}."
            }
        }
        if (failed != null) onRecordingFailed(failed)
    }

    /** Starts recording into [recorder] (replacing and closing any previous one). */
    fun startRecording(recorder: StreamRecorder) = synchronized(recorderLock) {
        this.recorder?.let { runCatching { it.close() } }
        this.recorder = recorder
    }

    /** Stops recording; returns the finished recorder (closed), or null if none was running. */
    fun stopRecording(): StreamRecorder? = synchronized(recorderLock) {
        val r = recorder
        recorder = null
        r?.close()
        r
    }

    override fun close() {
        try {
            runCatching { stopRecording() }
        } finally {
            tracker.close()
        }
    }
}
