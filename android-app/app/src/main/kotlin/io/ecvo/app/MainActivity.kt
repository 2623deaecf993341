package io.ecvo.app

import android.Manifest
import android.content.Intent
import android.content.pm.PackageManager
import android.hardware.camera2.CameraManager
import android.net.Uri
import android.os.Bundle
import android.os.Handler
import android.os.HandlerThread
import android.os.Looper
import android.os.SystemClock
import android.util.Log
import android.view.View
import android.widget.Button
import android.widget.RadioGroup
import android.widget.TextView
import android.widget.Toast
import android.widget.ToggleButton
import androidx.activity.result.contract.ActivityResultContracts
import androidx.appcompat.app.AlertDialog
import androidx.appcompat.app.AppCompatActivity
import androidx.core.content.ContextCompat
import io.ecvo.Admission
import io.ecvo.DepthFormat
import io.ecvo.Tracker
import io.ecvo.TrackerConfig
import io.ecvo.shared.CameraIntrinsics
import io.ecvo.shared.FrameSource
import io.ecvo.shared.ProjectionPlane
import io.ecvo.shared.StatusKind
import io.ecvo.shared.StreamFiles
import io.ecvo.shared.StreamReader
import io.ecvo.shared.StreamRecorder
import io.ecvo.shared.TrackingPresenter
import java.io.File
import java.text.SimpleDateFormat
import java.util.Date
import java.util.Locale

/**
 * The one screen: replays the bundled sample or a recording picked with the Storage Access
 * Framework, or tracks live from a depth camera; draws the trajectory and the status; can
 * record what it tracks in the recorded-stream format.
 */
class MainActivity : AppCompatActivity() {
    private val presenter = TrackingPresenter()
    private val ui = Handler(Looper.getMainLooper())
    private lateinit var frameThread: HandlerThread
    private lateinit var frames: Handler

    private var session: TrackingSession? = null
    private var replay: Thread? = null
    private var live: DepthCameraSource? = null
    private var depthSetup: DepthCameraSource.Setup? = null
    private val pose = FloatArray(16)

    private lateinit var stateText: TextView
    private lateinit var numbersText: TextView
    private lateinit var messageText: TextView
    private lateinit var trajectoryView: TrajectoryView
    private lateinit var liveButton: Button
    private lateinit var recordButton: ToggleButton

    private val requestCamera = registerForActivityResult(ActivityResultContracts.RequestPermission()) { granted ->
        presenter.onCameraPermission(granted)
        if (granted) startLive()
        render()
    }

    private val pickRecording = registerForActivityResult(ActivityResultContracts.OpenDocumentTree()) { uri: Uri? ->
        if (uri != null) {
            runCatching { contentResolver.takePersistableUriPermission(uri, Intent.FLAG_GRANT_READ_URI_PERMISSION) }
            startReplay(DocumentTreeStreamFiles(contentResolver, uri))
        }
    }

    private val poll = object : Runnable {
        override fun run() {
            refresh()
            ui.postDelayed(this, POLL_MS)
        }
    }

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        setContentView(R.layout.activity_main)
        stateText = findViewById(R.id.status_state)
        numbersText = findViewById(R.id.status_numbers)
        messageText = findViewById(R.id.status_message)
        trajectoryView = findViewById(R.id.trajectory)
        liveButton = findViewById(R.id.live)
        recordButton = findViewById(R.id.record)

        frameThread = HandlerThread("ecvo-frames").also { it.start() }
        frames = Handler(frameThread.looper)

        findViewById<Button>(R.id.replay_sample).setOnClickListener { startReplay(AssetStreamFiles(assets)) }
        findViewById<Button>(R.id.replay_pick).setOnClickListener { pickRecording.launch(null) }
        liveButton.setOnClickListener { onLiveClicked() }
        findViewById<Button>(R.id.stop).setOnClickListener { stopSource(); render() }
        findViewById<Button>(R.id.reset).setOnClickListener { reset() }
        recordButton.setOnCheckedChangeListener { _, on -> setRecording(on) }
        findViewById<RadioGroup>(R.id.plane).setOnCheckedChangeListener { _, id ->
            trajectoryView.plane = when (id) {
                R.id.plane_xy -> ProjectionPlane.XY
                R.id.plane_yz -> ProjectionPlane.YZ
                else -> ProjectionPlane.XZ
            }
        }

        depthSetup = try {
            DepthCameraSource.find(getSystemService(CAMERA_SERVICE) as CameraManager)
        } catch (e: Exception) {
            Log.w(TAG, "looking for a depth camera failed", e)
            null
        }
        presenter.onDepthCameraChecked(depthSetup != null)
        // Not granted yet is not a denial: the user is asked when they press Live.
        if (depthSetup != null && hasCameraPermission()) presenter.onCameraPermission(true)
        render()
    }

    override fun onResume() {
        super.onResume()
        ui.post(poll)
    }

    override fun onPause() {
        ui.removeCallbacks(poll)
        // The camera is released when the app leaves the screen; a replay keeps running.
        if (live != null) stopSource()
        super.onPause()
    }

    override fun onDestroy() {
        stopSource()
        session?.close()
        session = null
        frameThread.quitSafely()
        super.onDestroy()
    }

    private fun hasCameraPermission() =
        ContextCompat.checkSelfPermission(this, Manifest.permission.CAMERA) == PackageManager.PERMISSION_GRANTED

    private fun onLiveClicked() {
        if (depthSetup == null) { render(); return }
        when {
            hasCameraPermission() -> startLive()
            shouldShowRequestPermissionRationale(Manifest.permission.CAMERA) ->
                AlertDialog.Builder(this)
                    .setTitle(R.string.permission_title)
                    .setMessage(R.string.permission_rationale)
                    .setPositiveButton(R.string.permission_continue) { _, _ -> requestCamera.launch(Manifest.permission.CAMERA) }
                    .setNegativeButton(R.string.permission_not_now) { _, _ -> presenter.onCameraPermission(false); render() }
                    .show()
            else -> requestCamera.launch(Manifest.permission.CAMERA)
        }
    }

    /** A fresh tracker for [camera] (the frames' intrinsics; depth in its depth-scale units). */
    private fun newSession(camera: CameraIntrinsics, admission: Admission): TrackingSession {
        session?.close()
        val mm = camera.depthScale == 1000.0
        val config = TrackerConfig(
            width = camera.width, height = camera.height,
            fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy,
            depthFormat = if (mm) DepthFormat.MILLIMETRES else DepthFormat.CUSTOM_SCALE,
            depthScale = camera.depthScale,
            admission = admission,
        )
        return TrackingSession(Tracker(config)).also { session = it; trajectoryView.clear() }
    }

    private fun startReplay(files: StreamFiles) {
        stopSource()
        val s: TrackingSession
        val reader: StreamReader
        try {
            reader = StreamReader(files)
            // Replaying never drops frames: pushFrame waits for the tracker.
            s = newSession(reader.camera, Admission.OFFLINE)
        } catch (e: Exception) {
            fail(e)
            return
        }
        presenter.onStarted(FrameSource.REPLAY, SystemClock.elapsedRealtimeNanos())
        val thread = Thread({
            val me = Thread.currentThread()
            try {
                // Paced like the recording, so that it is drawn as it was taken.
                val t0 = SystemClock.elapsedRealtimeNanos()
                val first = reader.frames.first().timestampNs
                for (frame in reader) {
                    if (me.isInterrupted) return@Thread
                    val wait = (frame.timestampNs - first) - (SystemClock.elapsedRealtimeNanos() - t0)
                    if (wait > 0) Thread.sleep(wait / 1_000_000, (wait % 1_000_000).toInt())
                    s.push(frame.timestampNs, frame.depth, frame.intensity)
                }
                s.tracker.flush()
                ui.post { if (replay === me) { replay = null; presenter.onStopped(); refresh() } }
            } catch (e: InterruptedException) {
                // Stopped.
            } catch (e: IllegalStateException) {
                // The tracker was closed (reset) while replaying.
            } catch (e: Exception) {
                ui.post { fail(e) }
            }
        }, "ecvo-replay")
        replay = thread
        thread.start()
        render()
    }

    private fun startLive() {
        val setup = depthSetup ?: return
        stopSource()
        val s = try {
            newSession(setup.frame, Admission.LIVE)
        } catch (e: Exception) {
            fail(e)
            return
        }
        presenter.onStarted(FrameSource.LIVE, SystemClock.elapsedRealtimeNanos())
        val source = DepthCameraSource(
            getSystemService(CAMERA_SERVICE) as CameraManager, setup, frames, minConfidence = 1,
            onFrame = { ts, depth, gray ->
                try {
                    s.push(ts, depth, gray)
                } catch (e: IllegalStateException) {
                    // Closed by reset while a frame was in flight.
                } catch (e: RuntimeException) {
                    ui.post { stopSource(); fail(e) }
                }
            },
            onFailure = { msg -> ui.post { stopSource(); presenter.onError(msg); render() } },
        )
        live = source
        source.start()
        render()
    }

    private fun stopSource() {
        replay?.let { it.interrupt(); replay = null }
        live?.let { it.stop(); live = null }
        if (recordButton.isChecked) recordButton.isChecked = false
        presenter.onStopped()
    }

    private fun reset() {
        stopSource()
        session?.close()
        session = null
        trajectoryView.clear()
        presenter.onStopped()
        render()
    }

    private fun setRecording(on: Boolean) {
        val s = session
        if (on) {
            if (s == null || (replay == null && live == null)) { recordButton.isChecked = false; return }
            val name = SimpleDateFormat("yyyyMMdd-HHmmss", Locale.ROOT).format(Date())
            val dir = File(getExternalFilesDir(null), "recordings/$name")
            val c = s.tracker.config
            try {
                s.startRecording(StreamRecorder(dir, CameraIntrinsics(c.width, c.height, c.fx, c.fy, c.cx, c.cy, if (c.depthFormat == DepthFormat.CUSTOM_SCALE) c.depthScale else 1000.0)))
            } catch (e: Exception) {
                recordButton.isChecked = false
                fail(e)
                return
            }
            presenter.onRecording(true)
        } else {
            val r = s?.stopRecording()
            presenter.onRecording(false)
            if (r != null) Toast.makeText(this, getString(R.string.recorded_to, r.framesWritten, r.dir.path), Toast.LENGTH_LONG).show()
        }
        render()
    }

    private fun fail(e: Exception) {
        Log.e(TAG, "ecvo", e)
        presenter.onError(e.message ?: e.toString())
        render()
    }

    /** Polls the tracker and redraws. */
    private fun refresh() {
        val s = session
        if (s != null && !s.tracker.isClosed) {
            try {
                val t = s.tracker
                val ts = t.getPose(pose)
                presenter.onTrackerUpdate(t.state, t.stats(), ts, SystemClock.elapsedRealtimeNanos())
                trajectoryView.show(t.trajectory(), t.references(), if (ts == Tracker.NO_POSE) null else pose)
            } catch (e: IllegalStateException) {
                // Closed between the check and the calls.
            }
        }
        render()
    }

    private fun render() {
        val st = presenter.status
        stateText.text = st.state
        stateText.setTextColor(
            when (st.kind) {
                StatusKind.TRACKING -> 0xFF34A853.toInt()
                StatusKind.LOST, StatusKind.ERROR -> 0xFFEA4335.toInt()
                StatusKind.INITIALISING -> 0xFFFBBC05.toInt()
                StatusKind.IDLE -> 0xFF9E9E9E.toInt()
            },
        )
        numbersText.text = "${st.timing}   ${st.references}\n${st.frames}"
        messageText.text = st.message ?: ""
        messageText.visibility = if (st.message == null) View.GONE else View.VISIBLE
        liveButton.isEnabled = depthSetup != null
        if (recordButton.isChecked != st.recording) recordButton.isChecked = st.recording
    }

    companion object {
        private const val TAG = "ecvo"
        private const val POLL_MS = 50L
    }
}
