package io.ecvo.shared

import java.io.BufferedOutputStream
import java.io.File
import java.io.FileOutputStream
import java.io.IOException
import java.io.OutputStream
import java.util.zip.CRC32
import java.util.zip.ZipEntry
import java.util.zip.ZipOutputStream

/**
 * The stream a session belongs to: the recording it replays, or the last recording made
 * during it (null for the bundled sample or an unrecorded live session). Reset at every
 * start, so an export never attaches the recording of an earlier session.
 *
 * Not thread-safe: call it from the UI thread.
 */
class SessionStreams {
    /** The current session's stream folder, or null. */
    var stream: File? = null
        private set

    /** A session started; [replayed] is the recording it replays (null: sample or live). */
    fun onStarted(replayed: File?) { stream = replayed }

    /** A recording into [dir] started during the current session. */
    fun onRecording(dir: File) { stream = dir }

    /** [dir] was deleted; a session that pointed at it has no stream any more. */
    fun onDeleted(dir: File) {
        if (stream != null && sameFile(stream!!, dir)) stream = null
    }
}

/** What one export holds: the session's results (trajectory, references, cloud) and/or a stream. */
data class ExportPlan(val withSession: Boolean, val stream: File?) {
    init {
        require(withSession || stream != null) { "an export holds the session, a stream or both" }
    }
}

/** Which files an export attaches; pure, tested on the JVM. */
object ExportSelection {
    /**
     * The Share button: the current session's results with the stream it came from (the
     * replayed recording or the one made during it), if that folder still exists; null
     * without a session.
     */
    fun forSession(hasSession: Boolean, sessionStream: File?): ExportPlan? =
        if (!hasSession) null else ExportPlan(true, sessionStream?.takeIf { it.isDirectory })

    /**
     * A recording chosen in the recordings list: that recording's stream, whichever session
     * is running, plus the session's results only when the session is that recording's
     * (it replays it, or recorded it).
     */
    fun forRecording(chosen: File, hasSession: Boolean, sessionStream: File?): ExportPlan =
        ExportPlan(hasSession && sessionStream != null && sameFile(sessionStream, chosen), chosen)
}

/**
 * The exports folder (`cache/exports`): each export gets its own zip (never overwriting or
 * deleting one a share target may still be reading), and only the oldest beyond [KEEP]
 * are removed.
 */
object ExportFiles {
    /** Zips kept in the exports folder (the newest ones). */
    const val KEEP: Int = 8

    /** `<base>.zip` in [dir], or `<base>-2.zip`, `<base>-3.zip`, ... if taken (a folder of that stem too). */
    fun uniqueZip(dir: File, base: String): File {
        require(base.isNotEmpty() && !base.contains('/')) { "bad export name '$base'" }
        var n = 1
        while (true) {
            val stem = if (n == 1) base else "$base-$n"
            val zip = File(dir, "$stem.zip")
            if (!zip.exists() && !File(dir, stem).exists()) return zip
            n++
        }
    }

    /** Deletes the zips of [dir] beyond the newest [keep] (by modification time, then name), never [spare]; returns them. */
    fun prune(dir: File, keep: Int = KEEP, spare: File? = null): List<File> {
        val zips = dir.listFiles { f -> f.isFile && f.name.endsWith(".zip") }?.toList() ?: return emptyList()
        val old = zips.sortedWith(compareByDescending<File> { it.lastModified() }.thenByDescending { it.name }).drop(keep)
            .filter { spare == null || !sameFile(it, spare) }
        old.forEach { it.delete() }
        return old
    }

    /**
     * Writes one export into a new zip `<base>[-n].zip` in [exportsDir] ([write]), then
     * prunes the older zips. Returns the zip; on failure none is left behind.
     */
    fun pack(plan: ExportPlan, exportsDir: File, base: String, writeSession: (File) -> Unit): File {
        if (!exportsDir.isDirectory && !exportsDir.mkdirs()) throw IOException("cannot create folder $exportsDir")
        val zip = uniqueZip(exportsDir, base)
        try {
            FileOutputStream(zip).use { write(plan, it, zip.name.removeSuffix(".zip"), exportsDir, writeSession) }
        } catch (e: Exception) {
            zip.delete()
            throw e
        }
        prune(exportsDir, KEEP, spare = zip)
        return zip
    }

    /**
     * Writes one export as a zip to [out] (a file, or a Downloads entry), every entry
     * under the top folder [top]: the session's files, written by [writeSession] into a
     * scratch folder in [scratchDir] when [plan] asks for them (a few small files), and
     * the stream zipped straight from its folder under `stream/` ([StreamSnapshot]: no
     * copy of the recording, consistent while it is still being written; PNGs stored,
     * not deflated again). Does not close [out].
     */
    fun write(plan: ExportPlan, out: OutputStream, top: String, scratchDir: File, writeSession: (File) -> Unit) {
        // Taken first, so that what is zipped is what the lists said at this moment.
        val snapshot = plan.stream?.let { s ->
            if (!s.isDirectory) throw IOException("the recording ${s.name} no longer exists")
            StreamSnapshot.take(s)
        }
        val z = ZipOutputStream(BufferedOutputStream(out))
        if (plan.withSession) {
            val tmp = File(scratchDir, "$top.session")
            try {
                tmp.deleteRecursively()
                if (!tmp.mkdirs()) throw IOException("cannot create folder $tmp")
                writeSession(tmp)
                tmp.walkTopDown().filter { it.isFile }.sortedBy { it.path }.forEach { f ->
                    ZipEntries.deflated(z, "$top/" + f.relativeTo(tmp).invariantSeparatorsPath, f.readBytes())
                }
            } finally {
                tmp.deleteRecursively()
            }
        }
        snapshot?.writeTo(z, "$top/stream")
        z.finish()
        z.flush()
    }
}

/** Zip entries of a known content. */
internal object ZipEntries {
    fun deflated(z: ZipOutputStream, name: String, bytes: ByteArray) {
        z.putNextEntry(ZipEntry(name))
        z.write(bytes)
        z.closeEntry()
    }

    /** A STORED entry (already-compressed data such as PNGs: deflating again costs time and gains nothing). */
    fun stored(z: ZipOutputStream, name: String, bytes: ByteArray) {
        val e = ZipEntry(name)
        e.method = ZipEntry.STORED
        e.size = bytes.size.toLong()
        e.compressedSize = bytes.size.toLong()
        e.crc = CRC32().also { it.update(bytes) }.value
        z.putNextEntry(e)
        z.write(bytes)
        z.closeEntry()
    }
}

/**
 * A stream folder as its lists describe it at one moment, for zipping while a recorder
 * may still be writing into it. The recorder writes a frame's PNGs before its list
 * lines, and its `rgb.txt` line before its `depth.txt` line; so the lists are read first
 * (`depth.txt`, then `rgb.txt`), each cut after its last complete line, and only the
 * files they name (plus the folder's other top-level files: `camera.json`,
 * `groundtruth.txt`) are zipped: every named PNG is complete, and a PNG being written
 * is left out.
 */
class StreamSnapshot private constructor(
    private val dir: File,
    private val lists: List<Pair<String, ByteArray>>,
    /** The files to zip, relative to the folder, in order. */
    val files: List<String>,
) {
    /** Writes the lists and files under [prefix] (a folder inside the zip). */
    fun writeTo(z: ZipOutputStream, prefix: String) {
        for ((name, bytes) in lists) ZipEntries.deflated(z, "$prefix/$name", bytes)
        for (rel in files) {
            val bytes = File(dir, rel).readBytes()
            if (rel.endsWith(".png", ignoreCase = true)) ZipEntries.stored(z, "$prefix/$rel", bytes) else ZipEntries.deflated(z, "$prefix/$rel", bytes)
        }
    }

    companion object {
        private val LISTS = listOf("depth.txt", "rgb.txt")

        fun take(dir: File): StreamSnapshot {
            val lists = LISTS.map { name ->
                val f = File(dir, name)
                if (!f.isFile) throw IOException("${dir.name} has no $name")
                name to complete(f.readBytes())
            }
            val named = LinkedHashSet<String>()
            for ((name, bytes) in lists) {
                for (line in String(bytes, Charsets.UTF_8).lineSequence()) {
                    val t = line.trim()
                    if (t.isEmpty() || t.startsWith("#")) continue
                    val path = t.split(Regex("\\s+")).getOrNull(1) ?: throw IOException("${dir.name}/$name: bad line '$t'")
                    if (path.startsWith("/") || path.split('/').any { it == ".." }) throw IOException("${dir.name}/$name: path $path leaves the folder")
                    if (!File(dir, path).isFile) throw IOException("${dir.name}/$name names $path, which does not exist")
                    named += path
                }
            }
            val others = dir.listFiles { f -> f.isFile && f.name !in LISTS }?.map { it.name }?.sorted() ?: emptyList()
            return StreamSnapshot(dir, lists.reversed(), others + named)
        }

        /** [bytes] up to and including the last newline (a line being written is left out). */
        private fun complete(bytes: ByteArray): ByteArray {
            var n = bytes.size
            while (n > 0 && bytes[n - 1] != '\n'.code.toByte()) n--
            return bytes.copyOf(n)
        }
    }
}

internal fun sameFile(a: File, b: File): Boolean = try {
    a.canonicalFile == b.canonicalFile
} catch (e: IOException) {
    a.absoluteFile == b.absoluteFile
}
