package io.ecvo.app

import android.Manifest
import android.app.Activity
import android.app.AlertDialog
import android.content.ActivityNotFoundException
import android.content.Intent
import android.content.pm.PackageManager
import android.graphics.Bitmap
import android.hardware.camera2.CameraManager
import android.os.Build
import android.os.Bundle
import android.os.Handler
import android.os.Looper
import android.net.Uri
import android.provider.Settings
import android.util.Log
import android.view.View
import android.view.WindowInsets
import android.view.WindowManager
import android.widget.Button
import android.widget.ImageView
import android.widget.RadioGroup
import android.widget.TextView
import android.widget.Toast
import android.widget.ToggleButton
import android.window.OnBackInvokedCallback
import android.window.OnBackInvokedDispatcher
import io.ecvo.ReferenceFrame
import io.ecvo.Tracker
import io.ecvo.shared.AppSettings
import io.ecvo.shared.CameraIntrinsics
import io.ecvo.shared.ScreenOnSwitch
import io.ecvo.shared.DirectoryFiles
import io.ecvo.shared.ExportPlan
import io.ecvo.shared.ExportSelection
import io.ecvo.shared.FrameSource
import io.ecvo.shared.PreviewKind
import io.ecvo.shared.ProjectionPlane
import io.ecvo.shared.SessionController
import io.ecvo.shared.StatusKind
import io.ecvo.shared.StreamFiles
import io.ecvo.shared.StreamMetadata
import io.ecvo.shared.StreamReader
import io.ecvo.shared.StreamRecorder
import java.io.File
import java.text.SimpleDateFormat
import java.util.Date
import java.util.Locale

/**
 * The one screen: replays the bundled sample or one of the app's recordings, or tracks
 * live from a depth camera; draws the trajectory, the status and an optional preview;
 * records, shares and sets the settings. The session itself lives in [SessionHolder], so
 * rotating the phone does not lose it; this class only draws and forwards taps.
 *
 * A platform Activity (no AndroidX): its resources and Kotlin are compiled in CI against
 * the platform alone (scripts/android-stubs).
 */
class MainActivity : Activity() {
    private val controller: SessionController get() = SessionHolder.controller
    private val ui = Handler(Looper.getMainLooper())
    private val pose = FloatArray(16)
    private var polls = 0L
    private var references: List<ReferenceFrame> = emptyList()
    private val settings: AppSettings get() = SessionHolder.settings(this)
    private var hasDepthCamera = false
    private val screenOn = ScreenOnSwitch()
    private var previewBitmap: Bitmap? = null
    private val settingsDialog by lazy { SettingsDialog(this) { kind, d -> keep(kind, d) } }
    private val recordingsDialog by lazy {
        RecordingsDialog(
            this, recordingsDir, { kind, d -> keep(kind, d) },
            replay = { r -> startReplay(DirectoryFiles(r.dir), r.dir) },
            export = { r, target -> exportPlan(ExportSelection.forRecording(r.dir, controller.session != null, SessionHolder.streams.stream), r.name, target) },
        )
    }
    private val exporter by lazy { Exporter(this) { msg -> controller.presenter.onNotice(msg); render() } }

    private lateinit var stateText: TextView
    private lateinit var numbersText: TextView
    private lateinit var messageText: TextView
    private lateinit var trajectoryView: TrajectoryView
    private lateinit var preview: ImageView
    private lateinit var liveButton: Button
    private lateinit var recordButton: ToggleButton
    private lateinit var pauseButton: Button

    private val poll = object : Runnable {
        override fun run() {
            refresh()
            ui.postDelayed(this, POLL_MS)
        }
    }

    /** From the application context: the camera source outlives this activity (rotation). */
    private val cameraManager: CameraManager get() = applicationContext.getSystemService(CAMERA_SERVICE) as CameraManager
    private val recordingsDir: File get() = File(getExternalFilesDir(null) ?: filesDir, "recordings")

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        setContentView(R.layout.activity_main)
        // targetSdk 35: Android 15 draws the window edge to edge, under the status and
        // navigation bars; the root pads itself by their insets (and the cutout's).
        val root = findViewById<View>(R.id.root)
        val pad = root.paddingLeft
        root.setOnApplyWindowInsetsListener { v, insets -> applyInsets(v, insets, pad) }
        root.requestApplyInsets()
        // Back ends the session. On Android 12+ the default Back of a root activity only
        // moves the task behind (the session would go on); on 13+ with predictive back
        // the system calls this callback instead of onBackPressed.
        if (Build.VERSION.SDK_INT >= 33) {
            onBackInvokedDispatcher.registerOnBackInvokedCallback(
                OnBackInvokedDispatcher.PRIORITY_DEFAULT,
                object : OnBackInvokedCallback {
                    override fun onBackInvoked() = finish()
                },
            )
        }
        stateText = findViewById(R.id.status_state)
        numbersText = findViewById(R.id.status_numbers)
        messageText = findViewById(R.id.status_message)
        trajectoryView = findViewById(R.id.trajectory)
        preview = findViewById(R.id.preview)
        liveButton = findViewById(R.id.live)
        recordButton = findViewById(R.id.record)
        pauseButton = findViewById(R.id.pause)
        SessionHolder.preview = settings.preview

        findViewById<Button>(R.id.replay_sample).setOnClickListener { startReplay(AssetStreamFiles(assets)) }
        findViewById<Button>(R.id.recordings).setOnClickListener { recordingsDialog.show() }
        liveButton.setOnClickListener { onLiveClicked() }
        findViewById<Button>(R.id.stop).setOnClickListener { SessionHolder.resumeLive = false; controller.stopSource(); render() }
        pauseButton.setOnClickListener {
            SessionHolder.resumeReplay = false
            if (controller.paused) controller.resumePaused() else controller.pause()
            render()
        }
        findViewById<Button>(R.id.reset).setOnClickListener { SessionHolder.resumeLive = false; controller.reset(); trajectoryView.clear(); render() }
        findViewById<Button>(R.id.export).setOnClickListener { chooseExport() }
        findViewById<Button>(R.id.settings).setOnClickListener { settingsDialog.show() }
        recordButton.setOnClickListener { setRecording(recordButton.isChecked) }
        findViewById<RadioGroup>(R.id.plane).setOnCheckedChangeListener { _, id ->
            trajectoryView.plane = when (id) {
                R.id.plane_xy -> ProjectionPlane.XY
                R.id.plane_yz -> ProjectionPlane.YZ
                else -> ProjectionPlane.XZ
            }
        }

        hasDepthCamera = try {
            DepthCameraSource.hasDepthCamera(cameraManager)
        } catch (e: Exception) {
            Log.w(TAG, "looking for a depth camera failed", e)
            false
        }
        controller.presenter.onDepthCameraChecked(hasDepthCamera)
        // Not granted yet is not a denial: the user is asked when they press Live.
        if (hasDepthCamera && hasCameraPermission()) controller.presenter.onCameraPermission(true)
        render()
        // A rotation closed the dialog that was open: show it again.
        savedInstanceState?.getString(STATE_DIALOG)?.let { reopenDialog(it) }
    }

    override fun onResume() {
        super.onResume()
        // Granted in the system settings while away: the "denied" message goes.
        if (hasDepthCamera && hasCameraPermission()) controller.presenter.onCameraPermission(true)
        if (SessionHolder.resumeLive) {
            SessionHolder.resumeLive = false
            if (hasCameraPermission()) resumeLive()
        }
        if (SessionHolder.resumeReplay) {
            SessionHolder.resumeReplay = false
            controller.resumePaused()
        }
        ui.post(poll)
    }

    override fun onPause() {
        ui.removeCallbacks(poll)
        // The camera is released when the app leaves the screen (not for a rotation); the
        // tracker and its trajectory stay, and live tracking resumes on return.
        if (!isChangingConfigurations && controller.running == FrameSource.LIVE) {
            SessionHolder.resumeLive = true
            controller.stopSource()
        }
        // A replay holds still while the app is away, and goes on on return (if the user had not paused it).
        if (!isChangingConfigurations && controller.running == FrameSource.REPLAY && !controller.paused) {
            SessionHolder.resumeReplay = controller.pause()
        }
        super.onPause()
    }

    @Deprecated("Called up to Android 12L, and on 13+ without predictive back")
    @Suppress("DEPRECATION")
    override fun onBackPressed() {
        finish() // not super: on 12+ that only moves a root activity's task to the back
    }

    /** Pads [v] by the system bars' and cutout's insets plus its own [pad]. */
    private fun applyInsets(v: View, insets: WindowInsets, pad: Int): WindowInsets {
        if (Build.VERSION.SDK_INT >= 30) {
            val i = insets.getInsets(WindowInsets.Type.systemBars() or WindowInsets.Type.displayCutout())
            v.setPadding(pad + i.left, pad + i.top, pad + i.right, pad + i.bottom)
        } else {
            @Suppress("DEPRECATION")
            v.setPadding(
                pad + insets.systemWindowInsetLeft, pad + insets.systemWindowInsetTop,
                pad + insets.systemWindowInsetRight, pad + insets.systemWindowInsetBottom,
            )
        }
        return insets
    }

    override fun onDestroy() {
        // Leaving the app (back) ends the session; a rotation keeps it.
        if (isFinishing && !isChangingConfigurations) {
            SessionHolder.resumeLive = false
            controller.reset()
        }
        // A dialog left open would leak its window; onSaveInstanceState noted it for the next activity.
        dialog?.let { d -> dialog = null; d.dismiss() }
        super.onDestroy()
    }

    /** The dialog on screen and what it shows, to reopen it after a rotation. */
    private var dialog: AlertDialog? = null
    private var dialogKind: String? = null

    private fun keep(kind: String, d: AlertDialog) {
        dialog = d
        dialogKind = kind
        d.setOnDismissListener { if (dialog === d) { dialog = null; dialogKind = null } }
    }

    override fun onSaveInstanceState(outState: Bundle) {
        super.onSaveInstanceState(outState)
        dialogKind?.let { outState.putString(STATE_DIALOG, it) }
    }

    /** Reopens the dialog a rotation closed ([kind] as [keep] named it). */
    private fun reopenDialog(kind: String) {
        when {
            kind == "settings" -> settingsDialog.show()
            kind == "recordings" -> recordingsDialog.show()
            kind == "permission" -> onLiveClicked()
            kind.startsWith("recording:") || kind.startsWith("delete:") -> recordingsDialog.reopen(kind)
        }
    }

    private fun hasCameraPermission() = checkSelfPermission(Manifest.permission.CAMERA) == PackageManager.PERMISSION_GRANTED

    private fun onLiveClicked() {
        if (!hasDepthCamera) { render(); return }
        when {
            hasCameraPermission() -> startLive()
            shouldShowRequestPermissionRationale(Manifest.permission.CAMERA) ->
                keep("permission", AlertDialog.Builder(this)
                    .setTitle(R.string.permission_title)
                    .setMessage(R.string.permission_rationale)
                    .setPositiveButton(R.string.permission_continue) { _, _ -> requestPermissions(arrayOf(Manifest.permission.CAMERA), REQUEST_CAMERA) }
                    .setNegativeButton(R.string.permission_not_now) { _, _ -> controller.presenter.onCameraPermission(false); render() }
                    .show())
            else -> requestPermissions(arrayOf(Manifest.permission.CAMERA), REQUEST_CAMERA)
        }
    }

    override fun onRequestPermissionsResult(requestCode: Int, permissions: Array<String>, grantResults: IntArray) {
        super.onRequestPermissionsResult(requestCode, permissions, grantResults)
        if (requestCode != REQUEST_CAMERA) return
        val granted = grantResults.isNotEmpty() && grantResults[0] == PackageManager.PERMISSION_GRANTED
        controller.presenter.onCameraPermission(granted)
        if (granted) {
            startLive()
        } else if (grantResults.isNotEmpty() && !shouldShowRequestPermissionRationale(Manifest.permission.CAMERA)) {
            // "Don't ask again" (or denied twice): only the app's settings can grant it now.
            AlertDialog.Builder(this)
                .setTitle(R.string.permission_settings_title)
                .setMessage(R.string.permission_settings_message)
                .setPositiveButton(R.string.permission_open_settings) { _, _ -> openAppSettings() }
                .setNegativeButton(R.string.close, null)
                .show()
        }
        render()
    }

    /** The file picker's answer (Recordings… → Import…). */
    override fun onActivityResult(requestCode: Int, resultCode: Int, data: Intent?) {
        super.onActivityResult(requestCode, resultCode, data)
        val uri = data?.data
        if (requestCode == RecordingsDialog.REQUEST_IMPORT && resultCode == RESULT_OK && uri != null) recordingsDialog.onImportPicked(uri)
    }

    private fun openAppSettings() {
        try {
            startActivity(Intent(Settings.ACTION_APPLICATION_DETAILS_SETTINGS, Uri.fromParts("package", packageName, null)))
        } catch (e: ActivityNotFoundException) {
            controller.presenter.onNotice("Open Settings → Apps → ecvo → Permissions to allow camera access.")
            render()
        }
    }

    /**
     * Replays [files]; [recording] is the recordings folder it comes from (null: the
     * bundled sample). The stream's lists are parsed on a worker thread (136 ms for a
     * 10-minute list on a desktop JVM), then the replay starts on the UI thread.
     */
    private fun startReplay(files: StreamFiles, recording: File? = null) {
        Thread(Runnable {
            val meta = StreamMetadata.read(files)
            val reader = try {
                StreamReader(files)
            } catch (e: Exception) {
                ui.post {
                    controller.stopSource()
                    controller.presenter.onError("Cannot replay ${files.description}: ${e.message ?: e.javaClass.simpleName}")
                    render()
                }
                return@Runnable
            }
            ui.post { if (!isDestroyed) startReplay(reader, recording, meta?.gravityUp) }
        }, "ecvo-replay-open").start()
    }

    private fun startReplay(reader: StreamReader, recording: File?, gravityUp: DoubleArray?) {
        SessionHolder.camera = null
        // The recording's gravity if it stored one; else the first camera's x-z top view.
        if (gravityUp != null) GravitySensor.use(this, gravityUp) else GravitySensor.clear(this)
        SessionHolder.resumeLive = false
        SessionHolder.resumeReplay = false
        trajectoryView.clear()
        SessionHolder.previewSize = reader.camera.width to reader.camera.height
        val s = settings
        val started = controller.start(FrameSource.REPLAY, s.trackerConfig(reader.camera, FrameSource.REPLAY)) { cb ->
            ReplaySource(reader, cb, s.replaySpeed) { d, g -> if (SessionHolder.preview != PreviewKind.NONE) SessionHolder.latest.put(d, g) }
                .also { SessionHolder.replay = it }.start()
        }
        // Set whether or not the start succeeded: a failed start must not export the previous session's stream.
        SessionHolder.streams.onStarted(if (started) recording else null)
        SessionHolder.sessionPointCloud = s.pointCloud
        SessionHolder.sessionCamera = reader.camera
        render()
    }

    /** The live setup of the current session (kept to resume after a pause). */
    private var liveSetup: DepthCameraSource.Setup?
        get() = SessionHolder.liveSetup
        set(v) { SessionHolder.liveSetup = v }

    private fun startLive() {
        // Read now, with the permission granted: earlier, the calibration is hidden.
        val s = settings
        val setup = try {
            DepthCameraSource.find(cameraManager, s.liveCameras, s.depthOnlyPairs, s.trackingResolution)
        } catch (e: Exception) {
            controller.presenter.onError("Reading the depth camera failed: ${e.message ?: e.javaClass.simpleName}")
            render()
            return
        }
        if (setup == null) {
            hasDepthCamera = false
            controller.presenter.onDepthCameraChecked(false)
            render()
            return
        }
        liveSetup = setup
        GravitySensor.measure(this, setup.sensorOrientation, setup.backFacing)
        trajectoryView.clear()
        SessionHolder.gravityPending = true
        val started = controller.start(FrameSource.LIVE, s.trackerConfig(setup.frame, FrameSource.LIVE)) { cb -> openCamera(setup, cb) }
        SessionHolder.streams.onStarted(null) // also after a failed start: no earlier session's stream
        SessionHolder.sessionPointCloud = s.pointCloud
        SessionHolder.sessionCamera = setup.frame
        if (started) {
            setup.notes.forEach { controller.presenter.onNotice(it) }
        }
        render()
    }

    private fun resumeLive() {
        val setup = liveSetup ?: return
        controller.resume(FrameSource.LIVE) { cb -> openCamera(setup, cb) }
        render()
    }

    private fun openCamera(setup: DepthCameraSource.Setup, cb: io.ecvo.shared.SourceCallbacks): io.ecvo.shared.SourceHandle {
        SessionHolder.previewSize = setup.frame.width to setup.frame.height
        val app = applicationContext
        val source = DepthCameraSource(
            cameraManager, setup, SessionHolder.frames, settings.confidence, cb,
            onTracked = { d, g ->
                // The tracker's world is the first tracked frame's camera: gravity is taken then.
                if (SessionHolder.gravityPending) {
                    SessionHolder.gravityPending = false
                    ui.post { GravitySensor.freeze() }
                }
                if (SessionHolder.preview != PreviewKind.NONE) SessionHolder.latest.put(d, g)
            },
            // Remembered for this phone: the next Live starts with depth alone.
            onFellBack = { key -> SessionHolder.rememberDepthOnly(app, key) },
        )
        SessionHolder.replay = null
        SessionHolder.camera = source
        val camera = source.start()
        // The gyroscope runs exactly as long as the camera: the handle the controller stops
        // (pause, reset, restart) unregisters it too.
        val gyro = GyroSensor.start(this, setup.sensorOrientation, setup.backFacing, GyroTarget)
        // The samples reach the tracker in the depth camera's axes (recorded in the device's).
        controller.session?.imuRotation = if (gyro) GyroSensor.rotationCameraDevice else null
        if (gyro && GyroSensor.rateLimited) {
            cb.notice("The gyroscope is limited to 200 Hz on this phone (the fastest rate was refused).")
        }
        return GyroHandle(app, camera)
    }

    /** The current session's gyroscope buffer, looked up at each sample (a session may be replaced). */
    private object GyroTarget : GyroSensor.Target {
        override fun buffer() = SessionHolder.controller.session?.gyro
    }

    /** Stops the gyroscope with the camera it runs beside. */
    private class GyroHandle(private val app: android.content.Context, private val camera: io.ecvo.shared.SourceHandle) : io.ecvo.shared.SourceHandle {
        override fun stop() {
            GyroSensor.stop(app)
            camera.stop()
        }
    }

    private fun setRecording(on: Boolean) {
        if (on) {
            val name = SimpleDateFormat("yyyyMMdd-HHmmss", Locale.ROOT).format(Date())
            val dir = File(recordingsDir, name)
            val meta = { cam: CameraIntrinsics ->
                DeviceInfo.metadata(this, settings, controller.presenter.status.mode.ifEmpty { null }, cam)
            }
            // With a gyroscope, camera.json carries its calibration and imu.txt is written beside the frames.
            val imu = GyroSensor.rotationCameraDevice?.let { r -> controller.session?.imuCalibration(r) }
            if (controller.startRecording { cam -> StreamRecorder(dir, cam, imu).also { meta(cam).write(dir) } }) SessionHolder.streams.onRecording(dir)
        } else {
            // Returns at once; the queue drains on the recorder's thread, then the toast.
            val app = applicationContext
            if (controller.stopRecording { r ->
                    val text = app.getString(R.string.recorded_to, r.recorder.framesWritten, r.recorder.dir.path) +
                        (if (r.dropped > 0) app.getString(R.string.recorded_dropped, r.dropped) else "")
                    Toast.makeText(app, text, Toast.LENGTH_LONG).show()
                }
            ) {
                Toast.makeText(this, R.string.recording_finishing, Toast.LENGTH_SHORT).show()
            }
        }
        render()
    }

    /** The Share button: the session with the stream it replays or recorded, shared or saved to Downloads. */
    private fun chooseExport() {
        val plan = ExportSelection.forSession(controller.session != null, SessionHolder.streams.stream)
        if (plan == null) {
            Toast.makeText(this, R.string.nothing_to_export, Toast.LENGTH_LONG).show()
            return
        }
        AlertDialog.Builder(this)
            .setItems(arrayOf<CharSequence>(getString(R.string.export_share), getString(R.string.export_downloads))) { _, which ->
                exportPlan(plan, null, if (which == 0) Exporter.Target.SHARE else Exporter.Target.DOWNLOADS)
            }
            .setNegativeButton(R.string.close, null)
            .show()
    }

    private fun exportPlan(plan: ExportPlan, recordingName: String?, target: Exporter.Target) {
        val meta = DeviceInfo.metadata(this, settings, controller.presenter.status.mode.ifEmpty { null }, SessionHolder.sessionCamera)
        exporter.export(plan, recordingName, if (plan.withSession) controller.session else null, SessionHolder.sessionPointCloud, meta, target)
    }

    /** Polls the session and redraws. */
    private fun refresh() {
        polls++
        val ts = controller.poll(pose, SessionHolder.camera?.pairer?.droppedNoColour ?: 0)
        if (polls % REFERENCES_EVERY == 0L) {
            references = try {
                controller.session?.tracker?.references() ?: emptyList()
            } catch (e: IllegalStateException) {
                emptyList()
            }
        }
        trajectoryView.show(controller.trajectory.poses, references, if (ts == Tracker.NO_POSE) null else pose)
        if (polls % PREVIEW_EVERY == 0L) updatePreview()
        render()
    }

    private fun updatePreview() {
        val kind = settings.preview
        preview.visibility = if (kind == PreviewKind.NONE) View.GONE else View.VISIBLE
        val (w, h) = SessionHolder.previewSize ?: return
        val px = SessionHolder.latest.takePreview(kind) ?: return
        if (px.size != w * h) return
        // One bitmap per size, refilled: not a new one every 200 ms.
        val b = previewBitmap?.takeIf { it.width == w && it.height == h }
        if (b != null) {
            b.setPixels(px, 0, w, 0, 0, w, h)
            preview.invalidate()
        } else {
            previewBitmap = Bitmap.createBitmap(px, w, h, Bitmap.Config.ARGB_8888).copy(Bitmap.Config.ARGB_8888, true)
            preview.setImageBitmap(previewBitmap)
        }
    }

    private fun render() {
        val st = controller.presenter.status
        stateText.text = if (st.mode.isEmpty()) st.state else "${st.state} · ${st.mode}" // e.g. "Tracking · depth only"
        stateText.setTextColor(
            when (st.kind) {
                StatusKind.TRACKING -> 0xFF34A853.toInt()
                StatusKind.LOST, StatusKind.ERROR -> 0xFFEA4335.toInt()
                StatusKind.INITIALISING -> 0xFFFBBC05.toInt()
                StatusKind.IDLE -> 0xFF9E9E9E.toInt()
            },
        )
        numbersText.text = "${st.timing}   ${st.references}\n${st.frames}\n${st.stages}"
        messageText.text = st.message ?: ""
        messageText.visibility = if (st.message == null) View.GONE else View.VISIBLE
        liveButton.isEnabled = hasDepthCamera
        if (recordButton.isChecked != st.recording) recordButton.isChecked = st.recording
        pauseButton.isEnabled = controller.running == FrameSource.REPLAY
        pauseButton.setText(if (controller.paused) R.string.resume else R.string.pause)
        // Keep the screen on during a hands-off live session only; the window is touched on changes only.
        when (screenOn.update(controller.running == FrameSource.LIVE)) {
            true -> window.addFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON)
            false -> window.clearFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON)
            null -> Unit
        }
    }

    companion object {
        private const val TAG = "ecvo"
        private const val POLL_MS = 50L
        private const val REFERENCES_EVERY = 10L
        private const val PREVIEW_EVERY = 4L
        private const val REQUEST_CAMERA = 1
        private const val STATE_DIALOG = "dialog"
    }
}
