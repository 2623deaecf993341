package io.ecvo.shared

import io.ecvo.ReferenceFrame
import io.ecvo.TimedPose
import kotlin.math.PI
import kotlin.math.sqrt
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNotNull
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

class ProjectionTest {
    private fun pose(t: Double, x: Double, y: Double, z: Double) = TimedPose(t, x, y, z, 0.0, 0.0, 0.0, 1.0)

    @Test
    fun planesPickAxesAndSigns() {
        assertEquals(1.0 to 3.0, ProjectionPlane.XZ.project(1.0, 2.0, 3.0))
        assertEquals(1.0 to -2.0, ProjectionPlane.XY.project(1.0, 2.0, 3.0))
        assertEquals(3.0 to -2.0, ProjectionPlane.YZ.project(1.0, 2.0, 3.0))
    }

    @Test
    fun fitPreservesAspectAndKeepsMargins() {
        // A path 2 m wide (x) and 1 m deep (z) in a 400x800 view with 20 px margins.
        val traj = listOf(pose(0.0, 0.0, 0.0, 0.0), pose(1.0, 2.0, 0.5, 1.0), pose(2.0, -0.0, -0.3, 0.5))
        val s = TrajectoryProjector(ProjectionPlane.XZ, marginPx = 20.0).project(traj, emptyList(), null, 400, 800)
        assertEquals(180.0, s.transform.scale, 1e-9) // (400 - 40) / 2 m
        // x: 0..2 m spans exactly the free width; centred vertically.
        assertEquals(20f, s.path[0], 1e-4f)
        assertEquals(380f, s.path[2], 1e-4f)
        // Forward (z) is up: the z = 1 m point is 180 px above z = 0.
        assertEquals(s.path[1] - 180f, s.path[3], 1e-4f)
        assertEquals(400f, (s.path[1] + s.path[3]) / 2, 1e-4f) // z range centred in the 800 px height
        assertEquals(s.path[0], s.origin.first, 0f)
        for (i in 0 until s.pathSize) {
            assertTrue(s.path[2 * i] in 20f - 1e-3f..380f + 1e-3f)
            assertTrue(s.path[2 * i + 1] in 20f..780f)
        }
        assertNull(s.marker)
    }

    @Test
    fun shortTrajectoriesAreNotBlownUp() {
        val traj = listOf(pose(0.0, 0.0, 0.0, 0.0), pose(1.0, 0.01, 0.0, 0.0))
        val s = TrajectoryProjector(marginPx = 0.0, minExtentM = 0.5).project(traj, emptyList(), null, 500, 500)
        assertEquals(1000.0, s.transform.scale, 1e-9) // 500 px for 0.5 m
        // Empty trajectory: the origin in the middle.
        val e = TrajectoryProjector().project(emptyList(), emptyList(), null, 300, 200)
        assertEquals(150f to 100f, e.origin)
        assertEquals(0, e.pathSize)
    }

    @Test
    fun markerHeadingAndReferences() {
        val identity = pose(0.0, 0.0, 0.0, 0.0).toMatrix()
        val projector = TrajectoryProjector(ProjectionPlane.XZ, marginPx = 10.0)
        // Looking forward (+z) in the top view: up on screen.
        val m = projector.project(emptyList(), emptyList(), identity, 200, 200).marker
        assertNotNull(m)
        assertTrue(m!!.hasHeading)
        assertEquals(-PI / 2, m.heading.toDouble(), 1e-6)
        // Turned 90 degrees about y: looking along +x, to the right.
        val h = sqrt(0.5)
        val yawed = TimedPose(0.0, 1.0, 0.0, 2.0, 0.0, h, 0.0, h).toMatrix()
        val s = projector.project(emptyList(), emptyList(), yawed, 200, 200)
        val mk = s.marker!!
        assertEquals(0.0, mk.heading.toDouble(), 1e-6)
        // The current pose is part of the fit.
        assertTrue(mk.x in 10f..190f && mk.y in 10f..190f)
        // In the front view the camera looks along the normal: no heading.
        assertFalse(TrajectoryProjector(ProjectionPlane.XY).project(emptyList(), emptyList(), identity, 200, 200).marker!!.hasHeading)
        // References keep their level and land on the path's pixels.
        val traj = listOf(pose(0.0, 0.0, 0.0, 0.0), pose(1.0, 0.5, 0.0, 0.5), pose(2.0, 1.0, 0.0, 0.0))
        val refs = listOf(ReferenceFrame(traj[1], 1), ReferenceFrame(traj[2], 2))
        val sc = projector.project(traj, refs, null, 300, 300)
        assertEquals(listOf(1, 2), sc.references.map { it.level })
        assertEquals(sc.path[2], sc.references[0].x, 1e-4f)
        assertEquals(sc.path[5], sc.references[1].y, 1e-4f)
    }

    @Test
    fun scaleBarsUseOneTwoFive() {
        assertEquals(1.0, TrajectoryProjector.scaleBar(100.0, 150.0).metres, 0.0)
        assertEquals(0.5, TrajectoryProjector.scaleBar(100.0, 99.0).metres, 0.0)
        assertEquals(0.2, TrajectoryProjector.scaleBar(100.0, 30.0).metres, 0.0)
        assertEquals(0.1, TrajectoryProjector.scaleBar(100.0, 10.0).metres, 0.0)
        assertEquals(5.0, TrajectoryProjector.scaleBar(10.0, 60.0).metres, 0.0)
        assertEquals(20f, TrajectoryProjector.scaleBar(100.0, 30.0).lengthPx, 1e-4f)
        assertEquals("20 cm", TrajectoryProjector.scaleBar(100.0, 30.0).label)
        assertEquals("2 m", TrajectoryProjector.scaleBar(10.0, 25.0).label)
    }
}
