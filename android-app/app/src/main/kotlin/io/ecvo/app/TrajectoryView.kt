package io.ecvo.app

import android.content.Context
import android.graphics.Canvas
import android.graphics.Color
import android.graphics.Paint
import android.graphics.Path
import android.util.AttributeSet
import android.view.View
import io.ecvo.ReferenceFrame
import io.ecvo.TimedPose
import io.ecvo.shared.ProjectionPlane
import io.ecvo.shared.TrajectoryProjector

/**
 * Draws the estimated trajectory in a chosen plane (top view by default): the path, the
 * reference frames (level 1 and level 2 in different colours), the current pose with its
 * heading, the origin and a scale bar. All geometry comes from [TrajectoryProjector].
 */
class TrajectoryView @JvmOverloads constructor(context: Context, attrs: AttributeSet? = null) : View(context, attrs) {
    private val projector = TrajectoryProjector()
    private var trajectory: List<TimedPose> = emptyList()
    private var references: List<ReferenceFrame> = emptyList()
    private var pose: FloatArray? = null

    /** The plane to draw in. */
    var plane: ProjectionPlane
        get() = projector.plane
        set(value) {
            projector.plane = value
            invalidate()
        }

    private val density = resources.displayMetrics.density
    private val pathPaint = Paint(Paint.ANTI_ALIAS_FLAG).apply {
        style = Paint.Style.STROKE; strokeWidth = 2 * density; color = Color.rgb(66, 133, 244)
    }
    private val l1Paint = Paint(Paint.ANTI_ALIAS_FLAG).apply { color = Color.rgb(251, 188, 5) }
    private val l2Paint = Paint(Paint.ANTI_ALIAS_FLAG).apply { color = Color.rgb(234, 67, 53) }
    private val markerPaint = Paint(Paint.ANTI_ALIAS_FLAG).apply { color = Color.rgb(52, 168, 83) }
    private val axisPaint = Paint(Paint.ANTI_ALIAS_FLAG).apply { color = Color.GRAY; strokeWidth = density }
    private val textPaint = Paint(Paint.ANTI_ALIAS_FLAG).apply { color = Color.GRAY; textSize = 12 * density }
    private val linePath = Path()
    private val markerPath = Path()

    init {
        projector.marginPx = 24.0 * density
    }

    /** Shows a new state; [pose] is a 4x4 column-major camera-to-world matrix or null. */
    fun show(trajectory: List<TimedPose>, references: List<ReferenceFrame>, pose: FloatArray?) {
        this.trajectory = trajectory
        this.references = references
        this.pose = pose?.copyOf()
        // The top view looks down along gravity once a live session measured it.
        val up = GravitySensor.up
        if (projector.up !== up) projector.up = up
        invalidate()
    }

    /** Forgets everything shown. */
    fun clear() = show(emptyList(), emptyList(), null)

    override fun onDraw(canvas: Canvas) {
        super.onDraw(canvas)
        if (width == 0 || height == 0) return
        val scene = projector.project(trajectory, references, pose, width, height)

        val (ox, oy) = scene.origin
        val cross = 6 * density
        canvas.drawLine(ox - cross, oy, ox + cross, oy, axisPaint)
        canvas.drawLine(ox, oy - cross, ox, oy + cross, axisPaint)

        if (scene.pathSize > 1) {
            linePath.rewind()
            linePath.moveTo(scene.path[0], scene.path[1])
            for (i in 1 until scene.pathSize) linePath.lineTo(scene.path[2 * i], scene.path[2 * i + 1])
            canvas.drawPath(linePath, pathPaint)
        }
        for (r in scene.references) {
            canvas.drawCircle(r.x, r.y, (if (r.level >= 2) 5f else 3.5f) * density, if (r.level >= 2) l2Paint else l1Paint)
        }
        scene.marker?.let { m ->
            if (m.hasHeading) {
                val len = 14 * density
                val half = 6 * density
                val c = kotlin.math.cos(m.heading)
                val s = kotlin.math.sin(m.heading)
                markerPath.rewind()
                markerPath.moveTo(m.x + c * len, m.y + s * len)
                markerPath.lineTo(m.x - s * half, m.y + c * half)
                markerPath.lineTo(m.x + s * half, m.y - c * half)
                markerPath.close()
                canvas.drawPath(markerPath, markerPaint)
            } else {
                canvas.drawCircle(m.x, m.y, 6 * density, markerPaint)
            }
        }

        val bar = scene.scaleBar
        val x0 = 12 * density
        val y0 = height - 12 * density
        canvas.drawLine(x0, y0, x0 + bar.lengthPx, y0, axisPaint)
        canvas.drawText(bar.label, x0, y0 - 4 * density, textPaint)
        val label = if (plane == ProjectionPlane.XZ && projector.up != null) "top" else plane.name
        canvas.drawText(label, width - 40 * density, y0, textPaint)
    }
}
