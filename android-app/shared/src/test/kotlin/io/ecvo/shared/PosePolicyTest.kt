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
}
