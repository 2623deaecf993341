package io.ecvo.shared

import java.io.File
import java.io.IOException

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
     * Writes one export: a fresh folder `<base>[-n]` in [exportsDir], the session's files
     * by [writeSession] when [plan] asks for them, the stream under `stream/`, then the
     * zip beside it; the folder is removed, older zips pruned. Returns the zip.
     */
    fun pack(plan: ExportPlan, exportsDir: File, base: String, writeSession: (File) -> Unit): File {
        if (!exportsDir.isDirectory && !exportsDir.mkdirs()) throw IOException("cannot create folder $exportsDir")
        val zip = uniqueZip(exportsDir, base)
        val dir = File(exportsDir, zip.name.removeSuffix(".zip"))
        try {
            if (!dir.mkdirs()) throw IOException("cannot create folder $dir")
            if (plan.withSession) writeSession(dir)
            plan.stream?.let { s ->
                if (!s.isDirectory) throw IOException("the recording ${s.name} no longer exists")
                s.copyRecursively(File(dir, "stream"))
            }
            SessionExport.zip(dir, zip)
        } catch (e: Exception) {
            zip.delete()
            throw e
        } finally {
            dir.deleteRecursively()
        }
        prune(exportsDir, KEEP, spare = zip)
        return zip
    }
}

internal fun sameFile(a: File, b: File): Boolean = try {
    a.canonicalFile == b.canonicalFile
} catch (e: IOException) {
    a.absoluteFile == b.absoluteFile
}
