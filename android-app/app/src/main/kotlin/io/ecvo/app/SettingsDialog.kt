package io.ecvo.app

import android.app.Activity
import android.app.AlertDialog
import android.widget.Toast
import io.ecvo.shared.SettingsMenu

/**
 * The settings dialog: one row per setting ([SettingsMenu]); [keep] registers the dialog
 * with the activity so that a rotation reopens it.
 */
class SettingsDialog(private val activity: Activity, private val keep: (String, AlertDialog) -> Unit) {
    /** Shows the rows; tapping one moves it to its next value, stores the settings and shows them again. */
    fun show() {
        val s = SessionHolder.settings(activity)
        val rows = SettingsMenu.Row.entries
        val labels = rows.map { "${activity.getString(settingTitle(it))}: ${SettingsMenu.value(s, it)}" }.toTypedArray<CharSequence>()
        keep("settings", AlertDialog.Builder(activity)
            .setTitle(R.string.settings)
            .setItems(labels) { _, which ->
                val row = rows[which]
                SessionHolder.saveSettings(activity, SettingsMenu.step(s, row))
                if (row == SettingsMenu.Row.REPLAY_SPEED) SessionHolder.replay?.setSpeed(SessionHolder.settings(activity).replaySpeed)
                if (!row.appliesAtOnce) Toast.makeText(activity, R.string.settings_applies, Toast.LENGTH_SHORT).show()
                show()
            }
            .setNeutralButton(R.string.licences) { _, _ -> showLicences() }
            .setNegativeButton(R.string.close, null)
            .show())
    }

    /** The licence notices of the app, its native library's crates and the Kotlin library (res/raw/notices.txt). */
    private fun showLicences() {
        val text = activity.resources.openRawResource(R.raw.notices).use { String(it.readBytes(), Charsets.UTF_8) }
        AlertDialog.Builder(activity)
            .setTitle(R.string.licences)
            .setMessage(text)
            .setNegativeButton(R.string.close, null)
            .show()
    }

    private fun settingTitle(row: SettingsMenu.Row): Int = when (row) {
        SettingsMenu.Row.PRESET -> R.string.settings_preset
        SettingsMenu.Row.MODE -> R.string.settings_mode
        SettingsMenu.Row.CONFIDENCE -> R.string.settings_confidence
        SettingsMenu.Row.PREVIEW -> R.string.settings_preview
        SettingsMenu.Row.POINT_CLOUD -> R.string.settings_cloud
        SettingsMenu.Row.LIVE_CAMERAS -> R.string.settings_live_cameras
        SettingsMenu.Row.RESOLUTION -> R.string.settings_resolution
        SettingsMenu.Row.REPLAY_SPEED -> R.string.settings_speed
    }
}
