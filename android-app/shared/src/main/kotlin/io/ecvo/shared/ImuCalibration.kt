package io.ecvo.shared

import java.io.IOException
import java.util.Locale
import kotlin.math.abs
import kotlin.math.cos
import kotlin.math.sin

/**
 * The calibration of a stream's IMU (issue 47), stored as the `imu` object of
 * `camera.json` in the layout of `docs/imu.md` (what ecvo-io's reader takes):
 *
 * ```
 * "imu": {"camera_from_imu": [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]],
 *         "time_offset": 0.0, "gyro_noise_density": 0.00012}
 * ```
 *
 * - `camera_from_imu`: the rotation R (rows) taking a vector in the IMU's axes to the
 *   camera's (x right, y down, z forward): `ω_camera = R ω_imu`.
 * - `time_offset`: seconds, `t_frames = t_imu + time_offset`. The app writes `imu.txt`
 *   already on the frames' clock, so it writes 0; how that clock was matched ([clock],
 *   [CameraClock.Method]) goes to `metadata.json` (`imu_clock`): ecvo-io refuses keys
 *   it does not know in this object.
 * - `gyro_noise_density` (rad/s/√Hz) and `gyro_bias_random_walk` (rad/s/√s), left out
 *   when not known.
 */
class ImuCalibration(
    /** R, row-major (9 values), a rotation. */
    val rotationCameraImu: DoubleArray,
    /** Seconds added to an IMU timestamp to put it on the frames' clock. */
    val timeOffsetS: Double = 0.0,
    /** How the IMU's clock was put on the frames' ([CameraClock.Method] name), or null; not part of `camera.json`. */
    val clock: String? = null,
    /** Gyroscope white noise, rad/s/√Hz, if known. */
    val gyroNoiseDensity: Double? = null,
    /** Gyroscope bias random walk, rad/s/√s, if known. */
    val gyroBiasRandomWalk: Double? = null,
) {
    init {
        require(rotationCameraImu.size == 9 && rotationCameraImu.all { it.isFinite() }) { "camera_from_imu: 9 finite numbers expected" }
        require(isRotation(rotationCameraImu)) { "camera_from_imu: not a rotation (RᵀR = I and det R = 1 within $ROTATION_TOLERANCE)" }
        require(timeOffsetS.isFinite() && abs(timeOffsetS) <= MAX_TIME_OFFSET_S) { "time_offset: $timeOffsetS s is not within ±$MAX_TIME_OFFSET_S s" }
        for ((k, v) in listOf("gyro_noise_density" to gyroNoiseDensity, "gyro_bias_random_walk" to gyroBiasRandomWalk)) {
            require(v == null || (v.isFinite() && v >= 0)) { "$k: $v is not a finite non-negative number" }
        }
    }

    /** The `imu` object's JSON text (one line), for `camera.json`. */
    fun toJson(): String = buildString {
        append("{\"camera_from_imu\": [")
        for (row in 0 until 3) {
            if (row > 0) append(", ")
            append('[')
            for (col in 0 until 3) {
                if (col > 0) append(", ")
                append(String.format(Locale.ROOT, "%.9f", rotationCameraImu[3 * row + col]))
            }
            append(']')
        }
        append("], \"time_offset\": ").append(Timestamps.plain(timeOffsetS))
        gyroNoiseDensity?.let { append(", \"gyro_noise_density\": ").append(Timestamps.plain(it)) }
        gyroBiasRandomWalk?.let { append(", \"gyro_bias_random_walk\": ").append(Timestamps.plain(it)) }
        append('}')
    }

    /** Rotates an IMU-axes vector into the camera's axes. */
    fun toCamera(x: Double, y: Double, z: Double): DoubleArray {
        val r = rotationCameraImu
        return doubleArrayOf(r[0] * x + r[1] * y + r[2] * z, r[3] * x + r[4] * y + r[5] * z, r[6] * x + r[7] * y + r[8] * z)
    }

    companion object {
        /** Largest |time_offset| read: a second (a larger one is a wrong clock, not an offset). */
        const val MAX_TIME_OFFSET_S: Double = 1.0

        /** Tolerance of the rotation check (the file's 9 decimals give about 1e-9). */
        const val ROTATION_TOLERANCE: Double = 1e-6

        /**
         * The nominal camera-from-device rotation of a camera with `SENSOR_ORIENTATION`
         * [orientationDeg] facing the back ([backFacing]) or the user: the device's sensor
         * axes (x right and y up in the natural orientation, z out of the screen) into the
         * camera's (x right, y down, z forward), as [GravityAlignment.upInCamera] maps
         * gravity. It ignores the few tenths of a degree a camera module is mounted off its
         * nominal axes.
         */
        fun cameraFromDevice(orientationDeg: Int, backFacing: Boolean): DoubleArray {
            require(orientationDeg % 90 == 0) { "orientation $orientationDeg° is not a multiple of 90" }
            val t = Math.toRadians(orientationDeg.toDouble())
            val s = if (backFacing) 1.0 else -1.0
            val c = Math.round(cos(t)).toDouble(); val n = Math.round(sin(t)).toDouble()
            return doubleArrayOf(s * c, -n, 0.0, -s * n, -c, 0.0, 0.0, 0.0, -s)
        }

        /** Whether [r] (row-major 3x3) is a rotation within [ROTATION_TOLERANCE]. */
        fun isRotation(r: DoubleArray): Boolean {
            if (r.size != 9) return false
            for (i in 0 until 3) for (j in 0 until 3) {
                var d = 0.0
                for (k in 0 until 3) d += r[3 * k + i] * r[3 * k + j]
                if (abs(d - (if (i == j) 1.0 else 0.0)) > ROTATION_TOLERANCE) return false
            }
            val det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) + r[2] * (r[3] * r[7] - r[4] * r[6])
            return abs(det - 1.0) <= ROTATION_TOLERANCE
        }

        /**
         * The `imu` object of `camera.json` text, or null when it has none; IOException
         * naming [source] and the field for a malformed one.
         */
        fun fromCameraJson(text: String, source: String = CameraIntrinsics.FILE_NAME): ImuCalibration? {
            val root = try {
                Json.parse(text)
            } catch (e: IllegalArgumentException) {
                throw IOException("$source: ${e.message}")
            } as? Map<*, *> ?: throw IOException("$source: expected a JSON object")
            val imu = root["imu"] ?: return null
            if (imu !is Map<*, *>) throw IOException("$source: field `imu` is not an object")
            val rows = imu["camera_from_imu"] as? List<*> ?: throw IOException("$source: imu.camera_from_imu is missing or not an array")
            if (rows.size != 3) throw IOException("$source: imu.camera_from_imu has ${rows.size} rows, expected 3")
            val r = DoubleArray(9)
            for (i in 0 until 3) {
                val row = rows[i] as? List<*> ?: throw IOException("$source: imu.camera_from_imu[$i] is not an array")
                if (row.size != 3) throw IOException("$source: imu.camera_from_imu[$i] has ${row.size} values, expected 3")
                for (j in 0 until 3) r[3 * i + j] = (row[j] as? Double) ?: throw IOException("$source: imu.camera_from_imu[$i][$j] is not a number")
            }
            fun num(k: String): Double? = when (val v = imu[k]) {
                null -> null
                is Double -> v
                else -> throw IOException("$source: imu.$k is not a number")
            }
            return try {
                ImuCalibration(r, num("time_offset") ?: 0.0, null, num("gyro_noise_density"), num("gyro_bias_random_walk"))
            } catch (e: IllegalArgumentException) {
                throw IOException("$source: imu.${e.message}")
            }
        }

        /** The calibration in the stream's `camera.json`, or null when it has none. */
        fun read(files: StreamFiles): ImuCalibration? =
            if (!files.exists(CameraIntrinsics.FILE_NAME)) null
            else fromCameraJson(String(files.readBytes(CameraIntrinsics.FILE_NAME), Charsets.UTF_8), "${files.description}/${CameraIntrinsics.FILE_NAME}")
    }
}
