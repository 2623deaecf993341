package io.ecvo.shared

import io.ecvo.ReferenceFrame
import io.ecvo.TimedPose
import kotlin.math.atan2
import kotlin.math.floor
import kotlin.math.hypot
import kotlin.math.log10
import kotlin.math.max
import kotlin.math.min
import kotlin.math.pow

/**
 * The plane a trajectory is drawn in. World coordinates are the first camera's (x right,
 * y down, z forward); each plane names the world axis shown to the right ([right]) and
 * the one shown upwards on screen ([up]), each as an axis index and a sign.
 */
enum class ProjectionPlane(
    val rightAxis: Int, val rightSign: Double,
    val upAxis: Int, val upSign: Double,
) {
    /** Top view: x to the right, forward (z) up. The default. */
    XZ(0, 1.0, 2, 1.0),

    /** Front view, as the first camera sees it: x to the right, up is -y. */
    XY(0, 1.0, 1, -1.0),

    /** Side view: forward (z) to the right, up is -y. */
    YZ(2, 1.0, 1, -1.0);

    /** Plane coordinates (right, up) of a world point. */
    fun project(x: Double, y: Double, z: Double): Pair<Double, Double> {
        val p = doubleArrayOf(x, y, z)
        return rightSign * p[rightAxis] to upSign * p[upAxis]
    }
}

/**
 * A uniform-scale map from plane coordinates (metres) to view pixels (y down): a point
 * at plane (r, u) lands at `(centreX + (r - midR) * scale, centreY - (u - midU) * scale)`.
 */
data class ViewTransform(
    /** Pixels per metre, the same on both axes. */
    val scale: Double,
    val midR: Double,
    val midU: Double,
    val centreX: Double,
    val centreY: Double,
) {
    fun x(r: Double): Float = (centreX + (r - midR) * scale).toFloat()
    fun y(u: Double): Float = (centreY - (u - midU) * scale).toFloat()

    companion object {
        /**
         * The largest scale that shows the box [minR]..[maxR] x [minU]..[maxU] inside a
         * [viewWidth] x [viewHeight] view with [margin] pixels free on every side, aspect
         * preserved and the box centred. A box smaller than [minExtent] metres on a side
         * is treated as that big, so a short trajectory is not blown up.
         */
        fun fit(
            minR: Double, maxR: Double, minU: Double, maxU: Double,
            viewWidth: Int, viewHeight: Int, margin: Double, minExtent: Double,
        ): ViewTransform {
            val w = max(1.0, viewWidth - 2 * margin)
            val h = max(1.0, viewHeight - 2 * margin)
            val er = max(maxR - minR, minExtent)
            val eu = max(maxU - minU, minExtent)
            val s = min(w / er, h / eu)
            return ViewTransform(s, (minR + maxR) / 2, (minU + maxU) / 2, viewWidth / 2.0, viewHeight / 2.0)
        }
    }
}

/** The current camera drawn as a marker: position in pixels and heading (radians, screen coordinates, 0 = right, π/2 = down). */
data class PoseMarker(val x: Float, val y: Float, val heading: Float, val hasHeading: Boolean)

/** A reference frame in view pixels, with its level. */
data class ProjectedReference(val x: Float, val y: Float, val level: Int)

/** A scale bar: [lengthPx] pixels stand for [metres]. */
data class ScaleBar(val metres: Double, val lengthPx: Float) {
    /** "10 cm", "50 cm", "1 m", "2 m" ... */
    val label: String get() = if (metres < 1.0) "${Math.round(metres * 100)} cm" else if (metres == floor(metres)) "${metres.toLong()} m" else "$metres m"
}

/** Everything a trajectory view draws, in view pixels. */
class ProjectedScene(
    /** Path vertices as x, y pairs. */
    val path: FloatArray,
    val references: List<ProjectedReference>,
    val marker: PoseMarker?,
    /** Where the world origin (the first camera) is. */
    val origin: Pair<Float, Float>,
    val transform: ViewTransform,
    val scaleBar: ScaleBar,
) {
    /** Number of path vertices. */
    val pathSize: Int get() = path.size / 2
}

/**
 * Projects a trajectory, its reference frames and the current pose onto a
 * [ProjectionPlane] and fits them into a view. Pure: the view calls [project] on every
 * draw with what the tracker reports.
 */
class TrajectoryProjector(
    var plane: ProjectionPlane = ProjectionPlane.XZ,
    /** Free pixels on every side. */
    var marginPx: Double = 32.0,
    /** Smallest extent shown, metres (so a still camera is not zoomed in on noise). */
    var minExtentM: Double = 0.5,
    /**
     * Gravity's opposite in world coordinates ([GravityAlignment.upInCamera] at the session's
     * start), or null: the top view ([ProjectionPlane.XZ]) then looks down along it
     * ([GravityPlane]) instead of along the first camera's y axis.
     */
    up: DoubleArray? = null,
) {
    private var gravity: GravityPlane? = up?.let { GravityPlane(it) }

    /** See the constructor; null for none. */
    var up: DoubleArray? = up
        set(v) {
            field = v
            gravity = v?.let { GravityPlane(it) }
        }

    /** Plane coordinates of a world point (or direction) in the current view. */
    private fun onPlane(x: Double, y: Double, z: Double): Pair<Double, Double> {
        val g = gravity
        return if (plane == ProjectionPlane.XZ && g != null) g.project(x, y, z) else plane.project(x, y, z)
    }

    /**
     * Projects [trajectory], [references] and the current pose [current] (a 4x4
     * column-major camera-to-world matrix as `Tracker.getPose` writes it, or null) into a
     * [viewWidth] x [viewHeight] view. The fit covers every pose, reference, the current
     * pose and the origin.
     */
    fun project(
        trajectory: List<TimedPose>,
        references: List<ReferenceFrame>,
        current: FloatArray?,
        viewWidth: Int,
        viewHeight: Int,
    ): ProjectedScene {
        val n = trajectory.size
        val pr = DoubleArray(n)
        val pu = DoubleArray(n)
        var minR = 0.0; var maxR = 0.0; var minU = 0.0; var maxU = 0.0 // the origin is always shown
        fun include(r: Double, u: Double) {
            minR = min(minR, r); maxR = max(maxR, r); minU = min(minU, u); maxU = max(maxU, u)
        }
        for ((i, p) in trajectory.withIndex()) {
            val (r, u) = onPlane(p.tx, p.ty, p.tz)
            pr[i] = r; pu[i] = u
            include(r, u)
        }
        val refs = references.map { onPlane(it.pose.tx, it.pose.ty, it.pose.tz) }
        refs.forEach { include(it.first, it.second) }
        var cur: Pair<Double, Double>? = null
        var fwd: Pair<Double, Double>? = null
        if (current != null) {
            require(current.size >= 16) { "pose matrix needs 16 floats, got ${current.size}" }
            cur = onPlane(current[12].toDouble(), current[13].toDouble(), current[14].toDouble())
            // Column 2: the camera's forward (z) axis in the world.
            fwd = onPlane(current[8].toDouble(), current[9].toDouble(), current[10].toDouble())
            include(cur.first, cur.second)
        }
        val t = ViewTransform.fit(minR, maxR, minU, maxU, viewWidth, viewHeight, marginPx, minExtentM)

        val path = FloatArray(2 * n)
        for (i in 0 until n) {
            path[2 * i] = t.x(pr[i]); path[2 * i + 1] = t.y(pu[i])
        }
        val projectedRefs = refs.mapIndexed { i, (r, u) -> ProjectedReference(t.x(r), t.y(u), references[i].level) }
        val marker = cur?.let { (r, u) ->
            val (fr, fu) = fwd!!
            val has = hypot(fr, fu) > 1e-3 // looking along the plane's normal: no heading to show
            // Screen y grows downwards, so an upward plane direction is a negative screen angle.
            PoseMarker(t.x(r), t.y(u), if (has) atan2(-fu, fr).toFloat() else 0f, has)
        }
        return ProjectedScene(path, projectedRefs, marker, t.x(0.0) to t.y(0.0), t, scaleBar(t.scale, viewWidth / 4.0))
    }

    companion object {
        /** The longest 1-2-5 length (metres) whose bar is at most [maxPx] pixels at [pixelsPerMetre]. */
        fun scaleBar(pixelsPerMetre: Double, maxPx: Double): ScaleBar {
            val maxM = maxPx / pixelsPerMetre
            var m = 10.0.pow(floor(log10(maxM)))
            for (k in doubleArrayOf(5.0, 2.0, 1.0)) {
                if (m * k <= maxM * (1 + 1e-9)) { m *= k; break }
            }
            val rounded = Math.round(m * 1e6) / 1e6 // drop binary noise such as 0.30000000000000004
            return ScaleBar(rounded, (rounded * pixelsPerMetre).toFloat())
        }
    }
}
