package io.ecvo.shared

/**
 * When to lock the colour camera's auto-exposure and white balance: the tracker's
 * photometric terms assume a point keeps its brightness, which free-running exposure and
 * white balance break whenever the view changes. Locked once both report CONVERGED in a
 * capture result (`CONTROL_AE_STATE`, `CONTROL_AWB_STATE`), after at least [minFrames]
 * frames; a camera that reports no state (LEGACY) is locked after [minFrames]; one that
 * never converges is locked after [maxFrames] anyway, with a note. Not thread-safe: the
 * camera thread calls [onResult].
 */
class ExposureLock(private val minFrames: Int = 10, private val maxFrames: Int = 90) {
    private var frames = 0
    private var done = false

    /** What to do after a capture result. */
    enum class Action { WAIT, LOCK, LOCK_UNCONVERGED }

    init {
        require(minFrames in 1..maxFrames) { "need 1 <= minFrames ($minFrames) <= maxFrames ($maxFrames)" }
    }

    /** A capture result with these states (null: not reported); [Action.LOCK] or [Action.LOCK_UNCONVERGED] exactly once. */
    fun onResult(aeState: Int?, awbState: Int?): Action {
        if (done) return Action.WAIT
        frames++
        if (frames < minFrames) return Action.WAIT
        val aeOk = aeState == null || aeState == AE_STATE_CONVERGED || aeState == AE_STATE_FLASH_REQUIRED
        val awbOk = awbState == null || awbState == AWB_STATE_CONVERGED
        val action = when {
            aeOk && awbOk -> Action.LOCK
            frames >= maxFrames -> Action.LOCK_UNCONVERGED
            else -> return Action.WAIT
        }
        done = true
        return action
    }

    companion object {
        /** `CaptureResult.CONTROL_AE_STATE_CONVERGED`, `..._FLASH_REQUIRED` (converged, too dark without flash). */
        const val AE_STATE_CONVERGED: Int = 2
        const val AE_STATE_FLASH_REQUIRED: Int = 4

        /** `CaptureResult.CONTROL_AWB_STATE_CONVERGED`. */
        const val AWB_STATE_CONVERGED: Int = 2

        /** The note shown when the exposure was locked without converging. */
        const val UNCONVERGED_NOTE: String = "The colour camera's exposure did not settle in 3 s; it was locked as it was (tracking may suffer in this light)."
    }
}
