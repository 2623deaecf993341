package io.ecvo.app

import android.content.ContentResolver
import android.content.res.AssetManager
import android.net.Uri
import android.provider.DocumentsContract
import io.ecvo.shared.StreamFiles
import java.io.FileNotFoundException

/** A recorded stream bundled in the APK's assets, under [prefix] ("" = the assets' root). */
class AssetStreamFiles(private val assets: AssetManager, private val prefix: String = "") : StreamFiles {
    override val description: String get() = "assets/$prefix".trimEnd('/')

    private fun full(path: String) = if (prefix.isEmpty()) path else "$prefix/$path"

    override fun exists(path: String): Boolean = try {
        assets.open(full(path)).close()
        true
    } catch (e: java.io.IOException) {
        false
    }

    override fun readBytes(path: String): ByteArray = assets.open(full(path)).use { it.readBytes() }
}

/**
 * A recorded stream in a folder picked with the Storage Access Framework
 * (`ACTION_OPEN_DOCUMENT_TREE`). Each folder's listing is queried once and cached.
 */
class DocumentTreeStreamFiles(private val resolver: ContentResolver, private val treeUri: Uri) : StreamFiles {
    override val description: String get() = treeUri.lastPathSegment ?: treeUri.toString()

    /** document id of a folder -> (child name -> child document id). */
    private val listings = HashMap<String, Map<String, String>>()

    private fun children(folderId: String): Map<String, String> = listings.getOrPut(folderId) {
        val uri = DocumentsContract.buildChildDocumentsUriUsingTree(treeUri, folderId)
        val cols = arrayOf(DocumentsContract.Document.COLUMN_DOCUMENT_ID, DocumentsContract.Document.COLUMN_DISPLAY_NAME)
        val out = HashMap<String, String>()
        resolver.query(uri, cols, null, null, null)?.use { c ->
            while (c.moveToNext()) out[c.getString(1)] = c.getString(0)
        }
        out
    }

    private fun resolve(path: String): Uri? {
        var id = DocumentsContract.getTreeDocumentId(treeUri)
        for (part in path.split('/').filter { it.isNotEmpty() }) {
            id = children(id)[part] ?: return null
        }
        return DocumentsContract.buildDocumentUriUsingTree(treeUri, id)
    }

    override fun exists(path: String): Boolean = resolve(path) != null

    override fun readBytes(path: String): ByteArray {
        val uri = resolve(path) ?: throw FileNotFoundException("$description/$path: no such file")
        return resolver.openInputStream(uri)?.use { it.readBytes() }
            ?: throw FileNotFoundException("$description/$path: cannot open")
    }
}
