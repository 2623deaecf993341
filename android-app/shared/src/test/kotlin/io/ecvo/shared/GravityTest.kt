package io.ecvo.shared

import io.ecvo.TimedPose
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** The gravity-aligned top view. */
class GravityTest {
    private fun near(expected: DoubleArray, actual: DoubleArray?) = assertArrayEquals(expected, actual!!, 1e-9)

    @Test
    fun upInTheCameraFrameFollowsSensorOrientation() {
        // Phone upright in portrait (accelerometer +g along device y), back camera mounted at 90°
        // (the usual case): the image's x axis points down the phone, so up is the camera's -x.
        near(doubleArrayOf(-1.0, 0.0, 0.0), GravityAlignment.upInCamera(0.0, 9.81, 0.0, 90, backFacing = true))
        // Sensor orientation 0: up is the image's up, -y.
        near(doubleArrayOf(0.0, -1.0, 0.0), GravityAlignment.upInCamera(0.0, 9.81, 0.0, 0, backFacing = true))
        // Phone lying on a table, screen up: the back camera looks down, so up is -z.
        near(doubleArrayOf(0.0, 0.0, -1.0), GravityAlignment.upInCamera(0.0, 0.0, 9.81, 90, backFacing = true))
        // Landscape, the phone's left side down (the reading points up: device +x): the
        // image is upright, up is its -y; turned the other way, +y.
        near(doubleArrayOf(0.0, -1.0, 0.0), GravityAlignment.upInCamera(9.81, 0.0, 0.0, 90, backFacing = true))
        near(doubleArrayOf(0.0, 1.0, 0.0), GravityAlignment.upInCamera(-9.81, 0.0, 0.0, 90, backFacing = true))
        // Front camera at 270° (the usual case), phone upright: its raw image is turned the
        // other way, so its x axis points up the phone.
        near(doubleArrayOf(1.0, 0.0, 0.0), GravityAlignment.upInCamera(0.0, 9.81, 0.0, 270, backFacing = false))
        assertNull(GravityAlignment.upInCamera(0.0, 0.1, 0.0, 90, true))
    }

    private fun pose(x: Double, y: Double, z: Double) = TimedPose(0.0, x, y, z, 0.0, 0.0, 0.0, 1.0)

    @Test
    fun theTopViewOfAnUprightPhoneShowsItsWalkNotItsHeight() {
        val up = GravityAlignment.upInCamera(0.0, 9.81, 0.0, 90, backFacing = true)!! // (-1, 0, 0)
        val plane = GravityPlane(up)
        // A step forward (camera z) is up on screen; a step to the user's right is the
        // camera's -y (image x points down the phone, so image y points to the user's left).
        assertEquals(0.0 to 1.0, plane.project(0.0, 0.0, 1.0))
        assertEquals(1.0 to 0.0, plane.project(0.0, -1.0, 0.0))
        // Raising the phone (world up = camera -x) does not move it in the top view.
        val (r, f) = plane.project(-1.0, 0.0, 0.0)
        assertEquals(0.0, r, 1e-12); assertEquals(0.0, f, 1e-12)

        // The projector: a walk 1 m forward then 1 m right, lifting the phone by 0.5 m on the way.
        val walk = listOf(pose(0.0, 0.0, 0.0), pose(-0.25, 0.0, 0.5), pose(-0.5, 0.0, 1.0), pose(-0.5, -1.0, 1.0))
        val withGravity = TrajectoryProjector(up = up).project(walk, emptyList(), null, 400, 400)
        val flat = TrajectoryProjector().project(walk, emptyList(), null, 400, 400)
        fun extent(path: FloatArray, axis: Int) = (0 until path.size / 2).map { path[2 * it + axis] }.let { it.max() - it.min() }
        // Aligned: 1 m by 1 m, a square's extents; the first camera's x-z plane sees 0.5 m by 1 m.
        val t = withGravity.transform.scale
        assertEquals(1.0, extent(withGravity.path, 0) / t, 1e-5)
        assertEquals(1.0, extent(withGravity.path, 1) / t, 1e-5)
        assertEquals(0.5, extent(flat.path, 0) / flat.transform.scale, 1e-5)
        // The last step (to the right) is drawn to the right.
        assertTrue(withGravity.path[6] > withGravity.path[4])
        // Other planes are not changed by gravity.
        val side = TrajectoryProjector(plane = ProjectionPlane.YZ, up = up).project(walk, emptyList(), null, 400, 400)
        val sideFlat = TrajectoryProjector(plane = ProjectionPlane.YZ).project(walk, emptyList(), null, 400, 400)
        assertArrayEquals(sideFlat.path, side.path, 1e-6f)
    }

    @Test
    fun aLevelCameraKeepsTheClassicTopView() {
        val up = GravityAlignment.upInCamera(9.81, 0.0, 0.0, 90, backFacing = true)!! // landscape, camera level
        near(doubleArrayOf(0.0, -1.0, 0.0), up)
        val walk = listOf(pose(0.0, 0.0, 0.0), pose(0.3, 0.1, 0.7))
        val a = TrajectoryProjector(up = up).project(walk, emptyList(), null, 300, 200)
        val b = TrajectoryProjector().project(walk, emptyList(), null, 300, 200)
        assertArrayEquals(b.path, a.path, 1e-4f)
    }
}
