package io.ecvo.shared

import io.ecvo.PoseTracker
import io.ecvo.PushStatus
import io.ecvo.Tracker
import java.util.concurrent.atomic.AtomicLong

/**
 * One run of the tracker: owns the [PoseTracker] and the optional recorder. Frames come
 * in on a source's thread ([push]); the UI thread reads the tracker and switches
 * recording on and off.
 *
 * Every frame the tracker took is recorded, whatever became of it there (a
 * [PushStatus.DROPPED] frame was queued too: the one dropped was an older one), so that
 * replaying a recording offline sees every frame the camera gave. Recording runs on its
 * own thread with a bounded queue ([AsyncRecorder]): a frame that finds the queue full
 * is not recorded and counted ([recordingDropped]). A recorder that fails (disk full) is
 * closed, what it wrote stays a readable stream, and [onRecordingFailed] is told (on the
 * recorder's thread); tracking goes on.
 */
class TrackingSession(
    val tracker: PoseTracker,
    private val recorderCapacity: Int = AsyncRecorder.DEFAULT_CAPACITY,
    private val onRecordingFailed: (String) -> Unit = {},
) : AutoCloseable {
    private val recorderLock = Any()
    private var recorder: AsyncRecorder<StreamRecorder>? = null
    private var lastDropped = 0L
    private val refused = AtomicLong()

    /** Whether a recorder is running. */
    val recording: Boolean get() = synchronized(recorderLock) { recorder != null }

    /** Frames the running (or last) recording could not keep up with. */
    val recordingDropped: Long get() = synchronized(recorderLock) { recorder?.framesDropped ?: lastDropped }

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
        synchronized(recorderLock) { recorder?.offer(timestampNs, depthMm, intensity) }
        return status
    }

    private fun onFailed(r: AsyncRecorder<StreamRecorder>, message: String) {
        synchronized(recorderLock) {
            if (recorder !== r) return
            recorder = null
            lastDropped = r.framesDropped
        }
        onRecordingFailed(message)
    }

    /** Starts recording into [recorder] (replacing and finishing any previous one). */
    fun startRecording(recorder: StreamRecorder) {
        stopRecording()
        val r = AsyncRecorder(recorder, recorderCapacity, ::onFailed)
        synchronized(recorderLock) { this.recorder = r }
    }

    /**
     * Stops recording: waits for the queued frames to be written, and returns the
     * finished recorder (closed), or null if none was running.
     */
    fun stopRecording(): StreamRecorder? {
        val r = synchronized(recorderLock) {
            val r = recorder ?: return null
            recorder = null
            lastDropped = r.framesDropped
            r
        }
        return r.finish()
    }

    override fun close() {
        try {
            runCatching { stopRecording() }
        } finally {
            tracker.close()
        }
    }
}
