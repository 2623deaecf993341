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
     * The gyroscope samples waiting for the next frame: the app's sensor listener adds
     * them (`SensorEvent.timestamp`, rad/s in the device's sensor axes), and each frame
     * takes them all in one batch, put on the frames' timeline, before it is pushed.
     */
    val gyro = GyroBuffer()

    /**
     * The current camera instance's clock against the sensors' ([CameraClock]); null (no
     * gyroscope, a replay) leaves the samples waiting, bounded by [gyro]'s capacity.
     */
    @Volatile var cameraClock: CameraClock? = null

    /**
     * The rotation taking the gyroscope's axes into the depth camera's (row-major 3x3,
     * [ImuCalibration.cameraFromDevice]): set, the samples go to the tracker too
     * ([PoseTracker.pushImu], which takes the camera's axes); null, they are only recorded.
     */
    @Volatile var imuRotation: DoubleArray? = null

    private var imuRecorder: ImuRecorder? = null
    private val imuPlaced = AtomicLong()
    private val imuUnplaced = AtomicLong()
    private val imuSink = ImuSink()

    /** Gyroscope samples put on the frames' timeline (and recorded, while recording). */
    val imuSamples: Long get() = imuPlaced.get()

    /** Gyroscope samples dropped: taken before their camera instance's clock was known, or the buffer overflowed. */
    val imuSamplesDropped: Long get() = imuUnplaced.get() + gyro.dropped

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
    fun push(timestampNs: Long, depthMm: ShortArray, intensity: ByteArray, arrivalNs: Long = timestampNs, arrivalMonotonicNs: Long = arrivalNs): PushStatus? {
        val ts = timeline.map(timestampNs, arrivalNs)
        feedImu(timestampNs, arrivalNs, arrivalMonotonicNs)
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

    /**
     * Before the frame stamped [rawNs] (camera clock), which arrived at [arrivalNs]
     * (`elapsedRealtimeNanos`, the sensors' clock, in the app) and [arrivalMonotonicNs]
     * (`System.nanoTime`): measures the camera's clock on it, then hands the waiting
     * gyroscope samples on in one batch.
     */
    private fun feedImu(rawNs: Long, arrivalNs: Long, arrivalMonotonicNs: Long) {
        val clock = cameraClock ?: return
        clock.onFrame(rawNs, arrivalNs, arrivalMonotonicNs)
        // Until the clock is measured the samples cannot be placed: the sink counts them as dropped.
        gyro.drain(imuSink)
    }

    /** Puts a drained batch on the timeline (in place) and records it (a named class: the APK's dexer cannot desugar lambdas). */
    private inner class ImuSink : GyroSink {
        override fun accept(timestampsNs: LongArray, gyro: FloatArray, n: Int) {
            val clock = cameraClock
            var m = 0
            for (i in 0 until n) {
                val c = clock?.toCamera(timestampsNs[i]) ?: continue
                val t = timeline.mapInstant(c) ?: continue
                timestampsNs[m] = t
                gyro[3 * m] = gyro[3 * i]; gyro[3 * m + 1] = gyro[3 * i + 1]; gyro[3 * m + 2] = gyro[3 * i + 2]
                m++
            }
            imuUnplaced.addAndGet((n - m).toLong())
            if (m == 0) return
            imuPlaced.addAndGet(m.toLong())
            // Recorded in the IMU's own axes (camera.json holds the rotation) ...
            synchronized(recorderLock) {
                val r = imuRecorder
                if (r != null) {
                    try {
                        r.write(timestampsNs, gyro, m)
                    } catch (e: java.io.IOException) {
                        imuRecorder = null
                        runCatching { r.close() }
                        onNotice("Recording the gyroscope stopped: ${e.message ?: e.javaClass.simpleName}. The frames are still recorded.")
                    }
                }
            }
            // ... and given to the tracker in the camera's.
            val rot = imuRotation ?: return
            for (i in 0 until m) {
                val x = gyro[3 * i].toDouble(); val y = gyro[3 * i + 1].toDouble(); val z = gyro[3 * i + 2].toDouble()
                gyro[3 * i] = (rot[0] * x + rot[1] * y + rot[2] * z).toFloat()
                gyro[3 * i + 1] = (rot[3] * x + rot[4] * y + rot[5] * z).toFloat()
                gyro[3 * i + 2] = (rot[6] * x + rot[7] * y + rot[8] * z).toFloat()
            }
            try {
                tracker.pushImu(timestampsNs, gyro, m)
            } catch (e: IllegalStateException) {
                if (!tracker.isClosed) throw e
            } catch (e: IllegalArgumentException) {
                // A sensor that gave a non-finite rate: that batch is not taken; tracking goes on.
                imuRefusedBatches.incrementAndGet()
            }
        }
    }

    private val imuRefusedBatches = AtomicLong()

    /** Batches of gyroscope samples the tracker refused (a non-finite rate), not taken. */
    val imuBatchesRefused: Long get() = imuRefusedBatches.get()

    /**
     * The IMU calibration for a recording made now: the camera-from-device rotation
     * [rotationCameraDevice] (see [ImuCalibration.cameraFromDevice]), and how the clocks
     * were matched; null without a gyroscope (no [cameraClock]).
     */
    fun imuCalibration(rotationCameraDevice: DoubleArray): ImuCalibration? {
        val clock = cameraClock ?: return null
        return ImuCalibration(rotationCameraDevice, 0.0, clock.method?.label ?: "unmeasured")
    }

    private fun onFailed(r: AsyncRecorder<StreamRecorder>, message: String) {
        synchronized(recorderLock) {
            if (recorder !== r) return
            recorder = null
            imuRecorder?.let { runCatching { it.close() } }
            imuRecorder = null
            lastDropped = r.framesDropped
        }
        onNotice(message)
    }

    /**
     * Starts recording into [recorder] (replacing and finishing any previous one); with a
     * calibrated IMU ([StreamRecorder.imu]) the gyroscope samples go to `imu.txt` beside it.
     */
    fun startRecording(recorder: StreamRecorder) {
        stopRecording()
        val r = AsyncRecorder(recorder, recorderCapacity, ::onFailed)
        val imu = if (recorder.imu != null) ImuRecorder(recorder.dir) else null
        synchronized(recorderLock) {
            this.recorder = r
            imuRecorder = imu
        }
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
        imuRecorder?.let { runCatching { it.close() } }
        imuRecorder = null
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
