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
import android.os.Handler
import android.util.Size
import io.ecvo.shared.CameraIntrinsics
import io.ecvo.shared.Depth16
import io.ecvo.shared.DepthResample
import io.ecvo.shared.GrayPlane
import io.ecvo.shared.IntensityRegistration
import io.ecvo.shared.LensPose
import kotlin.math.abs

/**
 * Live frames from a Camera2 depth camera (`ImageFormat.DEPTH16`) with intensity from a
 * colour camera facing the same way (the Y plane of `YUV_420_888`), registered to the
 * depth frame with :shared's [IntensityRegistration]. Frames reach [onFrame] on
 * [handler]'s thread as 320x180 millimetres and 8-bit gray; problems reach [onFailure].
 */
class DepthCameraSource(
    private val manager: CameraManager,
    private val setup: Setup,
    private val handler: Handler,
    private val minConfidence: Int,
    private val onFrame: (timestampNs: Long, depthMm: ShortArray, intensity: ByteArray) -> Unit,
    private val onFailure: (String) -> Unit,
) {
    /** The cameras and sizes chosen by [find], and the intrinsics of the tracker's frame. */
    class Setup(
        val depthId: String,
        val depthSize: Size,
        val colourId: String,
        val colourSize: Size,
        /** Intrinsics of the 320x180 frames handed to the tracker (millimetres). */
        val frame: CameraIntrinsics,
        val registration: IntensityRegistration,
    )

    private val depthReader = ImageReader.newInstance(setup.depthSize.width, setup.depthSize.height, ImageFormat.DEPTH16, 3)
    private val colourReader = ImageReader.newInstance(setup.colourSize.width, setup.colourSize.height, ImageFormat.YUV_420_888, 3)
    private val devices = ArrayList<CameraDevice>()
    private val sessions = ArrayList<CameraCaptureSession>()
    private val rawDepth = ShortArray(setup.depthSize.width * setup.depthSize.height)
    private val y = ByteArray(setup.colourSize.width * setup.colourSize.height)
    private var yTimestamp = Long.MIN_VALUE
    @Volatile private var running = false

    /** Opens both cameras and starts streaming. Call with the CAMERA permission granted. */
    @SuppressLint("MissingPermission")
    fun start() {
        running = true
        colourReader.setOnImageAvailableListener({ r ->
            val img = r.acquireLatestImage() ?: return@setOnImageAvailableListener
            img.use {
                val p = it.planes[0] // Y: pixel stride 1
                val b = p.buffer
                val w = setup.colourSize.width
                for (row in 0 until setup.colourSize.height) {
                    b.position(row * p.rowStride)
                    b.get(y, row * w, w)
                }
                yTimestamp = it.timestamp
            }
        }, handler)
        depthReader.setOnImageAvailableListener({ r ->
            val img = r.acquireLatestImage() ?: return@setOnImageAvailableListener
            val ts = img.use {
                val p = it.planes[0]
                Depth16.decodePlane(p.buffer, p.rowStride, setup.depthSize.width, setup.depthSize.height, minConfidence, rawDepth)
                it.timestamp
            }
            // Pair with the latest Y image if it is close enough in time (same clock on one device).
            if (!running || yTimestamp == Long.MIN_VALUE || abs(ts - yTimestamp) > MAX_PAIR_DT_NS) return@setOnImageAvailableListener
            val f = setup.frame
            val depth = DepthResample.nearest(rawDepth, setup.depthSize.width, setup.depthSize.height, f.width, f.height)
            val gray = setup.registration.register(depth, GrayPlane(y, setup.colourSize.width, setup.colourSize.height))
            onFrame(ts, depth, gray)
        }, handler)
        open(setup.colourId, colourReader)
        open(setup.depthId, depthReader)
    }

    @SuppressLint("MissingPermission")
    private fun open(id: String, reader: ImageReader) {
        try {
            manager.openCamera(id, object : CameraDevice.StateCallback() {
                override fun onOpened(device: CameraDevice) {
                    if (!running) { device.close(); return }
                    devices += device
                    @Suppress("DEPRECATION")
                    device.createCaptureSession(listOf(reader.surface), object : CameraCaptureSession.StateCallback() {
                        override fun onConfigured(session: CameraCaptureSession) {
                            if (!running) { session.close(); return }
                            sessions += session
                            val request = device.createCaptureRequest(CameraDevice.TEMPLATE_PREVIEW).apply { addTarget(reader.surface) }
                            session.setRepeatingRequest(request.build(), null, handler)
                        }

                        override fun onConfigureFailed(session: CameraCaptureSession) = onFailure("camera $id: stream configuration failed")
                    }, handler)
                }

                override fun onDisconnected(device: CameraDevice) { device.close(); onFailure("camera $id was disconnected") }

                override fun onError(device: CameraDevice, error: Int) {
                    device.close()
                    onFailure(
                        if (error == CameraDevice.StateCallback.ERROR_MAX_CAMERAS_IN_USE || error == CameraDevice.StateCallback.ERROR_CAMERA_IN_USE) {
                            "camera $id is in use; this phone may not stream the depth and colour cameras at once"
                        } else {
                            "camera $id failed (error $error)"
                        },
                    )
                }
            }, handler)
        } catch (e: CameraAccessException) {
            onFailure("camera $id: ${e.message}")
        }
    }

    /** Stops streaming and closes the cameras. */
    fun stop() {
        running = false
        handler.post {
            sessions.forEach { it.close() }
            devices.forEach { it.close() }
            sessions.clear(); devices.clear()
            depthReader.close(); colourReader.close()
        }
    }

    companion object {
        /** Largest time between a depth image and the Y image used for its intensity. */
        const val MAX_PAIR_DT_NS = 50_000_000L

        /**
         * Finds a camera with `DEPTH_OUTPUT` and DEPTH16 streams and a colour camera facing
         * the same way; null if the phone has no depth camera (the UI says so).
         */
        fun find(manager: CameraManager, frameWidth: Int = 320, frameHeight: Int = 180): Setup? {
            val ids = manager.cameraIdList
            for (depthId in ids) {
                val dc = manager.getCameraCharacteristics(depthId)
                val caps = dc.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES) ?: continue
                if (CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_DEPTH_OUTPUT !in caps) continue
                val sizes = dc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP)?.getOutputSizes(ImageFormat.DEPTH16) ?: continue
                if (sizes.isEmpty()) continue
                // The size closest to the tracker's frame, preferring the same aspect.
                val depthSize = sizes.minBy { abs(it.width - frameWidth) + abs(it.height - frameHeight) * 2 }
                val facing = dc.get(CameraCharacteristics.LENS_FACING)
                val colourId = ids.firstOrNull { id ->
                    if (id == depthId) return@firstOrNull false
                    val c = manager.getCameraCharacteristics(id)
                    c.get(CameraCharacteristics.LENS_FACING) == facing &&
                        c.get(CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES)
                            ?.contains(CameraMetadata.REQUEST_AVAILABLE_CAPABILITIES_BACKWARD_COMPATIBLE) == true
                } ?: continue
                val cc = manager.getCameraCharacteristics(colourId)
                val yuv = cc.get(CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP)?.getOutputSizes(ImageFormat.YUV_420_888) ?: continue
                val aspect = depthSize.width.toDouble() / depthSize.height
                // Small but at least twice the tracker's width, with the depth camera's aspect if possible.
                val colourSize = yuv.filter { it.width >= 2 * frameWidth }
                    .minByOrNull { abs(it.width.toDouble() / it.height - aspect) * 10_000 + it.width }
                    ?: yuv.maxBy { it.width * it.height }
                val depthCam = intrinsics(dc, depthSize)
                val colourCam = intrinsics(cc, colourSize)
                val frame = depthCam.resized(frameWidth, frameHeight)
                val relative = LensPose.depthToColour(
                    dc.get(CameraCharacteristics.LENS_POSE_ROTATION), dc.get(CameraCharacteristics.LENS_POSE_TRANSLATION),
                    cc.get(CameraCharacteristics.LENS_POSE_ROTATION), cc.get(CameraCharacteristics.LENS_POSE_TRANSLATION),
                )
                return Setup(depthId, depthSize, colourId, colourSize, frame, IntensityRegistration(frame, colourCam, relative))
            }
            return null
        }

        /**
         * Pinhole intrinsics of a camera's output of [size]: from `LENS_INTRINSIC_CALIBRATION`
         * (given for the pre-correction active array) when present, else from the focal
         * length and the physical sensor size with the principal point at the centre; then
         * cropped and scaled the way Camera2 makes an output of another aspect (centred crop).
         */
        private fun intrinsics(c: CameraCharacteristics, size: Size): CameraIntrinsics {
            val array = c.get(CameraCharacteristics.SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE)
            val cal = c.get(CameraCharacteristics.LENS_INTRINSIC_CALIBRATION)
            if (cal != null && array != null && cal[0] > 0f && cal[1] > 0f) {
                val full = CameraIntrinsics(array.width(), array.height(), cal[0].toDouble(), cal[1].toDouble(),
                    (cal[2] - array.left).toDouble(), (cal[3] - array.top).toDouble())
                return full.forOutput(size.width, size.height)
            }
            val f = c.get(CameraCharacteristics.LENS_INFO_AVAILABLE_FOCAL_LENGTHS)?.firstOrNull() ?: 0f
            val phys = c.get(CameraCharacteristics.SENSOR_INFO_PHYSICAL_SIZE)
            val w = array?.width() ?: size.width
            val h = array?.height() ?: size.height
            val fx: Double = if (f > 0f && phys != null && phys.width > 0f) (f / phys.width * w).toDouble() else w * 0.8
            val fy: Double = if (f > 0f && phys != null && phys.height > 0f) (f / phys.height * h).toDouble() else fx
            return CameraIntrinsics(w, h, fx, fy, (w - 1) / 2.0, (h - 1) / 2.0).forOutput(size.width, size.height)
        }
    }
}
