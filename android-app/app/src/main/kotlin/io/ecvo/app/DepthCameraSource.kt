package io.ecvo.app

import android.annotation.SuppressLint
import android.graphics.ImageFormat
import android.hardware.camera2.CameraAccessException
import android.hardware.camera2.CameraCaptureSession
import android.hardware.camera2.CameraCharacteristics
import android.hardware.camera2.CameraDevice
import android.hardware.camera2.CameraManager
import android.hardware.camera2.CameraMetadata
import android.media.ImageReader
import android.os.Build
import android.os.Handler
import android.os.SystemClock
import io.ecvo.shared.CameraCalibration
import io.ecvo.shared.CameraIntrinsics
import io.ecvo.shared.CameraPose
import io.ecvo.shared.ConfidencePolicy
import io.ecvo.shared.DepthDecoder
import io.ecvo.shared.DepthRemap
import io.ecvo.shared.FramePairer
import io.ecvo.shared.GrayPlane
import io.ecvo.shared.IntensityRegistration
import io.ecvo.shared.Pairing
import io.ecvo.shared.PosePolicy
import io.ecvo.shared.PoseReference
import io.ecvo.shared.SensorRect
import io.ecvo.shared.SourceCallbacks
import io.ecvo.shared.SourceHandle
import io.ecvo.shared.StreamSize
import io.ecvo.shared.StreamSizes
import io.ecvo.shared.TimestampSource

/**
 * Live frames from a Camera2 depth camera (`ImageFormat.DEPTH16`) with intensity from a
 * colour camera facing the same way (the Y plane of `YUV_420_888`). Every decision is
 * made by :shared ([Setup.find] only copies `CameraCharacteristics` into it): the stream
 * sizes and the intrinsics, lens distortion, the depth-to-colour pose,
 * pairing by clock, and the confidence policy. Frames reach [callbacks] on [handler]'s
 * thread at the depth stream's native size (a 240x180 ToF stream stays 240x180 with its
 * own intrinsics) as millimetres and 8-bit gray; every failure (including a throwing
 * Camera2 call) reaches `callbacks.failed`, never the thread's uncaught handler.
 */
class DepthCameraSource(
    private val manager: CameraManager,
    private val setup: Setup,
    private val handler: Handler,
    confidence: ConfidencePolicy,
    private val callbacks: SourceCallbacks,
    /** Called with each frame handed to the tracker (for the preview). */
    private val onTracked: (ShortArray, ByteArray) -> Unit = { _, _ -> },
) : SourceHandle {
    /** The cameras and sizes chosen by [find], and how a frame is made from them. */
    class Setup(
        val depthId: String,
        val depthSize: StreamSize,
        val colourId: String,
        val colourSize: StreamSize,
        /** Depth stream to tracker frame (same size; undistorts if needed); its camera is the tracker's. */
        val remap: DepthRemap,
        val registration: IntensityRegistration,
        val pairing: Pairing,
        /** Sentences for the user about fallbacks taken (no calibration, no lens pose, clocks). */
        val notes: List<String>,
    ) {
        /** Intrinsics of the frames handed to the tracker. */
        val frame: CameraIntrinsics get() = remap.camera
    }

    private val depthReader = ImageReader.newInstance(setup.depthSize.width, setup.depthSize.height, ImageFormat.DEPTH16, 3)
    private val colourReader = ImageReader.newInstance(setup.colourSize.width, setup.colourSize.height, ImageFormat.YUV_420_888, 3)
    private val devices = ArrayList<CameraDevice>()
    private val sessions = ArrayList<CameraCaptureSession>()
    private val decoder = DepthDecoder(confidence)
    val pairer = FramePairer(setup.pairing)
    private val rawDepth = ShortArray(setup.depthSize.width * setup.depthSize.height)
    private val frameDepth = ShortArray(setup.frame.pixels)
    private val y = ByteArray(setup.colourSize.width * setup.colourSize.height)
    private var confidenceNoted = false
    @Volatile private var running = false

    /** Opens both cameras and starts streaming. Call with the CAMERA permission granted. */
    fun start(): DepthCameraSource {
        running = true
        colourReader.setOnImageAvailableListener({ r -> guarded("colour frame") { onColour(r) } }, handler)
        depthReader.setOnImageAvailableListener({ r -> guarded("depth frame") { onDepth(r) } }, handler)
        open(setup.colourId, colourReader)
        open(setup.depthId, depthReader)
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
            val p = img.planes[0] // Y: pixel stride 1, rows rowStride apart
            val b = p.buffer
            val w = setup.colourSize.width
            for (row in 0 until setup.colourSize.height) {
                b.position(row * p.rowStride)
                b.get(y, row * w, w)
            }
            pairer.onColour(img.timestamp, SystemClock.elapsedRealtimeNanos())
        } finally {
            img.close()
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
        if (!running || !pairer.onDepth(ts, SystemClock.elapsedRealtimeNanos())) return
        setup.remap.apply(rawDepth, frameDepth)
        val gray = setup.registration.register(frameDepth, GrayPlane(y, setup.colourSize.width, setup.colourSize.height))
        onTracked(frameDepth, gray)
        callbacks.frame(ts, frameDepth, gray)
    }

    @SuppressLint("MissingPermission")
    private fun open(id: String, reader: ImageReader) {
        try {
            manager.openCamera(id, object : CameraDevice.StateCallback() {
                override fun onOpened(device: CameraDevice) {
                    if (!running) { device.close(); return }
                    devices += device
                    guarded("camera $id") {
                        @Suppress("DEPRECATION")
                        device.createCaptureSession(listOf(reader.surface), object : CameraCaptureSession.StateCallback() {
                            override fun onConfigured(session: CameraCaptureSession) {
                                if (!running) { session.close(); return }
                                sessions += session
                                // Throws CameraAccessException, IllegalStateException (closed) or IllegalArgumentException.
                                guarded("camera $id: starting the stream") {
                                    val request = device.createCaptureRequest(CameraDevice.TEMPLATE_PREVIEW)
                                    request.addTarget(reader.surface)
                                    session.setRepeatingRequest(request.build(), null, handler)
                                }
                            }

                            override fun onConfigureFailed(session: CameraCaptureSession) =
                                callbacks.failed("camera $id: stream configuration failed")
                        }, handler)
                    }
                }

                override fun onDisconnected(device: CameraDevice) {
                    device.close()
                    // Ignored by the controller if this source was already replaced.
                    callbacks.failed("camera $id was disconnected")
                }

                override fun onError(device: CameraDevice, error: Int) {
                    device.close()
                    callbacks.failed(
                        if (error == CameraDevice.StateCallback.ERROR_MAX_CAMERAS_IN_USE || error == CameraDevice.StateCallback.ERROR_CAMERA_IN_USE) {
                            "camera $id is in use; this phone may not stream the depth and colour cameras at once"
                        } else {
                            "camera $id failed (error $error)"
                        },
                    )
                }
            }, handler)
        } catch (e: CameraAccessException) {
            callbacks.failed("camera $id: ${e.message}")
        } catch (e: SecurityException) {
            callbacks.failed("camera $id: camera permission missing")
        }
    }

    /** Stops streaming and closes the cameras and readers (on the camera thread). */
    override fun stop() {
        running = false
        handler.post {
            sessions.forEach { runCatching { it.close() } }
            devices.forEach { runCatching { it.close() } }
            sessions.clear(); devices.clear()
            depthReader.close(); colourReader.close()
        }
    }

    companion object {
        /**
         * Whether some camera has the `DEPTH_OUTPUT` capability (readable without the
         * CAMERA permission; the calibration is read later, by [find]).
         */
        fun hasDepthCamera(manager: CameraManager): Boolean = manager.cameraIdList.any { id ->
            manager.getCameraCharacteristics(id).get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES)
                ?.contains(CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_DEPTH_OUTPUT) == true
        }

        /**
         * Finds a camera with `DEPTH_OUTPUT` and DEPTH16 streams and a colour camera facing
         * the same way, reading their calibration; null if the phone has no depth camera.
         * Call at the start of a session, after the CAMERA permission was granted: without
         * it, Camera2 hides `LENS_INTRINSIC_CALIBRATION` and `LENS_POSE_*`.
         */
        fun find(manager: CameraManager): Setup? {
            val ids = manager.cameraIdList
            for (depthId in ids) {
                val dc = manager.getCameraCharacteristics(depthId)
                val caps = dc.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES) ?: continue
                if (CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_DEPTH_OUTPUT !in caps) continue
                val sizes = dc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP)?.getOutputSizes(ImageFormat.DEPTH16)
                    ?.map { StreamSize(it.width, it.height) } ?: continue
                // Tracked at the stream's native size (240x180 stays 240x180): no crop, no upsampling.
                val depthSize = StreamSizes.nativeDepth(sizes) ?: continue
                val facing = dc.get(CameraCharacteristics.LENS_FACING)
                // Colour cameras facing the same way; the largest sensor is the "primary" one.
                val colours = ids.filter { id ->
                    id != depthId && manager.getCameraCharacteristics(id).let { c ->
                        c.get(CameraCharacteristics.LENS_FACING) == facing &&
                            c.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES)
                                ?.contains(CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_BACKWARD_COMPATIBLE) == true
                    }
                }
                if (colours.isEmpty()) continue
                val primary = colours.maxBy { id ->
                    manager.getCameraCharacteristics(id).get(CameraCharacteristics.SENSOR_INFO_ACTIVE_ARRAY_SIZE)?.let { it.width().toLong() * it.height() } ?: 0L
                }
                val colourId = colours.first()
                val cc = manager.getCameraCharacteristics(colourId)
                val yuv = cc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP)?.getOutputSizes(ImageFormat.YUV_420_888)
                    ?.map { StreamSize(it.width, it.height) } ?: continue
                val colourSize = StreamSizes.colour(yuv, depthSize, depthSize.width) ?: continue

                val notes = ArrayList<String>()
                val depthCal = calibration(dc)
                val colourCal = calibration(cc)
                if (!depthCal.calibrated) notes += "The depth camera publishes no intrinsic calibration; its focal length is estimated from the lens and sensor size."
                val depthCam = depthCal.sensorIntrinsics().forOutput(depthSize.width, depthSize.height)
                val colourCam = colourCal.sensorIntrinsics().forOutput(colourSize.width, colourSize.height)
                val remap = DepthRemap.create(depthCam, depthSize.width, depthSize.height, depthCal.effectiveDistortion)
                val decision = PosePolicy.decide(pose(dc), pose(cc), colourIsPrimary = colourId == primary)
                decision.note?.let { notes += it }
                val pairing = Pairing.choose(clock(dc), clock(cc))
                if (pairing == Pairing.ARRIVAL_TIME) notes += "The cameras' timestamps are not on a common clock; depth and colour are paired by arrival time."
                return Setup(
                    depthId, depthSize, colourId, colourSize, remap,
                    IntensityRegistration(remap.camera, colourCam, decision.depthToColour), pairing, notes,
                )
            }
            return null
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
