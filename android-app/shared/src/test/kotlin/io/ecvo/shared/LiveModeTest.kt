package io.ecvo.shared

import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNotNull
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** The depth-only fallback of live tracking. */
class LiveModeTest {
    @Test
    fun noColourCameraStartsDepthOnlyWithANote() {
        val d = LiveModePolicy.start("5", null, listOf(setOf("0", "1")))
        assertEquals(LiveMode.DEPTH_ONLY, d.mode)
        assertNotNull(d.note)
        assertTrue(d.note!!, d.note.contains("depth alone"))
    }

    @Test
    fun aGuaranteedOrUnknownPairStartsWithBoth() {
        val listed = listOf(setOf("0", "5"), setOf("1", "2"))
        assertTrue(LiveModePolicy.guaranteed("5", "0", listed))
        assertEquals(LiveMode.DEPTH_AND_COLOUR, LiveModePolicy.start("5", "0", listed).mode)
        assertNull(LiveModePolicy.start("5", "0", listed).note)
        // Not listed (API 30+), or no answer (before API 30): not guaranteed, still tried.
        assertFalse(LiveModePolicy.guaranteed("5", "1", listed))
        assertFalse(LiveModePolicy.guaranteed("5", "0", null))
        assertFalse(LiveModePolicy.guaranteed("5", "0", emptyList()))
        assertEquals(LiveMode.DEPTH_AND_COLOUR, LiveModePolicy.start("5", "1", listed).mode)
        assertEquals(LiveMode.DEPTH_AND_COLOUR, LiveModePolicy.start("5", "0", null).mode)
    }

    @Test
    fun failuresWhileBothAreOpenFallBackToDepthAlone() {
        val both = LiveMode.DEPTH_AND_COLOUR
        for (f in CameraFailure.entries) {
            // The colour camera failing in any way leaves depth running.
            assertEquals(FailureAction.CONTINUE_DEPTH_ONLY, LiveModePolicy.onFailure(both, LiveCamera.COLOUR, f))
        }
        // The depth camera taken away by the colour one: reopened alone.
        assertEquals(FailureAction.RESTART_DEPTH_ONLY, LiveModePolicy.onFailure(both, LiveCamera.DEPTH, CameraFailure.IN_USE))
        assertEquals(FailureAction.RESTART_DEPTH_ONLY, LiveModePolicy.onFailure(both, LiveCamera.DEPTH, CameraFailure.DISCONNECTED))
        assertEquals(FailureAction.FAIL, LiveModePolicy.onFailure(both, LiveCamera.DEPTH, CameraFailure.OTHER))
        // Depth alone already: a depth failure ends the session (no restart loop).
        for (f in CameraFailure.entries) assertEquals(FailureAction.FAIL, LiveModePolicy.onFailure(LiveMode.DEPTH_ONLY, LiveCamera.DEPTH, f))
    }

    @Test
    fun aColourStreamThatNeverDeliversIsGivenUpOnce() {
        val w = ColourWatch(depthFrames = 3)
        assertFalse(w.onDepth()); assertFalse(w.onDepth())
        assertTrue(w.onDepth())
        assertFalse(w.onDepth())
        val ok = ColourWatch(depthFrames = 3)
        ok.onDepth(); ok.onColour()
        repeat(10) { assertFalse(ok.onDepth()) }
    }

    @Test
    fun theModeIsShownInTheStatus() {
        val p = TrackingPresenter()
        p.onStarted(FrameSource.LIVE, 0)
        p.onLiveMode(LiveMode.DEPTH_ONLY)
        assertEquals("depth only", p.status.mode)
        p.onStarted(FrameSource.REPLAY, 0)
        assertEquals("", p.status.mode)
    }
}
