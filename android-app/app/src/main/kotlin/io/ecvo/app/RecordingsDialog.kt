package io.ecvo.app

import android.app.Activity
import android.app.AlertDialog
import android.os.Handler
import android.os.Looper
import android.content.ActivityNotFoundException
import android.content.Intent
import android.net.Uri
import android.widget.Toast
import io.ecvo.shared.FrameSource
import io.ecvo.shared.RecordingEntry
import io.ecvo.shared.Recordings
import io.ecvo.shared.StreamImport
import java.io.File
import java.io.IOException
import java.text.SimpleDateFormat
import java.util.Date
import java.util.Locale

/**
 * The recordings dialogs (the list, one recording's actions, the delete confirmation) for
 * the recordings folder [root]; [keep] registers each dialog with the activity so that a
 * rotation reopens it ([reopen]). Folders are read and deleted on worker threads.
 */
class RecordingsDialog(
    private val activity: Activity,
    private val root: File,
    private val keep: (String, AlertDialog) -> Unit,
    /** Replays a recording. */
    private val replay: (RecordingEntry) -> Unit,
    /** Exports a recording to a target. */
    private val export: (RecordingEntry, Exporter.Target) -> Unit,
) {
    private val ui = Handler(Looper.getMainLooper())
    private val controller get() = SessionHolder.controller

    /** Lists the recordings on a worker thread (it reads every folder), then shows them. */
    fun show() {
                Thread(Runnable {
            val list = try {
                Recordings.list(root)
            } catch (e: Exception) {
                emptyList()
            }
            ui.post { if (!activity.isFinishing && !activity.isDestroyed) showRecordingList(list) }
        }, "ecvo-recordings").start()
    }

    private fun showRecordingList(list: List<RecordingEntry>) {
        if (list.isEmpty()) {
            keep("recordings", AlertDialog.Builder(activity)
                .setTitle(R.string.recordings_title)
                .setMessage(R.string.no_recordings)
                .setNeutralButton(R.string.import_stream) { _, _ -> pickZip() }
                .setNegativeButton(R.string.close, null)
                .show())
            return
        }
        val labels = list.map { String.format(Locale.ROOT, "%s · %d frames · %.1f MB", it.name, it.frames, it.bytes / 1e6) }.toTypedArray<CharSequence>()
        keep("recordings", AlertDialog.Builder(activity)
            .setTitle(R.string.recordings_title)
            .setItems(labels) { _, which -> showRecordingActions(list[which]) }
            .setNeutralButton(R.string.import_stream) { _, _ -> pickZip() }
            .setNegativeButton(R.string.close, null)
            .show())
    }

    /** Replay, export or delete one recording. */
    private fun showRecordingActions(r: RecordingEntry) {
        val actions = arrayOf<CharSequence>(
            activity.getString(R.string.recording_replay), activity.getString(R.string.recording_export), activity.getString(R.string.export_downloads), activity.getString(R.string.recording_delete),
        )
        keep("recording:" + r.name, AlertDialog.Builder(activity)
            .setTitle(r.name)
            .setItems(actions) { _, which ->
                when (which) {
                    0 -> replay(r)
                    1, 2 -> export(r, if (which == 1) Exporter.Target.SHARE else Exporter.Target.DOWNLOADS)
                    else -> confirmDelete(r)
                }
            }
            .setNegativeButton(R.string.close, null)
            .show())
    }

    private fun confirmDelete(r: RecordingEntry) {
        keep("delete:" + r.name, AlertDialog.Builder(activity)
            .setTitle(R.string.recording_delete)
            .setMessage(activity.getString(R.string.recording_delete_confirm, r.name, r.frames))
            .setPositiveButton(R.string.recording_delete) { _, _ ->
                // Not the folder being recorded into, nor the one a running replay reads.
                val inUse = if (controller.presenter.status.recording || controller.running == FrameSource.REPLAY) SessionHolder.streams.stream else null
                                Thread(Runnable {
                    val ok = Recordings.delete(root, r.dir, inUse)
                    ui.post {
                        if (ok) SessionHolder.streams.onDeleted(r.dir)
                        Toast.makeText(activity, if (ok) activity.getString(R.string.recording_deleted, r.name) else activity.getString(R.string.recording_not_deleted, r.name), Toast.LENGTH_LONG).show()
                    }
                }, "ecvo-delete").start()
            }
            .setNegativeButton(R.string.close, null)
            .show())
    }

    /** Asks the system's file picker for a zip (an export of this app, or any zip of a TUM-layout stream). */
    private fun pickZip() {
        val pick = Intent(Intent.ACTION_OPEN_DOCUMENT).addCategory(Intent.CATEGORY_OPENABLE).setType("application/zip")
        try {
            activity.startActivityForResult(pick, REQUEST_IMPORT)
        } catch (e: ActivityNotFoundException) {
            Toast.makeText(activity, e.message ?: "No file picker", Toast.LENGTH_LONG).show()
        }
    }

    /**
     * The activity's result for [REQUEST_IMPORT]: unpacks the chosen zip into the recordings
     * folder on a worker thread ([StreamImport]), then lists the recordings again.
     */
    fun onImportPicked(uri: Uri) {
        val app = activity.applicationContext
        val name = "import-" + SimpleDateFormat("yyyyMMdd-HHmmss", Locale.ROOT).format(Date())
        Toast.makeText(activity, R.string.importing, Toast.LENGTH_SHORT).show()
        Thread(Runnable {
            val text = try {
                val input = app.contentResolver.openInputStream(uri) ?: throw IOException("cannot open $uri")
                val dir = input.use { StreamImport.fromZip(it, root, name) }
                app.getString(R.string.imported, dir.name)
            } catch (e: Exception) {
                app.getString(R.string.import_failed, e.message ?: e.javaClass.simpleName)
            }
            ui.post {
                Toast.makeText(app, text, Toast.LENGTH_LONG).show()
                if (!activity.isFinishing && !activity.isDestroyed) show()
            }
        }, "ecvo-import").start()
    }

    /** Reopens a recording's actions or its delete confirmation after a rotation ([kind]: "recording:NAME" or "delete:NAME"). */
    fun reopen(kind: String) {
        val name = kind.substringAfter(':')
        Thread(Runnable {
            val r = try {
                Recordings.list(root).firstOrNull { it.name == name }
            } catch (e: Exception) {
                null
            }
            ui.post {
                if (r != null && !activity.isFinishing && !activity.isDestroyed) {
                    if (kind.startsWith("delete:")) confirmDelete(r) else showRecordingActions(r)
                }
            }
        }, "ecvo-recordings").start()
    }

    companion object {
        /** The request code of the file picker (MainActivity.onActivityResult forwards it). */
        const val REQUEST_IMPORT: Int = 7
    }
}
