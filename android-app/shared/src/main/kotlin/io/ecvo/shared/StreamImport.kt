package io.ecvo.shared

import java.io.File
import java.io.IOException
import java.io.InputStream
import java.util.zip.ZipInputStream

/**
 * Imports a stream from a zip (an export of this app, or any zip holding a TUM-layout
 * folder: `camera.json`, `rgb.txt`, `depth.txt` and their images) into the recordings
 * folder, where it can be replayed like a recording. Bounded: at most [maxEntries]
 * entries and [maxBytes] bytes unpacked, no entry outside the target folder; anything else
 * is an IOException and leaves nothing behind.
 */
object StreamImport {
    /**
     * Unpacks [zip] into a new folder `<name>[-n]` of [recordingsDir] and returns it (the
     * stream folder itself: the zip's folder that holds `camera.json`, `rgb.txt` and
     * `depth.txt`, the shallowest if several).
     */
    fun fromZip(zip: InputStream, recordingsDir: File, name: String, maxEntries: Int = 200_000, maxBytes: Long = 8L shl 30): File {
        require(name.isNotEmpty() && !name.contains('/') && name != "." && name != "..") { "bad recording name '$name'" }
        if (!recordingsDir.isDirectory && !recordingsDir.mkdirs()) throw IOException("cannot create folder $recordingsDir")
        val work = File(recordingsDir, ".import-$name-${System.nanoTime()}")
        try {
            if (!work.mkdirs()) throw IOException("cannot create folder $work")
            val root = work.canonicalFile
            var entries = 0
            var bytes = 0L
            val buf = ByteArray(64 * 1024)
            ZipInputStream(zip).use { z ->
                while (true) {
                    val e = z.nextEntry ?: break
                    if (++entries > maxEntries) throw IOException("the zip has more than $maxEntries entries")
                    val f = File(root, e.name).canonicalFile
                    if (!f.path.startsWith(root.path + File.separator)) throw IOException("zip entry ${e.name} leaves its folder")
                    if (e.isDirectory) { f.mkdirs(); continue }
                    f.parentFile?.mkdirs()
                    f.outputStream().use { o ->
                        while (true) {
                            val n = z.read(buf)
                            if (n < 0) break
                            bytes += n
                            if (bytes > maxBytes) throw IOException("the zip unpacks to more than ${maxBytes shr 20} MB")
                            o.write(buf, 0, n)
                        }
                    }
                }
            }
            val stream = work.walkTopDown()
                .filter { d -> d.isDirectory && listOf(CameraIntrinsics.FILE_NAME, "rgb.txt", "depth.txt").all { File(d, it).isFile } }
                .minByOrNull { it.path.count { c -> c == File.separatorChar } }
                ?: throw IOException("the zip holds no stream folder (camera.json, rgb.txt and depth.txt together)")
            // Read once, so that a broken stream is refused here rather than at replay.
            StreamReader(DirectoryFiles(stream))
            var target = File(recordingsDir, name)
            var k = 2
            while (target.exists()) target = File(recordingsDir, "$name-${k++}")
            if (!stream.renameTo(target)) throw IOException("cannot move the stream to $target")
            return target
        } finally {
            work.deleteRecursively()
        }
    }
}
