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
        // Not listed (API 30+), or no answer (before API 30): not guaranteed; no answer is still tried.
        assertFalse(LiveModePolicy.guaranteed("5", "1", listed))
        assertFalse(LiveModePolicy.guaranteed("5", "0", null))
        assertFalse(LiveModePolicy.guaranteed("5", "0", emptyList()))
        assertEquals(LiveMode.DEPTH_AND_COLOUR, LiveModePolicy.start("5", "0", null).mode)
    }

    @Test
    fun anyFailureOfThePairFallsBackToDepthAloneAndIsRemembered() {
        val both = LiveMode.DEPTH_AND_COLOUR
        assertEquals(9, CameraFailure.entries.size)
        for (f in CameraFailure.entries) {
            // The colour camera failing in any way leaves depth running.
            assertEquals(f.name, FailureAction.CONTINUE_DEPTH_ONLY, LiveModePolicy.onFailure(both, LiveCamera.COLOUR, f))
            // The depth camera failing in any way (the opens race, so the colour open may
            // have pushed it out): reopened alone, never a failed session.
            assertEquals(f.name, FailureAction.RESTART_DEPTH_ONLY, LiveModePolicy.onFailure(both, LiveCamera.DEPTH, f))
            for (c in LiveCamera.entries) assertTrue(LiveModePolicy.remembers(both, LiveModePolicy.onFailure(both, c, f)))
            // Depth alone already: a depth failure ends the session (no restart loop), a late colour one changes nothing.
            assertEquals(FailureAction.FAIL, LiveModePolicy.onFailure(LiveMode.DEPTH_ONLY, LiveCamera.DEPTH, f))
            assertEquals(FailureAction.CONTINUE_DEPTH_ONLY, LiveModePolicy.onFailure(LiveMode.DEPTH_ONLY, LiveCamera.COLOUR, f))
            assertFalse(LiveModePolicy.remembers(LiveMode.DEPTH_ONLY, LiveModePolicy.onFailure(LiveMode.DEPTH_ONLY, LiveCamera.DEPTH, f)))
        }
        // Camera2's onError codes, 1..5, and an unknown one.
        assertEquals(
            listOf(CameraFailure.IN_USE, CameraFailure.MAX_CAMERAS_IN_USE, CameraFailure.DISABLED, CameraFailure.DEVICE, CameraFailure.SERVICE, CameraFailure.OTHER),
            (1..6).map { CameraFailure.fromErrorCode(it) },
        )
    }

    @Test
    fun theConcurrencyAnswerTheSettingAndTheRememberedFallbackChooseDepthAlone() {
        // API 30+: a phone listing combinations without this pair is taken at its word.
        val listed = listOf(setOf("0", "1"), setOf("1", "2"))
        assertTrue(LiveModePolicy.refused("5", "0", listed))
        val refused = LiveModePolicy.start("5", "0", listed)
        assertEquals(LiveMode.DEPTH_ONLY, refused.mode)
        assertTrue(refused.note!!, refused.note.contains("at once"))
        // An empty list (many phones) or no answer (before API 30) is not a refusal.
        assertFalse(LiveModePolicy.refused("5", "0", emptyList()))
        assertFalse(LiveModePolicy.refused("5", "0", null))
        // The user's setting wins over everything but a missing colour camera.
        val set = LiveModePolicy.start("5", "0", listOf(setOf("0", "5")), setting = LiveCameras.DEPTH_ONLY)
        assertEquals(LiveMode.DEPTH_ONLY, set.mode)
        assertTrue(set.note!!, set.note.contains("depth only"))
        // A pair that fell back before starts depth-only, unless the phone guarantees it.
        assertEquals(LiveMode.DEPTH_ONLY, LiveModePolicy.start("5", "0", emptyList(), remembered = true).mode)
        assertEquals(LiveMode.DEPTH_ONLY, LiveModePolicy.start("5", "0", null, remembered = true).mode)
        assertEquals(LiveMode.DEPTH_AND_COLOUR, LiveModePolicy.start("5", "0", null, remembered = false).mode)
    }

    @Test
    fun theRememberedFallbackIsKeptPerPairAcrossRestartsAndForgottenByAuto() {
        val key = LiveFallbackMemory.key("5", "0")
        val s = AppSettings().rememberDepthOnly(key).rememberDepthOnly(LiveFallbackMemory.key("6", "1"))
        val back = AppSettings.fromMap(s.toMap())
        assertEquals(setOf("5+0", "6+1"), back.depthOnlyPairs)
        assertTrue(key in back.depthOnlyPairs)
        assertFalse(LiveFallbackMemory.key("5", "2") in back.depthOnlyPairs)
        assertEquals(LiveMode.DEPTH_ONLY, LiveModePolicy.start("5", "0", null, back.liveCameras, key in back.depthOnlyPairs).mode)
        // Settings → Live cameras: depth only keeps them; auto again forgets them (tries the pair again).
        val depthOnly = back.withLiveCameras(LiveCameras.DEPTH_ONLY)
        assertEquals(LiveCameras.DEPTH_ONLY, AppSettings.fromMap(depthOnly.toMap()).liveCameras)
        assertEquals(2, depthOnly.depthOnlyPairs.size)
        assertTrue(depthOnly.withLiveCameras(LiveCameras.AUTO).depthOnlyPairs.isEmpty())
        assertEquals(emptySet<String>(), LiveFallbackMemory.decode(" , ,"))
        assertEquals(emptySet<String>(), LiveFallbackMemory.decode(null))
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

    @Test
    fun exposureAndWhiteBalanceAreLockedOnceConvergedOrAtTheTimeout() {
        val converging = ExposureLock(minFrames = 3, maxFrames = 10)
        // Searching (1) for 5 frames, then converged (2): locked at the first converged result.
        val actions = (1..8).map { i -> converging.onResult(if (i <= 5) 1 else 2, 2) }
        assertTrue(actions.take(5).all { it == ExposureLock.Action.WAIT })
        assertEquals(ExposureLock.Action.LOCK, actions[5])
        assertTrue(actions.drop(6).all { it == ExposureLock.Action.WAIT }) // once
        // White balance still searching keeps it unlocked.
        val awb = ExposureLock(minFrames = 1, maxFrames = 10)
        assertEquals(ExposureLock.Action.WAIT, awb.onResult(2, 1))
        assertEquals(ExposureLock.Action.LOCK, awb.onResult(2, 2))
        // Never converging: locked at the timeout, with the note.
        val never = ExposureLock(minFrames = 3, maxFrames = 10)
        val n = (1..12).map { never.onResult(1, 1) }
        assertEquals(ExposureLock.Action.LOCK_UNCONVERGED, n[9])
        assertEquals(1, n.count { it != ExposureLock.Action.WAIT })
        // A camera reporting no states (LEGACY): locked after minFrames.
        val legacy = ExposureLock(minFrames = 3, maxFrames = 10)
        assertEquals(listOf(ExposureLock.Action.WAIT, ExposureLock.Action.WAIT, ExposureLock.Action.LOCK), (1..3).map { legacy.onResult(null, null) })
    }
}
