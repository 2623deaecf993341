package io.ecvo.app

import android.content.res.AssetManager
import io.ecvo.shared.StreamFiles

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
