package io.ecvo.app

import android.content.Context
import android.os.Handler
import android.os.HandlerThread
import android.os.Looper
import android.os.SystemClock
import io.ecvo.shared.AppSettings
import io.ecvo.shared.LatestFrame
import io.ecvo.shared.SessionController

/**
 * The session outside the activity: one per process, so rotating the phone (which
 * recreates the activity) keeps the tracker, the source, the recording and the
 * trajectory. The activity only draws it and forwards taps. The camera thread and the
 * settings live here too.
 */
object SessionHolder {
    private val ui = Handler(Looper.getMainLooper())

    /**
     * The thread Camera2 delivers images and callbacks on, and the one that opens and
     * closes the cameras (DepthCameraSource confines its camera maps to it). Everything
     * DepthCameraSource runs here catches what it throws: an exception escaping to this
     * thread would end the process.
     */
    val frames: Handler by lazy {
        val t = HandlerThread("ecvo-frames")
        t.start()
        Handler(t.looper)
    }

    val controller: SessionController by lazy {
        SessionController(post = { block -> ui.post(block) }, nowNs = SystemClock::elapsedRealtimeNanos)
    }

    /** What the preview shows (read on the source threads, so that they hold no activity). */
    @Volatile var preview: io.ecvo.shared.PreviewKind = io.ecvo.shared.PreviewKind.NONE

    /** The latest frame, for the preview. */
    val latest = LatestFrame()

    /** The live camera, if one is running (for its drop counter). */
    @Volatile var camera: DepthCameraSource? = null

    /** The replay, if one is running (for its speed). */
    @Volatile var replay: ReplaySource? = null

    /** Whether live tracking should resume when the activity comes back (it was live at onPause). */
    var resumeLive = false

    /** Whether the replay should go on when the activity comes back (the activity paused it, not the user). */
    var resumeReplay = false

    /** The live camera setup of the session (to resume after a pause). */
    var liveSetup: DepthCameraSource.Setup? = null

    /** Width and height of the frames the preview shows. */
    @Volatile var previewSize: Pair<Int, Int>? = null

    /** Whether the live session still waits for its first tracked frame to take gravity (GravitySensor.freeze). */
    @Volatile var gravityPending = false

    /** The intrinsics of the current session's frames (for the export's metadata). */
    @Volatile var sessionCamera: io.ecvo.shared.CameraIntrinsics? = null

    /** Whether the current session builds a point cloud (the setting at its start, not at export). */
    @Volatile var sessionPointCloud = false

    /** The stream of the current session (the recording it replays or made), for export. */
    val streams = io.ecvo.shared.SessionStreams()

    private const val PREFS = "ecvo-settings"
    @Volatile private var settings: AppSettings? = null

    /** The settings (read once from the app's SharedPreferences). */
    fun settings(context: Context): AppSettings = settings ?: synchronized(this) {
        settings ?: context.applicationContext.getSharedPreferences(PREFS, Context.MODE_PRIVATE).let { p ->
            AppSettings.fromMap(p.all.mapValues { it.value?.toString() })
        }.also { settings = it }
    }

    /** Replaces the settings and stores them. */
    fun saveSettings(context: Context, s: AppSettings) = synchronized(this) {
        settings = s
        preview = s.preview
        val e = context.applicationContext.getSharedPreferences(PREFS, Context.MODE_PRIVATE).edit()
        for ((k, v) in s.toMap()) e.putString(k, v)
        e.apply()
    }

    /** Remembers (any thread) that the camera pair [key] fell back to depth alone: the next Live starts so. */
    fun rememberDepthOnly(context: Context, key: String) = synchronized(this) {
        val s = settings(context)
        if (key !in s.depthOnlyPairs) saveSettings(context, s.rememberDepthOnly(key))
    }
}
