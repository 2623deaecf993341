package io.ecvo.app

import io.ecvo.PushStatus
import io.ecvo.Tracker
import io.ecvo.shared.StreamRecorder

/**
 * One run of the tracker: owns the [Tracker] and the optional [StreamRecorder]. Frames
 * come in on a source's thread ([push]); the UI thread reads the tracker and switches
 * recording on and off.
 */
class TrackingSession(val tracker: Tracker) : AutoCloseable {
    private val recorderLock = Any()
    private var recorder: StreamRecorder? = null

    /** Pushes a frame to the tracker and, if it was accepted, records it. */
    fun push(timestampNs: Long, depthMm: ShortArray, intensity: ByteArray): PushStatus {
        val status = tracker.pushFrame(timestampNs, depthMm, intensity)
        if (status == PushStatus.ACCEPTED) {
            synchronized(recorderLock) { recorder?.writeFrame(timestampNs, depthMm, intensity) }
        }
        return status
    }

    /** Starts recording into [recorder] (replacing and closing any previous one). */
    fun startRecording(recorder: StreamRecorder) = synchronized(recorderLock) {
        this.recorder?.close()
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
        stopRecording()
        tracker.close()
    }
}
