package io.ecvo.app

import android.app.Activity
import android.content.ActivityNotFoundException
import android.content.ContentValues
import android.content.Intent
import android.os.Build
import android.os.Environment
import android.provider.MediaStore
import android.widget.Toast
import io.ecvo.shared.ExportFiles
import io.ecvo.shared.ExportPlan
import io.ecvo.shared.SessionExport
import io.ecvo.shared.StreamMetadata
import io.ecvo.shared.TrackingSession
import java.io.File
import java.io.FileOutputStream
import java.io.IOException
import java.text.SimpleDateFormat
import java.util.Date
import java.util.Locale

/**
 * Exports a session and/or a recording as one zip, written on a worker thread straight
 * from the recording's folder (ExportFiles.write: no copy of the recording, its lists
 * snapshotted first, so a recording still being written exports as the stream it is at
 * that moment). Share… puts the zip in the app's cache and offers it in the share
 * sheet; Save to Downloads writes it into the phone's Downloads (MediaStore on Android
 * 10+, where no permission is needed; the app's own Download folder before).
 */
class Exporter(
    private val activity: Activity,
    /** Shows a sentence on the screen (UI thread). */
    private val notice: (String) -> Unit,
) {
    /** Where the export goes. */
    enum class Target { SHARE, DOWNLOADS }

    /**
     * Writes [plan] on a worker thread, then shares it or says where it was saved;
     * [session] is the session whose results it holds (when the plan asks for them),
     * [pointCloud] whether that session built a cloud, [metadata] what goes beside them
     * as `metadata.json`.
     */
    fun export(plan: ExportPlan, recordingName: String?, session: TrackingSession?, pointCloud: Boolean, metadata: StreamMetadata, target: Target) {
        Toast.makeText(activity, R.string.exporting, Toast.LENGTH_SHORT).show()
        val stamp = SimpleDateFormat("yyyyMMdd-HHmmss", Locale.ROOT).format(Date())
        val base = if (recordingName != null) "ecvo-recording-$recordingName" else "ecvo-$stamp"
        val app = activity.applicationContext
        val cache = activity.cacheDir
        val ui = android.os.Handler(android.os.Looper.getMainLooper())
        val write = { dir: File ->
            val t = if (plan.withSession) session?.tracker else null
            if (t != null) {
                // The tracker keeps the latest Tracker.TRAJECTORY_WINDOW poses: export those.
                val poses = t.trajectorySince(t.stats().trajectoryStart.toInt())
                SessionExport.write(dir, poses, t.references(), if (pointCloud) t.pointCloud(MAX_EXPORT_POINTS) else null)
                metadata.write(dir) // device, versions, settings, intrinsics, gravity
            }
            Unit
        }
        Thread(Runnable {
            try {
                when (target) {
                    Target.SHARE -> {
                        val zip = ExportFiles.pack(plan, ExportProvider.exportsDir(cache), base, write)
                        ui.post { share(zip) }
                    }
                    Target.DOWNLOADS -> {
                        val where = saveToDownloads(plan, base, cache, write)
                        ui.post { Toast.makeText(app, app.getString(R.string.saved_to, where), Toast.LENGTH_LONG).show() }
                    }
                }
            } catch (e: Exception) {
                ui.post { notice("Export failed: ${e.message ?: e.javaClass.simpleName}") }
            }
        }, "ecvo-export").start()
    }

    /** Writes the zip into Downloads; returns where, for the user. */
    private fun saveToDownloads(plan: ExportPlan, base: String, cache: File, write: (File) -> Unit): String {
        val name = "$base.zip"
        if (Build.VERSION.SDK_INT >= 29) {
            val resolver = activity.applicationContext.contentResolver
            val values = ContentValues()
            values.put(MediaStore.MediaColumns.DISPLAY_NAME, name)
            values.put(MediaStore.MediaColumns.MIME_TYPE, "application/zip")
            values.put(MediaStore.MediaColumns.RELATIVE_PATH, Environment.DIRECTORY_DOWNLOADS)
            values.put(MediaStore.MediaColumns.IS_PENDING, 1)
            val uri = resolver.insert(MediaStore.Downloads.EXTERNAL_CONTENT_URI, values) ?: throw IOException("Downloads refused a new file")
            try {
                val out = resolver.openOutputStream(uri) ?: throw IOException("cannot write $uri")
                out.use { ExportFiles.write(plan, it, base, cache, write) }
                val done = ContentValues()
                done.put(MediaStore.MediaColumns.IS_PENDING, 0)
                resolver.update(uri, done, null, null)
            } catch (e: Exception) {
                runCatching { resolver.delete(uri, null, null) }
                throw e
            }
            return "Downloads/$name"
        }
        // Before Android 10, the public Downloads folder needs a storage permission: the
        // app's own Download folder instead (reachable over USB).
        val dir = activity.applicationContext.getExternalFilesDir(Environment.DIRECTORY_DOWNLOADS) ?: throw IOException("no external storage")
        val zip = ExportFiles.uniqueZip(dir.also { it.mkdirs() }, base)
        try {
            FileOutputStream(zip).use { ExportFiles.write(plan, it, zip.name.removeSuffix(".zip"), cache, write) }
        } catch (e: Exception) {
            zip.delete()
            throw e
        }
        return zip.path
    }

    private fun share(zip: File) {
        val send = Intent(Intent.ACTION_SEND)
            .setType("application/zip")
            .putExtra(Intent.EXTRA_STREAM, ExportProvider.uriFor(zip))
            .addFlags(Intent.FLAG_GRANT_READ_URI_PERMISSION)
        try {
            activity.startActivity(Intent.createChooser(send, activity.getString(R.string.share_title)))
        } catch (e: ActivityNotFoundException) {
            notice("No app can receive the export; it is at ${zip.path}")
        }
    }

    companion object {
        private const val MAX_EXPORT_POINTS = 500_000
    }
}
