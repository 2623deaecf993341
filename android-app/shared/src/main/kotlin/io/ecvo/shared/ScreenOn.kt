package io.ecvo.shared

/**
 * When to change the window's `FLAG_KEEP_SCREEN_ON`: the screen stays on while live
 * tracking runs (hands off), and only a change touches the window, since setting a
 * window flag makes it lay out again (the screen polls 20 times a second). One per
 * window (activity); not thread-safe: call it from the UI thread.
 */
class ScreenOnSwitch {
    private var on: Boolean? = null

    /** The flag to set for a screen that should be kept on if [keepOn], or null when it already is set so. */
    fun update(keepOn: Boolean): Boolean? {
        if (on == keepOn) return null
        on = keepOn
        return keepOn
    }
}
