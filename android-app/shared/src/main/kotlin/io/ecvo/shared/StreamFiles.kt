package io.ecvo.shared

import java.io.File
import java.io.FileNotFoundException

/**
 * Read access to the files of a recorded stream by relative path (`"rgb.txt"`,
 * `"depth/1.000000.png"`), so a stream can be read from a folder, from APK assets or
 * through Android's Storage Access Framework alike.
 */
interface StreamFiles {
    /** What the stream is, for error messages (a folder path, an asset or document name). */
    val description: String

    /** Whether the file at [path] exists. */
    fun exists(path: String): Boolean

    /** The bytes of the file at [path]; throws FileNotFoundException if there is none. */
    fun readBytes(path: String): ByteArray
}

/** A stream in a folder of the file system. */
class DirectoryFiles(val dir: File) : StreamFiles {
    override val description: String get() = dir.path

    override fun exists(path: String): Boolean = File(dir, path).isFile

    override fun readBytes(path: String): ByteArray {
        val f = File(dir, path)
        if (!f.isFile) throw FileNotFoundException("$f: no such file")
        return f.readBytes()
    }
}
