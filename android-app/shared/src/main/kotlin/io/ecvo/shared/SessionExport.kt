package io.ecvo.shared

import io.ecvo.ReferenceFrame
import io.ecvo.TimedPose
import java.io.BufferedOutputStream
import java.io.File
import java.io.FileOutputStream
import java.io.IOException
import java.nio.ByteBuffer
import java.nio.ByteOrder
import java.util.zip.ZipEntry
import java.util.zip.ZipOutputStream

/**
 * Writes a session the way `ecvo run --out` does, so the host tools read it directly:
 * `trajectory.txt` (TUM; `ecvo eval GT trajectory.txt`), `references.txt` (timestamp,
 * pose, level, frame index), `cloud.ply` (binary little-endian x y z and a gray colour,
 * as `ecvo-io`'s `write_ply`); with a recorded stream, the stream itself under
 * `stream/` (`ecvo run stream` replays it). [zip] packs such a folder for sharing.
 */
object SessionExport {
    /** Writes the files into [dir] (created); returns the files written. */
    fun write(dir: File, trajectory: List<TimedPose>, references: List<ReferenceFrame>, cloud: FloatArray?): List<File> {
        if (!dir.isDirectory && !dir.mkdirs()) throw IOException("cannot create folder $dir")
        val out = ArrayList<File>()
        File(dir, "trajectory.txt").also { TumTrajectory.write(it, trajectory); out += it }
        File(dir, "references.txt").also { it.writeText(referencesText(trajectory, references)); out += it }
        if (cloud != null) File(dir, "cloud.ply").also { writePly(it, cloud); out += it }
        return out
    }

    /** `references.txt` as `ecvo run` writes it: the frame index is the pose's position in [trajectory] (-1 if absent). */
    fun referencesText(trajectory: List<TimedPose>, references: List<ReferenceFrame>): String = buildString {
        append("# reference frames chosen by the tracker (the first frame, which anchors every level, is not listed)\n")
        append("# timestamp tx ty tz qx qy qz qw level frame_index\n")
        append("# level: highest level the frame became the reference of (a level-2 reference is also level 1)\n")
        val index = HashMap<Double, Int>()
        trajectory.forEachIndexed { i, p -> index.putIfAbsent(p.timestamp, i) }
        for (r in references) {
            if (r.level <= 0) continue
            val p = r.pose
            val i = index[p.timestamp] ?: -1
            if (i == 0) continue // the first frame anchors every level
            append(listOf(p.timestamp, p.tx, p.ty, p.tz, p.qx, p.qy, p.qz, p.qw).joinToString(" ") { Timestamps.plain(it) })
            append(' ').append(r.level).append(' ').append(i).append('\n')
        }
    }

    /** `cloud.ply` from `Tracker.pointCloud`'s floats (x, y, z, intensity 0..1 per point). */
    fun writePly(file: File, cloud: FloatArray) {
        require(cloud.size % 4 == 0) { "cloud has ${cloud.size} floats, not 4 per point" }
        val n = cloud.size / 4
        BufferedOutputStream(FileOutputStream(file)).use { o ->
            o.write(
                ("ply\nformat binary_little_endian 1.0\ncomment written by ecvo (Android)\nelement vertex $n\n" +
                    "property float x\nproperty float y\nproperty float z\n" +
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n").toByteArray(Charsets.US_ASCII),
            )
            val b = ByteBuffer.allocate(15).order(ByteOrder.LITTLE_ENDIAN)
            for (i in 0 until n) {
                b.clear()
                b.putFloat(cloud[4 * i]); b.putFloat(cloud[4 * i + 1]); b.putFloat(cloud[4 * i + 2])
                val g = (cloud[4 * i + 3].coerceIn(0f, 1f) * 255f + 0.5f).toInt().toByte()
                b.put(g); b.put(g); b.put(g)
                o.write(b.array(), 0, 15)
            }
        }
    }

    /** Packs [dir] (recursively, paths relative to it under a top folder named like it) into [zipFile]. */
    fun zip(dir: File, zipFile: File) {
        require(dir.isDirectory) { "$dir is not a folder" }
        ZipOutputStream(BufferedOutputStream(FileOutputStream(zipFile))).use { z ->
            dir.walkTopDown().filter { it.isFile && it != zipFile }.sortedBy { it.path }.forEach { f ->
                z.putNextEntry(ZipEntry(dir.name + "/" + f.relativeTo(dir).invariantSeparatorsPath))
                f.inputStream().use { it.copyTo(z) }
                z.closeEntry()
            }
        }
    }
}

/** One recording the app made: a stream folder under the app's recordings folder. */
data class RecordingEntry(val dir: File, val name: String, val frames: Int, val bytes: Long)

/**
 * The app's own recordings (`<app files>/recordings/<name>/`, a stream each), newest first;
 * folders that are not streams (no `camera.json`, `rgb.txt`, `depth.txt`) are skipped.
 * Listing the app's folder directly is what works since Android 11, where the system
 * folder picker cannot open `Android/data`.
 */
object Recordings {
    fun list(root: File): List<RecordingEntry> {
        val dirs = root.listFiles { f -> f.isDirectory } ?: return emptyList()
        return dirs.filter { d -> listOf(CameraIntrinsics.FILE_NAME, "rgb.txt", "depth.txt").all { File(d, it).isFile } }
            .map { d ->
                val frames = File(d, "depth.txt").useLines { lines -> lines.count { it.isNotBlank() && !it.startsWith("#") } }
                RecordingEntry(d, d.name, frames, d.walkTopDown().filter { it.isFile }.sumOf { it.length() })
            }
            .sortedByDescending { it.name }
    }

    /**
     * Deletes the recording [dir] if it is a stream folder directly inside [root] and not
     * [inUse] (being recorded into or replayed); returns whether it was deleted.
     */
    fun delete(root: File, dir: File, inUse: File? = null): Boolean {
        val parent = dir.absoluteFile.parentFile ?: return false
        if (!sameFile(parent, root) || !File(dir, CameraIntrinsics.FILE_NAME).isFile) return false
        if (inUse != null && sameFile(inUse, dir)) return false
        return dir.deleteRecursively()
    }
}
