package io.ecvo.app

import android.os.Handler
import android.os.HandlerThread
import android.os.Looper
import android.os.SystemClock
import io.ecvo.shared.LatestFrame
import io.ecvo.shared.SessionController

/**
 * The session outside the activity: one per process, so rotating the phone (which
 * recreates the activity) keeps the tracker, the source, the recording and the
 * trajectory. The activity only draws it and forwards taps. The camera thread lives here
 * too.
 */
object SessionHolder {
    private val ui = Handler(Looper.getMainLooper())

    /** The thread Camera2 delivers images on. */
    val frames: Handler by lazy { Handler(HandlerThread("ecvo-frames").also { it.start() }.looper) }

    val controller: SessionController by lazy {
        SessionController(post = { block -> ui.post(block) }, nowNs = SystemClock::elapsedRealtimeNanos)
    }

    /** What the preview shows (read on the source threads, so that they hold no activity). */
    @Volatile var preview: io.ecvo.shared.PreviewKind = io.ecvo.shared.PreviewKind.NONE

    /** The latest frame, for the preview. */
    val latest = LatestFrame()

    /** The live camera, if one is running (for its drop counter). */
    @Volatile var camera: DepthCameraSource? = null

    /** Whether live tracking should resume when the activity comes back (it was live at onPause). */
    var resumeLive = false

    /** The live camera setup of the session (to resume after a pause). */
    var liveSetup: DepthCameraSource.Setup? = null

    /** Width and height of the frames the preview shows. */
    @Volatile var previewSize: Pair<Int, Int>? = null

    /** The stream of the current session (the recording it replays or made), for export. */
    val streams = io.ecvo.shared.SessionStreams()
}
