package io.ecvo.app

import android.content.Context
import android.hardware.Sensor
import android.hardware.SensorEvent
import android.hardware.SensorEventListener
import android.hardware.SensorManager
import io.ecvo.shared.GravityAlignment

/**
 * Gravity at the first tracked frame of a live session, for the gravity-aligned top view
 * (the tracker's world is that frame's camera): [measure] starts listening to
 * `TYPE_GRAVITY` (or, without it, `TYPE_ACCELEROMETER`) at the Live press and keeps the
 * latest [READINGS] readings; [freeze], called when the first frame reaches the tracker,
 * averages them (or the next ones, if none came yet), turns the result into the depth
 * camera's frame with its `SENSOR_ORIENTATION`, and removes the listener. [up] stays null
 * for a replay (no gravity was recorded) or a phone without either sensor: the top view
 * is then the first camera's x-z plane, unless the recording stored gravity ([use]).
 * UI thread only.
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

    /** Uses [recorded] (a replayed recording's `gravity_up`) as the direction, with no measurement. */
    fun use(context: Context, recorded: DoubleArray) {
        stop(context)
        up = recorded.copyOf()
    }

    /** Starts listening for a session whose depth camera has [orientationDeg] and faces the back or not. */
    fun measure(context: Context, orientationDeg: Int, backFacing: Boolean) {
        clear(context)
        val sm = context.applicationContext.getSystemService(Context.SENSOR_SERVICE) as? SensorManager ?: return
        val sensor = sm.getDefaultSensor(Sensor.TYPE_GRAVITY) ?: sm.getDefaultSensor(Sensor.TYPE_ACCELEROMETER) ?: return
        val l = Listener(sm, orientationDeg, backFacing)
        listener = l
        sm.registerListener(l, sensor, SensorManager.SENSOR_DELAY_GAME)
    }

    /** The first frame was tracked: gravity is the average of the latest readings (or of the next ones). */
    fun freeze() {
        listener?.freeze()
    }

    private fun stop(context: Context) {
        val l = listener ?: return
        listener = null
        (context.applicationContext.getSystemService(Context.SENSOR_SERVICE) as? SensorManager)?.unregisterListener(l)
    }

    /** Keeps the latest [READINGS] readings (a named class, not a lambda: the APK's dexer cannot desugar lambdas). */
    private class Listener(private val sm: SensorManager, private val orientationDeg: Int, private val backFacing: Boolean) : SensorEventListener {
        private val ring = DoubleArray(3 * READINGS)
        private var n = 0
        private var frozen = false

        override fun onSensorChanged(event: SensorEvent) {
            val v = event.values
            if (v.size < 3) return
            val k = 3 * (n % READINGS)
            ring[k] = v[0].toDouble(); ring[k + 1] = v[1].toDouble(); ring[k + 2] = v[2].toDouble()
            n++
            if (frozen && n >= READINGS) finish()
        }

        fun freeze() {
            frozen = true
            if (n > 0) finish()
        }

        private fun finish() {
            val m = minOf(n, READINGS)
            var x = 0.0; var y = 0.0; var z = 0.0
            for (i in 0 until m) { x += ring[3 * i]; y += ring[3 * i + 1]; z += ring[3 * i + 2] }
            up = GravityAlignment.upInCamera(x / m, y / m, z / m, orientationDeg, backFacing)
            sm.unregisterListener(this)
            if (listener === this) listener = null
        }

        override fun onAccuracyChanged(sensor: Sensor, accuracy: Int) = Unit
    }

    /** Readings averaged (about 0.1 s at SENSOR_DELAY_GAME). */
    private const val READINGS = 5
}
