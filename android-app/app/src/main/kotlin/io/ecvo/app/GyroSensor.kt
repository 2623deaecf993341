package io.ecvo.app

import android.content.Context
import android.hardware.Sensor
import android.hardware.SensorEvent
import android.hardware.SensorEventListener
import android.hardware.SensorManager
import android.os.Handler
import android.os.HandlerThread
import io.ecvo.shared.GyroBuffer
import io.ecvo.shared.ImuCalibration

/**
 * The gyroscope of a live session (issue 47): `TYPE_GYROSCOPE` at the fastest rate the
 * phone gives, delivered on a thread of its own into the session's [GyroBuffer], which
 * each camera frame drains in one batch (`TrackingSession.gyro`).
 *
 * - Rate: `SENSOR_DELAY_FASTEST` (the sensor's `minDelay`, 200-500 Hz on phones). From
 *   Android 12 an app needs `HIGH_SAMPLING_RATE_SENSORS` (a normal permission, in the
 *   manifest) for more than 200 Hz; where it is refused anyway (the microphone privacy
 *   toggle rate-limits motion sensors, and some builds throw SecurityException) the
 *   listener is registered again at 200 Hz ([RATE_LIMITED_PERIOD_US]) and [rateLimited]
 *   says so.
 * - No gyroscope: [start] returns false and nothing else changes (tracking without IMU).
 * - Lifecycle: [start] when a live camera opens, [stop] when its source stops (pause, reset,
 *   restart), which unregisters the listener and ends the thread; [start] again replaces
 *   any earlier registration.
 *
 * UI thread only (the listener runs on its own thread).
 */
object GyroSensor {
    private var listener: Listener? = null
    private var thread: HandlerThread? = null

    /** The camera-from-device rotation of the running session's depth camera, or null without a gyroscope. */
    @Volatile var rotationCameraDevice: DoubleArray? = null
        private set

    /** Whether the fastest rate was refused and the gyroscope runs at 200 Hz. */
    @Volatile var rateLimited: Boolean = false
        private set

    /**
     * Registers the gyroscope for a depth camera with [orientationDeg] facing the back or
     * not; its samples go to whatever buffer [target] returns at each event (null: dropped).
     * False without a gyroscope.
     */
    fun start(context: Context, orientationDeg: Int, backFacing: Boolean, target: Target): Boolean {
        stop(context)
        val sm = context.applicationContext.getSystemService(Context.SENSOR_SERVICE) as? SensorManager ?: return false
        val sensor = sm.getDefaultSensor(Sensor.TYPE_GYROSCOPE) ?: return false
        val t = HandlerThread("ecvo-gyro")
        t.start()
        val handler = Handler(t.looper)
        val l = Listener(target)
        var ok = try {
            sm.registerListener(l, sensor, SensorManager.SENSOR_DELAY_FASTEST, handler)
        } catch (e: SecurityException) {
            false
        }
        rateLimited = !ok
        if (!ok) ok = sm.registerListener(l, sensor, RATE_LIMITED_PERIOD_US, handler)
        if (!ok) {
            t.quitSafely()
            rateLimited = false
            return false
        }
        listener = l
        thread = t
        rotationCameraDevice = ImuCalibration.cameraFromDevice(orientationDeg, backFacing)
        return true
    }

    /** Unregisters the listener and ends its thread; does nothing when not started. */
    fun stop(context: Context) {
        val l = listener
        listener = null
        if (l != null) {
            (context.applicationContext.getSystemService(Context.SENSOR_SERVICE) as? SensorManager)?.unregisterListener(l)
        }
        thread?.quitSafely()
        thread = null
        rotationCameraDevice = null
    }

    /** Where the samples go (a named interface: the APK's dexer cannot desugar lambdas). */
    fun interface Target {
        fun buffer(): GyroBuffer?
    }

    private class Listener(private val target: Target) : SensorEventListener {
        override fun onSensorChanged(event: SensorEvent) {
            val v = event.values
            if (v.size < 3) return
            target.buffer()?.add(event.timestamp, v[0], v[1], v[2])
        }

        override fun onAccuracyChanged(sensor: Sensor, accuracy: Int) = Unit
    }

    /** 200 Hz: the rate Android 12+ allows without HIGH_SAMPLING_RATE_SENSORS. */
    private const val RATE_LIMITED_PERIOD_US = 5000
}
