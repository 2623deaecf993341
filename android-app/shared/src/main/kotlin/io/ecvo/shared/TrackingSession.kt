package io.ecvo.shared

import io.ecvo.PoseTracker
import io.ecvo.PushStatus
import io.ecvo.Tracker
import java.util.concurrent.atomic.AtomicLong

/** A finished recording: the closed [recorder], the frames its queue had no room for, and why it failed (null: it did not). */
class RecordingResult(val recorder: StreamRecorder, val dropped: Long, val error: String?)

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
 * closed, what it wrote stays a readable stream, and [onNotice] is told (on the
 * recorder's thread); tracking goes on.
 */
class TrackingSession(
    val tracker: PoseTracker,
    private val recorderCapacity: Int = AsyncRecorder.DEFAULT_CAPACITY,
    /** A sentence for the user: a recording that failed (on the recorder's thread), timestamps re-based (on the frame's). */
    private val onNotice: (String) -> Unit = {},
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

    /** The timeline the frames of successive camera instances are put on ([CameraTimeline]). */
    val timeline = CameraTimeline()

    /**
     * Pushes the frame to the tracker and records it (if recording), with its timestamp
     * put on [timeline] ([arrivalNs]: the wall-clock time it arrived; a replay passes
     * its own timestamp). Returns null when the tracker is already closed (a reset while
     * a frame was in flight) or refused the frame's timestamp (not after the previous
     * frame's: a camera glitch, a clock jump); such a frame is skipped, counted in
     * [refusedTimestamps] and not recorded, and the session goes on; when refusals
     * persist, the timeline is re-based and [onNotice] says so. Other tracker errors are
     * thrown.
     */
    fun push(timestampNs: Long, depthMm: ShortArray, intensity: ByteArray, arrivalNs: Long = timestampNs): PushStatus? {
        val ts = timeline.map(timestampNs, arrivalNs)
        val status = try {
            tracker.pushFrame(ts, depthMm, intensity)
        } catch (e: IllegalStateException) {
            if (tracker.isClosed) return null else throw e
        } catch (e: IllegalArgumentException) {
            if (!Tracker.isRefusedTimestamp(e)) throw e
            val n = refused.incrementAndGet()
            if (timeline.refused()) onNotice(rebaseNotice(n))
            return null
        }
        timeline.accepted(ts, arrivalNs)
        // The tracker copied the frame; recording it afterwards keeps refused frames out.
        synchronized(recorderLock) { recorder?.offer(ts, depthMm, intensity) }
        return status
    }

    private fun onFailed(r: AsyncRecorder<StreamRecorder>, message: String) {
        synchronized(recorderLock) {
            if (recorder !== r) return
            recorder = null
            lastDropped = r.framesDropped
        }
        onNotice(message)
    }

    /** Starts recording into [recorder] (replacing and finishing any previous one). */
    fun startRecording(recorder: StreamRecorder) {
        stopRecording()
        val r = AsyncRecorder(recorder, recorderCapacity, ::onFailed)
        synchronized(recorderLock) { this.recorder = r }
    }

    /**
     * Stops recording and returns at once: the queued frames are written and the
     * recorder closed on a thread of its own ([AsyncRecorder.finishInBackground]), which
     * then calls [onFinished] with the result. False if no recorder was running.
     */
    fun stopRecording(onFinished: (RecordingResult) -> Unit = {}): Boolean {
        val r = detachRecorder() ?: return false
        r.finishInBackground { rec, e ->
            onFinished(RecordingResult(rec, r.framesDropped, r.failed ?: e?.let { "Finishing the recording failed: ${it.message ?: it.javaClass.simpleName}" }))
        }
        return true
    }

    /** Stops recording and waits until it is written and closed (tests, tools); the result, or null if none was running. */
    fun stopRecordingAndWait(): RecordingResult? {
        val r = detachRecorder() ?: return null
        val e = try {
            r.finish()
            null
        } catch (e: Exception) {
            e
        }
        return RecordingResult(r.recorder, r.framesDropped, r.failed ?: e?.let { "Finishing the recording failed: ${it.message ?: it.javaClass.simpleName}" })
    }

    private fun detachRecorder(): AsyncRecorder<StreamRecorder>? = synchronized(recorderLock) {
        val r = recorder ?: return null
        recorder = null
        lastDropped = r.framesDropped
        r
    }

    companion object {
        /** The sentence shown when [CameraTimeline] re-based the timestamps after [refused] refusals in all. */
        fun rebaseNotice(refused: Long): String =
            "The camera's timestamps went backwards ($refused frames refused); they were re-based on the phone's clock and tracking goes on."
    }

    override fun close() {
        try {
            stopRecording()
        } finally {
            tracker.close()
        }
    }
}
