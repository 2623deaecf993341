package io.ecvo.shared

import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNotNull
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test
import kotlin.math.sqrt

class PosePolicyTest {
    private val s = (sqrt(0.5)).toFloat()
    private val identity = floatArrayOf(0f, 0f, 0f, 1f)

    /** A back camera's pose relative to the gyroscope: 180° about x (Android sensor axes to camera axes). */
    private val gyroBack = floatArrayOf(1f, 0f, 0f, 0f)

    @Test
    fun posesWithTheSameReferenceAreComposed() {
        val d = CameraPose(gyroBack, floatArrayOf(0.01f, 0f, 0f), PoseReference.GYROSCOPE)
        val c = CameraPose(gyroBack, floatArrayOf(0.03f, 0f, 0f), PoseReference.GYROSCOPE)
        val p = PosePolicy.decide(d, c, colourIsPrimary = true)
        assertTrue(p.fromLensPoses)
        assertNull(p.note)
        // Same orientation: identity rotation, and the 2 cm baseline shows in x.
        assertEquals(1.0, p.depthToColour.rotation[0], 1e-6)
        assertEquals(1.0, p.depthToColour.rotation[8], 1e-6)
        assertEquals(0.02, kotlin.math.abs(p.depthToColour.translation[0]), 1e-6)
    }

    @Test
    fun aColourCameraWithoutAPoseIsNotTakenAsIdentityWhenThatTurnsTheDepthCameraAround() {
        val d = CameraPose(gyroBack, floatArrayOf(0.01f, 0f, 0f), PoseReference.GYROSCOPE)
        val c = CameraPose(null, null, PoseReference.GYROSCOPE)
        // The old code composed with identity: the depth axis would point backwards.
        val naive = LensPose.depthToColour(d.rotation, d.translation, identity, FloatArray(3))
        assertTrue(naive.rotation[8] < -0.99)
        val p = PosePolicy.decide(d, c, colourIsPrimary = true)
        assertFalse(p.fromLensPoses)
        assertEquals(RigidTransform.IDENTITY.rotation.toList(), p.depthToColour.rotation.toList())
        assertNotNull(p.note)
        assertTrue(p.note!!, p.note.contains("colour camera publishes no lens pose"))
    }

    @Test
    fun theColourCameraCanBeThePrimaryReference() {
        // Depth 1 cm beside the primary (colour) camera, same orientation.
        val d = CameraPose(identity, floatArrayOf(-0.01f, 0f, 0f), PoseReference.PRIMARY_CAMERA)
        val p = PosePolicy.decide(d, CameraPose(null, null, PoseReference.PRIMARY_CAMERA), colourIsPrimary = true)
        assertTrue(p.fromLensPoses)
        assertEquals(0.01, kotlin.math.abs(p.depthToColour.translation[0]), 1e-6)
        // Not the primary camera: no reference to compose with.
        assertFalse(PosePolicy.decide(d, CameraPose(null, null, PoseReference.PRIMARY_CAMERA), colourIsPrimary = false).fromLensPoses)
    }

    @Test
    fun differentOrUndefinedReferencesAndTurnedPosesFallBack() {
        val d = CameraPose(identity, FloatArray(3), PoseReference.GYROSCOPE)
        val c = CameraPose(identity, FloatArray(3), PoseReference.PRIMARY_CAMERA)
        assertTrue(PosePolicy.decide(d, c, true).note!!.contains("different references"))
        val u = CameraPose(identity, FloatArray(3), PoseReference.UNDEFINED)
        assertFalse(PosePolicy.decide(u, u, true).fromLensPoses)
        // 90° about y between the cameras: not two cameras facing the same way.
        val turned = CameraPose(floatArrayOf(0f, s, 0f, s), FloatArray(3), PoseReference.GYROSCOPE)
        val t = PosePolicy.decide(turned, d, true)
        assertFalse(t.fromLensPoses)
        assertTrue(t.note!!, t.note.contains("90°"))
        assertFalse(PosePolicy.decide(CameraPose(null, null, PoseReference.GYROSCOPE), d, true).fromLensPoses)
        assertEquals(PoseReference.PRIMARY_CAMERA, PoseReference.fromCode(null))
        assertEquals(PoseReference.UNDEFINED, PoseReference.fromCode(42))
        assertEquals(PoseReference.GYROSCOPE, PoseReference.fromCode(1))
    }

    @Test
    fun theFallbackTurnsTheImagesBySensorOrientation() {
        val none = CameraPose(null, null, PoseReference.PRIMARY_CAMERA)
        // Both mounted at 90°: still the identity, and the note says "axes".
        val same = PosePolicy.decide(none, none, colourIsPrimary = true, depthOrientation = 90, colourOrientation = 90)
        assertEquals(RigidTransform.IDENTITY.rotation.toList(), same.depthToColour.rotation.toList())
        assertTrue(same.note!!, same.note.contains("centre and axes"))
        // Depth sensor at 90°, colour at 0°: the depth image's right (+x) is the colour image's down (+y).
        val p = PosePolicy.decide(none, none, colourIsPrimary = true, depthOrientation = 90, colourOrientation = 0)
        assertFalse(p.fromLensPoses)
        val r = p.depthToColour.rotation
        val right = doubleArrayOf(r[0], r[3], r[6]) // R * (1, 0, 0)
        assertEquals(listOf(0.0, 1.0, 0.0), right.toList())
        assertEquals(1.0, r[8], 0.0) // the optical axis is kept
        assertTrue(p.note!!, p.note.contains("turned 90° apart"))
        // 270° against 90°: half a turn (an upside-down mount).
        val half = PosePolicy.orientationFallback(270, 90).rotation
        assertEquals(listOf(-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0), half.toList())
        // Registration with a half turn maps a depth pixel's point to the point mirrored
        // through the principal point in the colour image.
        val cam = CameraIntrinsics(40, 30, 30.0, 30.0, 19.5, 14.5)
        val reg = IntensityRegistration(cam, cam, PosePolicy.orientationFallback(180, 0))
        val depth = ShortArray(40 * 30) { 1000 }
        val gray = ByteArray(40 * 30) { i -> (i % 40 * 6).toByte() } // brightness grows to the right
        val out = reg.register(depth, GrayPlane(gray, 40, 30))
        val row = 15 * 40
        assertTrue("left of the depth image sees the bright right of the colour image", (out[row + 2].toInt() and 0xFF) > (out[row + 37].toInt() and 0xFF))
    }
}
