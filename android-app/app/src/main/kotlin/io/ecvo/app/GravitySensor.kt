package io.ecvo.app

import android.content.Context
import android.hardware.Sensor
import android.hardware.SensorEvent
import android.hardware.SensorEventListener
import android.hardware.SensorManager
import io.ecvo.shared.GravityAlignment

/**
 * Gravity at the start of a live session, for the gravity-aligned top view: the first few
 * readings of `TYPE_GRAVITY` (or, without it, `TYPE_ACCELEROMETER`) averaged, turned into
 * the depth camera's frame (the tracker's world is the first camera's) with its
 * `SENSOR_ORIENTATION`, then the listener is removed. [up] stays null for a replay (no
 * gravity was recorded) or a phone without either sensor: the top view is then the first
 * camera's x-z plane.
 */
object GravitySensor {
    /** World up in the tracker's world (the first camera's frame), or null. */
    @Volatile var up: DoubleArray? = null
        private set

    private var listener: Listener? = null

    /** Forgets the direction (a replay, a reset) and stops any measurement. */
    fun clear(context: Context) {
        stop(context)
        up = null
    }

    /** Starts measuring for a session whose depth camera has [orientationDeg] and faces the back or not. */
    fun measure(context: Context, orientationDeg: Int, backFacing: Boolean) {
        clear(context)
        val sm = context.applicationContext.getSystemService(Context.SENSOR_SERVICE) as? SensorManager ?: return
        val sensor = sm.getDefaultSensor(Sensor.TYPE_GRAVITY) ?: sm.getDefaultSensor(Sensor.TYPE_ACCELEROMETER) ?: return
        val l = Listener(sm, orientationDeg, backFacing)
        listener = l
        sm.registerListener(l, sensor, SensorManager.SENSOR_DELAY_GAME)
    }

    private fun stop(context: Context) {
        val l = listener ?: return
        listener = null
        (context.applicationContext.getSystemService(Context.SENSOR_SERVICE) as? SensorManager)?.unregisterListener(l)
    }

    /** Averages [READINGS] readings (a named class, not a lambda: the APK's dexer cannot desugar lambdas). */
    private class Listener(private val sm: SensorManager, private val orientationDeg: Int, private val backFacing: Boolean) : SensorEventListener {
        private val sum = DoubleArray(3)
        private var n = 0

        override fun onSensorChanged(event: SensorEvent) {
            val v = event.values
            if (v.size < 3 || n >= READINGS) return
            sum[0] += v[0].toDouble(); sum[1] += v[1].toDouble(); sum[2] += v[2].toDouble()
            n++
            if (n == READINGS) {
                up = GravityAlignment.upInCamera(sum[0] / n, sum[1] / n, sum[2] / n, orientationDeg, backFacing)
                sm.unregisterListener(this)
                if (listener === this) listener = null
            }
        }

        override fun onAccuracyChanged(sensor: Sensor, accuracy: Int) = Unit
    }

    /** Readings averaged (about 0.1 s at SENSOR_DELAY_GAME). */
    private const val READINGS = 5
}
