package io.ecvo.app

import android.annotation.SuppressLint
import android.graphics.ImageFormat
import android.hardware.camera2.CameraCaptureSession
import android.hardware.camera2.CameraCharacteristics
import android.hardware.camera2.CameraDevice
import android.hardware.camera2.CameraManager
import android.hardware.camera2.CameraMetadata
import android.hardware.camera2.CaptureRequest
import android.hardware.camera2.CaptureResult
import android.hardware.camera2.TotalCaptureResult
import android.media.ImageReader
import android.os.Build
import android.os.Handler
import android.os.SystemClock
import io.ecvo.shared.CameraCalibration
import io.ecvo.shared.CameraFailure
import io.ecvo.shared.CameraIntrinsics
import io.ecvo.shared.CameraPose
import io.ecvo.shared.ColourWatch
import io.ecvo.shared.ConfidencePolicy
import io.ecvo.shared.DepthDecoder
import io.ecvo.shared.DepthRemap
import io.ecvo.shared.ExposureLock
import io.ecvo.shared.FailureAction
import io.ecvo.shared.FramePairer
import io.ecvo.shared.GrayPlane
import io.ecvo.shared.IntensityRegistration
import io.ecvo.shared.LiveCamera
import io.ecvo.shared.LiveMode
import io.ecvo.shared.LiveModeDecision
import io.ecvo.shared.LiveCameras
import io.ecvo.shared.LiveFallbackMemory
import io.ecvo.shared.LiveModePolicy
import io.ecvo.shared.Pairing
import io.ecvo.shared.PosePolicy
import io.ecvo.shared.PoseReference
import io.ecvo.shared.SensorRect
import io.ecvo.shared.SourceCallbacks
import io.ecvo.shared.SourceHandle
import io.ecvo.shared.StreamSize
import io.ecvo.shared.StreamSizes
import io.ecvo.shared.TimestampSource
import io.ecvo.shared.TrackingResolution

/**
 * Live frames from a Camera2 depth camera (`ImageFormat.DEPTH16`) with intensity from a
 * colour camera facing the same way (the Y plane of `YUV_420_888`), or depth alone (an
 * all-zero intensity plane, which the engine tracks on depth alone) when there is no such
 * camera, the phone will not stream both, or no colour frame arrives ([LiveModePolicy];
 * the mode reaches the screen through `callbacks.mode`). Every decision is
 * made by :shared ([Setup.find] only copies `CameraCharacteristics` into it): the stream
 * sizes and the intrinsics, lens distortion, the depth-to-colour pose,
 * pairing by clock, and the confidence policy. Frames reach [callbacks] on [handler]'s
 * thread at the depth stream's native size (a 240x180 ToF stream stays 240x180 with its
 * own intrinsics), or halved ([TrackingResolution]), as millimetres and 8-bit gray;
 * every failure (including a throwing Camera2 call) reaches the fallback policy or
 * `callbacks.failed`, never the thread's uncaught handler. Camera opens, callbacks and
 * closes all run on [handler]'s thread, which alone touches the maps of open cameras.
 */
class DepthCameraSource(
    private val manager: CameraManager,
    private val setup: Setup,
    private val handler: Handler,
    confidence: ConfidencePolicy,
    private val callbacks: SourceCallbacks,
    /** Called with each frame handed to the tracker (for the preview). */
    private val onTracked: (ShortArray, ByteArray) -> Unit = { _, _ -> },
    /** Called (camera thread) with [Setup.pairKey] when the pair fell back to depth alone, to be remembered. */
    private val onFellBack: (String) -> Unit = {},
) : SourceHandle {
    /** The cameras and sizes chosen by [find], and how a frame is made from them. */
    class Setup(
        val depthId: String,
        val depthSize: StreamSize,
        /** The colour camera for intensity, or null (depth only). */
        val colour: Colour?,
        /** Depth stream to tracker frame (same size; undistorts if needed); its camera is the tracker's. */
        val remap: DepthRemap,
        /** The mode to start in ([LiveModePolicy.start]). */
        val mode: LiveModeDecision,
        /** The depth camera's `SENSOR_ORIENTATION` (degrees) and whether it faces the back, for gravity. */
        val sensorOrientation: Int,
        val backFacing: Boolean,
        /** Whether the depth camera's `SENSOR_INFO_TIMESTAMP_SOURCE` is REALTIME (one clock across camera instances). */
        val depthRealtime: Boolean,
        /** The depth + colour pair's [LiveFallbackMemory] key, or null without a colour camera. */
        val pairKey: String?,
        /** Sentences for the user about fallbacks taken (no calibration, no lens pose, clocks). */
        val notes: List<String>,
    ) {
        /** Intrinsics of the frames handed to the tracker. */
        val frame: CameraIntrinsics get() = remap.camera
    }

    /** The colour camera of a [Setup]. */
    class Colour(val id: String, val size: StreamSize, val registration: IntensityRegistration, val pairing: Pairing)

    private val depthReader = ImageReader.newInstance(setup.depthSize.width, setup.depthSize.height, ImageFormat.DEPTH16, 3)
    private val colourReader = setup.colour?.let { ImageReader.newInstance(it.size.width, it.size.height, ImageFormat.YUV_420_888, 3) }
    /** Cameras opened and not closed yet, by id (camera thread). */
    private val devices = HashMap<String, CameraDevice>()
    private val sessions = HashMap<String, CameraCaptureSession>()
    private var readersClosed = false
    private val decoder = DepthDecoder(confidence)
    val pairer = FramePairer(setup.colour?.pairing ?: Pairing.ARRIVAL_TIME)
    private val watch = ColourWatch()
    private val rawDepth = ShortArray(setup.depthSize.width * setup.depthSize.height)
    private val frameDepth = ShortArray(setup.frame.pixels)
    /** The intensity of a depth-only frame: all zero, which the engine tracks on depth alone. */
    private val noIntensity = ByteArray(setup.frame.pixels)
    /** The registered intensity, reused frame after frame (the tracker, recorder and preview copy it). */
    private val registered = ByteArray(setup.frame.pixels)
    private val y = ByteArray(setup.colour?.let { it.size.width * it.size.height } ?: 0)
    private var confidenceNoted = false
    private val exposure = ExposureLock()
    private var colourRequest: CaptureRequest.Builder? = null
    @Volatile private var running = false
    @Volatile var mode: LiveMode = setup.mode.mode
        private set

    /**
     * Opens the cameras (depth first) and starts streaming; returns at once. Call with the
     * CAMERA permission granted. The opens run on the camera thread, like every callback
     * and failure path, so the maps of open cameras are touched by that thread alone.
     */
    fun start(): DepthCameraSource {
        running = true
        depthReader.setOnImageAvailableListener({ r -> guarded("depth frame") { onDepth(r) } }, handler)
        colourReader?.setOnImageAvailableListener({ r -> guarded("colour frame") { onColour(r) } }, handler)
        callbacks.mode(mode)
        setup.mode.note?.let { callbacks.notice(it) }
        handler.post {
            if (running) {
                guarded("opening the cameras") {
                    open(setup.depthId, LiveCamera.DEPTH, depthReader)
                    val c = setup.colour
                    if (mode == LiveMode.DEPTH_AND_COLOUR && c != null && colourReader != null) open(c.id, LiveCamera.COLOUR, colourReader)
                }
            }
        }
        return this
    }

    private inline fun guarded(what: String, block: () -> Unit) {
        try {
            block()
        } catch (e: Exception) {
            callbacks.failed("$what: ${e.message ?: e.javaClass.simpleName}")
        }
    }

    private fun onColour(r: ImageReader) {
        val img = r.acquireLatestImage() ?: return
        try {
            if (mode != LiveMode.DEPTH_AND_COLOUR) return
            val size = setup.colour?.size ?: return
            val p = img.planes[0] // Y: pixel stride 1, rows rowStride apart
            val b = p.buffer
            for (row in 0 until size.height) {
                b.position(row * p.rowStride)
                b.get(y, row * size.width, size.width)
            }
            watch.onColour()
            pairer.onColour(img.timestamp, SystemClock.elapsedRealtimeNanos())
        } finally {
            img.close()
        }
    }

    /**
     * Watches the colour stream's capture results and locks auto-exposure and white
     * balance once both converged ([ExposureLock]): the tracker's photometric terms
     * assume a point keeps its brightness.
     */
    private inner class ExposureWatch : CameraCaptureSession.CaptureCallback() {
        override fun onCaptureCompleted(session: CameraCaptureSession, request: CaptureRequest, result: TotalCaptureResult) = guarded("colour exposure") {
            val action = exposure.onResult(result.get(CaptureResult.CONTROL_AE_STATE), result.get(CaptureResult.CONTROL_AWB_STATE))
            if (action == ExposureLock.Action.WAIT) return@guarded
            if (action == ExposureLock.Action.LOCK_UNCONVERGED) callbacks.notice(ExposureLock.UNCONVERGED_NOTE)
            lockExposure(session)
        }
    }

    private fun lockExposure(session: CameraCaptureSession) {
        val id = setup.colour?.id ?: return
        if (sessions[id] !== session) return
        val request = colourRequest ?: return
        guarded("camera $id: locking exposure") {
            request.set(CaptureRequest.CONTROL_AE_LOCK, true)
            request.set(CaptureRequest.CONTROL_AWB_LOCK, true)
            session.setRepeatingRequest(request.build(), null, handler)
        }
    }

    private fun onDepth(r: ImageReader) {
        val img = r.acquireLatestImage() ?: return
        val ts: Long
        try {
            val p = img.planes[0]
            decoder.decodePlane(p.buffer, p.rowStride, setup.depthSize.width, setup.depthSize.height, rawDepth)
            ts = img.timestamp
        } finally {
            img.close()
        }
        if (decoder.codesIgnored && !confidenceNoted) {
            confidenceNoted = true
            callbacks.notice("This depth camera's confidence codes do not follow Android's documentation; every measured pixel is kept.")
        }
        if (!running) return
        val colour = setup.colour
        if (mode == LiveMode.DEPTH_AND_COLOUR && colour != null) {
            if (watch.onDepth()) {
                setup.pairKey?.let(onFellBack)
                switchToDepthOnly("no colour frames arrived")
            } else {
                if (!pairer.onDepth(ts, SystemClock.elapsedRealtimeNanos())) return
                setup.remap.apply(rawDepth, frameDepth)
                val gray = colour.registration.register(frameDepth, GrayPlane(y, colour.size.width, colour.size.height), registered)
                onTracked(frameDepth, gray)
                callbacks.frame(ts, frameDepth, gray)
                return
            }
        }
        setup.remap.apply(rawDepth, frameDepth)
        onTracked(frameDepth, noIntensity)
        callbacks.frame(ts, frameDepth, noIntensity)
    }

    /** Closes the colour camera; depth goes on alone. */
    private fun switchToDepthOnly(why: String) {
        if (mode == LiveMode.DEPTH_ONLY) return
        mode = LiveMode.DEPTH_ONLY
        callbacks.mode(mode)
        callbacks.notice(LiveModePolicy.fallbackNote(why))
        val id = setup.colour?.id ?: return
        sessions.remove(id)?.let { runCatching { it.close() } }
        devices[id]?.let { runCatching { it.close() } } // removed in onClosed
    }

    /** Closes both cameras and reopens the depth camera alone (after the colour one took its place). */
    private fun restartDepthOnly(why: String) {
        mode = LiveMode.DEPTH_ONLY
        callbacks.mode(mode)
        callbacks.notice(LiveModePolicy.fallbackNote(why))
        sessions.values.forEach { runCatching { it.close() } }
        sessions.clear()
        devices.values.toList().forEach { runCatching { it.close() } }
        handler.postDelayed({ if (running) guarded("camera ${setup.depthId}: reopening") { open(setup.depthId, LiveCamera.DEPTH, depthReader) } }, REOPEN_DELAY_MS)
    }

    private fun onCameraFailed(id: String, camera: LiveCamera, failure: CameraFailure, message: String) {
        if (!running) return
        val action = LiveModePolicy.onFailure(mode, camera, failure)
        if (LiveModePolicy.remembers(mode, action)) setup.pairKey?.let(onFellBack)
        when (action) {
            FailureAction.CONTINUE_DEPTH_ONLY -> switchToDepthOnly(message)
            FailureAction.RESTART_DEPTH_ONLY -> restartDepthOnly(message)
            FailureAction.FAIL -> callbacks.failed(message)
        }
        if (camera == LiveCamera.DEPTH && devices[id] == null) closeReadersIfIdle()
    }

    /** The readers are closed only once no camera is open (a closing camera may still write to them). */
    private fun closeReadersIfIdle() {
        if (running || devices.isNotEmpty() || readersClosed) return
        readersClosed = true
        depthReader.close()
        colourReader?.close()
    }

    @SuppressLint("MissingPermission")
    private fun open(id: String, camera: LiveCamera, reader: ImageReader) {
        try {
            manager.openCamera(id, object : CameraDevice.StateCallback() {
                override fun onOpened(device: CameraDevice) {
                    devices[id] = device
                    if (!running || (camera == LiveCamera.COLOUR && mode != LiveMode.DEPTH_AND_COLOUR)) { device.close(); return }
                    // A new camera instance: its clock may restart lower (CameraTimeline).
                    if (camera == LiveCamera.DEPTH) callbacks.cameraStarted(setup.depthRealtime)
                    guarded("camera $id") {
                        @Suppress("DEPRECATION")
                        device.createCaptureSession(listOf(reader.surface), object : CameraCaptureSession.StateCallback() {
                            override fun onConfigured(session: CameraCaptureSession) {
                                if (!running || devices[id] !== device) { session.close(); return }
                                sessions[id] = session
                                // Throws CameraAccessException, IllegalStateException (closed) or IllegalArgumentException.
                                guarded("camera $id: starting the stream") {
                                    // Colour: TEMPLATE_RECORD (a steady frame rate), exposure and white balance locked once converged (ExposureWatch).
                                    val template = if (camera == LiveCamera.COLOUR) CameraDevice.TEMPLATE_RECORD else CameraDevice.TEMPLATE_PREVIEW
                                    val request = device.createCaptureRequest(template)
                                    request.addTarget(reader.surface)
                                    if (camera == LiveCamera.COLOUR) colourRequest = request
                                    session.setRepeatingRequest(request.build(), if (camera == LiveCamera.COLOUR) ExposureWatch() else null, handler)
                                }
                            }

                            override fun onConfigureFailed(session: CameraCaptureSession) =
                                onCameraFailed(id, camera, CameraFailure.CONFIGURE_FAILED, "camera $id: stream configuration failed")
                        }, handler)
                    }
                }

                override fun onClosed(device: CameraDevice) = guarded("camera $id: closing") {
                    if (devices[id] === device) devices.remove(id)
                    closeReadersIfIdle()
                }

                override fun onDisconnected(device: CameraDevice) = guarded("camera $id: disconnected") {
                    runCatching { device.close() }
                    // Ignored by the controller if this source was already replaced.
                    onCameraFailed(id, camera, CameraFailure.DISCONNECTED, "camera $id was disconnected")
                }

                override fun onError(device: CameraDevice, error: Int) = guarded("camera $id: error $error") {
                    runCatching { device.close() }
                    val failure = CameraFailure.fromErrorCode(error)
                    val inUse = failure == CameraFailure.IN_USE || failure == CameraFailure.MAX_CAMERAS_IN_USE
                    onCameraFailed(
                        id, camera, failure,
                        if (inUse) "camera $id is in use; this phone may not stream the depth and colour cameras at once" else "camera $id failed (error $error)",
                    )
                }
            }, handler)
        } catch (e: SecurityException) {
            callbacks.failed("camera $id: camera permission missing")
        } catch (e: Exception) {
            // CameraAccessException, IllegalArgumentException (an id gone), IllegalStateException:
            // on the camera thread (open runs there only), never uncaught on it.
            onCameraFailed(id, camera, CameraFailure.EXCEPTION, "camera $id: ${e.message ?: e.javaClass.simpleName}")
        }
    }

    /**
     * Stops streaming and closes the cameras (on the camera thread); the readers are closed
     * after the last camera reported `onClosed`, never under a camera still closing.
     */
    override fun stop() {
        running = false
        handler.post {
            sessions.values.forEach { runCatching { it.close() } }
            sessions.clear()
            devices.values.toList().forEach { runCatching { it.close() } }
            closeReadersIfIdle()
        }
    }

    companion object {
        /** Numeric camera ids tried beyond `getCameraIdList` ("0" to "15"). */
        private const val HIDDEN_IDS_PROBED = 16

        /** Wait before reopening the depth camera alone, after closing both. */
        private const val REOPEN_DELAY_MS = 300L

        /**
         * Whether some camera has the `DEPTH_OUTPUT` capability (readable without the
         * CAMERA permission; the calibration is read later, by [find]).
         */
        fun hasDepthCamera(manager: CameraManager): Boolean = cameraIds(manager).any { id ->
            characteristics(manager, id)?.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES)
                ?.contains(CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_DEPTH_OUTPUT) == true
        }

        /**
         * The listed camera ids, then the small numeric ids the list leaves out: some phones
         * keep their ToF camera out of `getCameraIdList` but describe and open it by id.
         */
        private fun cameraIds(manager: CameraManager): List<String> =
            (manager.cameraIdList.toList() + (0 until HIDDEN_IDS_PROBED).map { it.toString() }).distinct()

        /** The characteristics of camera [id], or null if the phone has no such camera. */
        private fun characteristics(manager: CameraManager, id: String): CameraCharacteristics? = try {
            manager.getCameraCharacteristics(id)
        } catch (e: IllegalArgumentException) {
            null
        }

        /**
         * Finds a camera with `DEPTH_OUTPUT` and DEPTH16 streams and, if there is one, a
         * colour camera facing the same way (without one, live tracking runs on depth
         * alone), reading their calibration; null if the phone has no depth camera.
         * Call at the start of a session, after the CAMERA permission was granted: without
         * it, Camera2 hides `LENS_INTRINSIC_CALIBRATION` and `LENS_POSE_*`.
         */
        fun find(
            manager: CameraManager,
            liveCameras: LiveCameras = LiveCameras.AUTO,
            depthOnlyPairs: Set<String> = emptySet(),
            resolution: TrackingResolution = TrackingResolution.AUTO,
        ): Setup? {
            // Listed and unlisted ids that the phone describes.
            val ids = cameraIds(manager).filter { characteristics(manager, it) != null }
            // Listed cameras before unlisted ones; within each, back-facing first (the usual world-facing ToF).
            val listed = manager.cameraIdList.toSet()
            val ordered = ids.sortedWith(
                compareBy<String>({ if (it in listed) 0 else 1 }, { if (characteristics(manager, it)?.get(CameraCharacteristics.LENS_FACING) == CameraMetadata.LENS_FACING_BACK) 0 else 1 }),
            )
            for (depthId in ordered) {
                val dc = characteristics(manager, depthId) ?: continue
                val caps = dc.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES) ?: continue
                if (CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_DEPTH_OUTPUT !in caps) continue
                val sizes = dc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP)?.getOutputSizes(ImageFormat.DEPTH16)
                    ?.map { StreamSize(it.width, it.height) } ?: continue
                // Tracked at the stream's native size (240x180 stays 240x180): no crop, no upsampling.
                val depthSize = StreamSizes.nativeDepth(sizes) ?: continue
                val facing = dc.get(CameraCharacteristics.LENS_FACING)
                // Listed colour cameras facing the same way (an unlisted one may be a physical
                // camera only its logical camera opens); the largest sensor is the "primary" one.
                val colours = manager.cameraIdList.filter { id ->
                    id != depthId && manager.getCameraCharacteristics(id).let { c ->
                        c.get(CameraCharacteristics.LENS_FACING) == facing &&
                            c.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES)
                                ?.contains(CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_BACKWARD_COMPATIBLE) == true
                    }
                }
                val notes = ArrayList<String>()
                val depthCal = calibration(dc)
                if (!depthCal.calibrated) notes += "The depth camera publishes no intrinsic calibration; its focal length is estimated from the lens and sensor size."
                val depthCam = depthCal.sensorIntrinsics().forOutput(depthSize.width, depthSize.height)
                // The tracker's frame: the stream's size, or halved (TrackingResolution), undistorted if needed.
                val frameSize = resolution.frameSize(depthSize)
                val remap = DepthRemap.create(depthCam, frameSize.width, frameSize.height, depthCal.effectiveDistortion)
                val colour = colourFor(manager, dc, colours, depthSize, remap, notes)
                // Which cameras the phone guarantees to stream at once (API 30+); before, unknown.
                val concurrent: List<Set<String>>? = if (Build.VERSION.SDK_INT >= 30) manager.concurrentCameraIds.map { it.toSet() } else null
                val pairKey = colour?.let { LiveFallbackMemory.key(depthId, it.id) }
                return Setup(
                    depthId, depthSize, colour, remap,
                    LiveModePolicy.start(depthId, colour?.id, concurrent, liveCameras, pairKey != null && pairKey in depthOnlyPairs),
                    dc.get(CameraCharacteristics.SENSOR_ORIENTATION) ?: 0,
                    facing != CameraMetadata.LENS_FACING_FRONT,
                    clock(dc) == TimestampSource.REALTIME, pairKey, notes,
                )
            }
            return null
        }

        /** The primary (largest-sensor) colour camera of [colours], with its registration to the depth frame; null if none or it has no YUV stream. */
        private fun colourFor(
            manager: CameraManager, dc: CameraCharacteristics, colours: List<String>, depthSize: StreamSize, remap: DepthRemap, notes: MutableList<String>,
        ): Colour? {
            if (colours.isEmpty()) return null
            // The largest sensor is the "primary" one; it is the one used (not merely the first listed).
            val primary = colours.maxBy { id ->
                manager.getCameraCharacteristics(id).get(CameraCharacteristics.SENSOR_INFO_ACTIVE_ARRAY_SIZE)?.let { it.width().toLong() * it.height() } ?: 0L
            }
            val colourId = primary
            val cc = manager.getCameraCharacteristics(colourId)
            val yuv = cc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP)?.getOutputSizes(ImageFormat.YUV_420_888)
                ?.map { StreamSize(it.width, it.height) } ?: return null
            val colourSize = StreamSizes.colour(yuv, depthSize, remap.camera.width) ?: return null
            val colourCam = calibration(cc).sensorIntrinsics().forOutput(colourSize.width, colourSize.height)
            val decision = PosePolicy.decide(
                pose(dc), pose(cc), colourIsPrimary = colourId == primary,
                depthOrientation = dc.get(CameraCharacteristics.SENSOR_ORIENTATION) ?: 0,
                colourOrientation = cc.get(CameraCharacteristics.SENSOR_ORIENTATION) ?: 0,
            )
            decision.note?.let { notes += it }
            val pairing = Pairing.choose(clock(dc), clock(cc))
            if (pairing == Pairing.ARRIVAL_TIME) notes += "The cameras' timestamps are not on a common clock; depth and colour are paired by arrival time."
            return Colour(colourId, colourSize, IntensityRegistration(remap.camera, colourCam, decision.depthToColour), pairing)
        }

        private fun calibration(c: CameraCharacteristics): CameraCalibration {
            val pre = c.get(CameraCharacteristics.SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE)
            val active = c.get(CameraCharacteristics.SENSOR_INFO_ACTIVE_ARRAY_SIZE)
            val phys = c.get(CameraCharacteristics.SENSOR_INFO_PHYSICAL_SIZE)
            val distortion = if (Build.VERSION.SDK_INT >= 28) c.get(CameraCharacteristics.LENS_DISTORTION) else null
            // Outputs are corrected only if the camera has a correction mode other than OFF
            // (and then FAST by default); depth cameras normally have none.
            val corrected = Build.VERSION.SDK_INT >= 28 &&
                (c.get(CameraCharacteristics.DISTORTION_CORRECTION_AVAILABLE_MODES)?.any { it != CameraMetadata.DISTORTION_CORRECTION_MODE_OFF } == true)
            return CameraCalibration(
                pre?.let { SensorRect(it.left, it.top, it.width(), it.height()) },
                active?.let { SensorRect(it.left, it.top, it.width(), it.height()) },
                c.get(CameraCharacteristics.LENS_INTRINSIC_CALIBRATION),
                distortion,
                c.get(CameraCharacteristics.LENS_INFO_AVAILABLE_FOCAL_LENGTHS)?.firstOrNull(),
                phys?.width, phys?.height,
                corrected,
            )
        }

        private fun pose(c: CameraCharacteristics) = CameraPose(
            c.get(CameraCharacteristics.LENS_POSE_ROTATION),
            c.get(CameraCharacteristics.LENS_POSE_TRANSLATION),
            PoseReference.fromCode(if (Build.VERSION.SDK_INT >= 28) c.get(CameraCharacteristics.LENS_POSE_REFERENCE) else null),
        )

        private fun clock(c: CameraCharacteristics) = TimestampSource.fromCode(c.get(CameraCharacteristics.SENSOR_INFO_TIMESTAMP_SOURCE))
    }
}
