package io.ecvo.app

import android.content.ContentProvider
import android.content.ContentValues
import android.database.Cursor
import android.database.MatrixCursor
import android.net.Uri
import android.os.ParcelFileDescriptor
import android.provider.OpenableColumns
import java.io.File
import java.io.FileNotFoundException

/**
 * Serves the app's exported zips (`cache/exports/<name>.zip`: a session, or any recording
 * of any run of the app, zipped by `ExportFiles.pack`) read-only to the app the user picks
 * in the share sheet, which gets a one-time read grant. This is how recordings leave the
 * phone on Android 11+, where no other app (nor the system file picker) reads
 * `Android/data/io.ecvo.app`. A platform
 * ContentProvider in a few lines instead of AndroidX's FileProvider (the app uses no
 * AndroidX).
 */
class ExportProvider : ContentProvider() {
    private fun file(uri: Uri): File {
        val ctx = context ?: throw FileNotFoundException("no context")
        val name = uri.lastPathSegment ?: throw FileNotFoundException("$uri")
        val dir = exportsDir(ctx.cacheDir)
        val f = File(dir, name)
        // Only plain names inside the exports folder.
        if (name.contains('/') || f.parentFile != dir || !f.isFile) throw FileNotFoundException("$uri")
        return f
    }

    override fun onCreate(): Boolean = true

    override fun openFile(uri: Uri, mode: String): ParcelFileDescriptor {
        if (mode != "r") throw SecurityException("exports are read-only")
        return ParcelFileDescriptor.open(file(uri), ParcelFileDescriptor.MODE_READ_ONLY)
    }

    override fun query(uri: Uri, projection: Array<String>?, selection: String?, selectionArgs: Array<String>?, sortOrder: String?): Cursor {
        val f = file(uri)
        val cols = projection ?: arrayOf(OpenableColumns.DISPLAY_NAME, OpenableColumns.SIZE)
        val c = MatrixCursor(cols, 1)
        c.addRow(cols.map<String, Any?> { col -> if (col == OpenableColumns.SIZE) f.length() else if (col == OpenableColumns.DISPLAY_NAME) f.name else null }.toTypedArray())
        return c
    }

    override fun getType(uri: Uri): String = "application/zip"

    override fun insert(uri: Uri, values: ContentValues?): Uri? = null

    override fun delete(uri: Uri, selection: String?, selectionArgs: Array<String>?): Int = 0

    override fun update(uri: Uri, values: ContentValues?, selection: String?, selectionArgs: Array<String>?): Int = 0

    companion object {
        const val AUTHORITY = "io.ecvo.app.exports"

        fun exportsDir(cacheDir: File): File = File(cacheDir, "exports")

        fun uriFor(zip: File): Uri = Uri.parse("content://$AUTHORITY/${Uri.encode(zip.name)}")
    }
}
