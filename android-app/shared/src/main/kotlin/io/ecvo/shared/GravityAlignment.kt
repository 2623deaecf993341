package io.ecvo.shared

import kotlin.math.cos
import kotlin.math.sin
import kotlin.math.sqrt

/**
 * The world's "up" in the depth camera's frame, from gravity at the start of a session:
 * the top view then looks down along it, whatever way the phone was held (a phone held
 * upright has its camera's x or y axis vertical, and the first camera's x-z plane is a
 * side view).
 */
object GravityAlignment {
    /**
     * Up (a unit vector) in camera coordinates (x right, y down, z forward, as the
     * tracker's world) from a `TYPE_GRAVITY` or `TYPE_ACCELEROMETER` reading ([ax], [ay],
     * [az], device axes: x right and y up in the natural orientation, z out of the screen;
     * a phone at rest reads +g upwards), for a camera with `SENSOR_ORIENTATION`
     * [orientationDeg] facing the back ([backFacing]) or the user. Null for a reading too
     * small to have a direction (free fall, no sensor).
     *
     * The camera's axes in device axes: the image, rotated [orientationDeg] clockwise, is
     * upright on the screen in the natural orientation, its right edge towards device +x
     * for a back camera (-x for a front one, whose unmirrored image is reversed), its
     * bottom towards -y; z is -z (back) or +z (front).
     */
    fun upInCamera(ax: Double, ay: Double, az: Double, orientationDeg: Int, backFacing: Boolean): DoubleArray? {
        val n = sqrt(ax * ax + ay * ay + az * az)
        if (!(n > MIN_READING)) return null
        val ux = ax / n; val uy = ay / n; val uz = az / n
        val t = Math.toRadians(orientationDeg.toDouble())
        val s = if (backFacing) 1.0 else -1.0
        return doubleArrayOf(s * cos(t) * ux - sin(t) * uy, -s * sin(t) * ux - cos(t) * uy, -s * uz)
    }

    /** Smallest reading (m/s²) taken as a direction. */
    const val MIN_READING: Double = 1.0
}

/**
 * A top view that looks down along [up] (world coordinates, any length): plane
 * coordinates are (right, forward), forward being the first camera's z axis made
 * horizontal (or, for a camera that looked straight down or up, its image's up
 * direction), right = forward x up, so that right x forward = up (seen from above).
 */
class GravityPlane(up: DoubleArray) {
    private val u: DoubleArray
    private val f: DoubleArray
    private val r: DoubleArray

    init {
        require(up.size == 3) { "up needs 3 values, got ${up.size}" }
        u = normalised(up) ?: throw IllegalArgumentException("up has no direction")
        f = horizontal(doubleArrayOf(0.0, 0.0, 1.0)) ?: horizontal(doubleArrayOf(0.0, -1.0, 0.0))!!
        r = cross(f, u)
    }

    /** Plane coordinates (right, forward) of a world point or direction. */
    fun project(x: Double, y: Double, z: Double): Pair<Double, Double> =
        (r[0] * x + r[1] * y + r[2] * z) to (f[0] * x + f[1] * y + f[2] * z)

    private fun horizontal(v: DoubleArray): DoubleArray? {
        val d = v[0] * u[0] + v[1] * u[1] + v[2] * u[2]
        val h = doubleArrayOf(v[0] - d * u[0], v[1] - d * u[1], v[2] - d * u[2])
        val n = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2])
        return if (n < 0.2) null else doubleArrayOf(h[0] / n, h[1] / n, h[2] / n)
    }

    private companion object {
        fun normalised(v: DoubleArray): DoubleArray? {
            val n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
            return if (!(n > 1e-9)) null else doubleArrayOf(v[0] / n, v[1] / n, v[2] / n)
        }

        fun cross(a: DoubleArray, b: DoubleArray) = doubleArrayOf(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    }
}
