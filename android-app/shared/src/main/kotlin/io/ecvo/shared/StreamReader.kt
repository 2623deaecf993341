package io.ecvo.shared

import io.ecvo.TimedPose
import java.io.File
import java.io.FileNotFoundException
import java.io.IOException

/** Where one frame's images are and when it was taken. */
data class FrameInfo(
    /** Position in the stream. */
    val index: Int,
    /** Frame time: the intensity image's timestamp, in seconds (as the TUM tools use it). */
    val timestamp: Double,
    /** The same, exactly, in nanoseconds. */
    val timestampNs: Long,
    /** The depth image's timestamp in seconds. */
    val depthTimestamp: Double,
    /** Relative path of the intensity PNG. */
    val rgb: String,
    /** Relative path of the 16-bit depth PNG. */
    val depth: String,
)

/** One decoded frame: `width * height` raw depth (camera depth-scale units, 0 = none) and 8-bit gray intensity. */
class StreamFrame(
    val index: Int,
    val timestampNs: Long,
    val depth: ShortArray,
    val intensity: ByteArray,
)

/**
 * Reads a recorded stream (or any TUM RGB-D folder with a `camera.json`) the way
 * `ecvo run` does: the camera from `camera.json`, the frames from `rgb.txt` and
 * `depth.txt`, pairing intensity and depth one-to-one by nearest timestamp within
 * [MAX_RGB_DEPTH_DT] seconds (greedily by increasing difference, as TUM's
 * `associate.py`), and the optional `groundtruth.txt`. Frames are decoded on demand.
 *
 * @throws IOException naming the file and line for a missing or malformed file.
 */
class StreamReader(val files: StreamFiles) : Iterable<StreamFrame> {
    /** Reads the stream in folder [dir]. */
    constructor(dir: File) : this(DirectoryFiles(dir))

    /** The camera of the frames. */
    val camera: CameraIntrinsics

    /** The associated frames, in time order. */
    val frames: List<FrameInfo>

    /** The ground truth, if the stream has a `groundtruth.txt`. */
    val groundtruth: List<TimedPose>?

    init {
        if (!files.exists(CameraIntrinsics.FILE_NAME)) throw FileNotFoundException("${files.description}: no ${CameraIntrinsics.FILE_NAME}")
        camera = CameraIntrinsics.fromJson(text(CameraIntrinsics.FILE_NAME), where(CameraIntrinsics.FILE_NAME))
        val rgb = readList("rgb.txt")
        val depth = readList("depth.txt")
        val pairs = associate(rgb.map { it.seconds }.toDoubleArray(), depth.map { it.seconds }.toDoubleArray(), MAX_RGB_DEPTH_DT)
        frames = pairs.mapIndexed { k, (i, j) ->
            FrameInfo(k, rgb[i].seconds, rgb[i].ns, depth[j].seconds, rgb[i].file, depth[j].file)
        }
        if (frames.isEmpty()) throw IOException("${files.description}: no colour/depth image pair within $MAX_RGB_DEPTH_DT s in rgb.txt and depth.txt")
        groundtruth = if (files.exists("groundtruth.txt")) TumTrajectory.parse(text("groundtruth.txt"), where("groundtruth.txt")) else null
        for (path in listOf(frames[0].rgb, frames[0].depth)) {
            val (w, h) = try {
                Png.size(files.readBytes(path))
            } catch (e: PngException) {
                throw PngException("${where(path)}: ${e.message}")
            }
            if (w != camera.width || h != camera.height) {
                throw IOException("${where(path)}: image is ${w}x$h, expected ${camera.width}x${camera.height} (camera.json)")
            }
        }
    }

    /** Number of frames. */
    val size: Int get() = frames.size

    private fun where(path: String) = "${files.description}/$path"

    private fun text(path: String) = String(files.readBytes(path), Charsets.UTF_8)

    private class Entry(val seconds: Double, val ns: Long, val file: String)

    private fun readList(name: String): List<Entry> {
        val src = where(name)
        if (!files.exists(name)) throw FileNotFoundException("$src: no such file")
        val out = ArrayList<Entry>()
        for ((line, f) in TumTrajectory.records(text(name))) {
            if (f.size != 2) throw IOException("$src:$line: expected `timestamp filename`, found ${f.size} field(s)")
            val t = TumTrajectory.parseNumber(f[0], src, line)
            if (out.isNotEmpty() && t <= out.last().seconds) throw IOException("$src:$line: timestamp ${f[0]} is not after the previous one")
            val ns = try {
                Timestamps.parseSecondsToNs(f[0])
            } catch (e: ArithmeticException) {
                throw IOException("$src:$line: timestamp ${f[0]} is out of range")
            } catch (e: NumberFormatException) {
                throw IOException("$src:$line: `${f[0]}` is not a number")
            }
            out += Entry(t, ns, f[1])
        }
        return out
    }

    /** Decodes frame [index]. */
    fun readFrame(index: Int): StreamFrame {
        val info = frames[index]
        val rgb = decode(info.rgb)
        val depth = decode(info.depth)
        for ((path, img) in listOf(info.rgb to rgb, info.depth to depth)) {
            if (img.width != camera.width || img.height != camera.height) {
                throw IOException("${where(path)}: image is ${img.width}x${img.height}, expected ${camera.width}x${camera.height}")
            }
        }
        return try {
            StreamFrame(index, info.timestampNs, depth.toGray16(), rgb.toGray8())
        } catch (e: PngException) {
            throw PngException("${files.description}: frame $index: ${e.message}")
        }
    }

    private fun decode(path: String): PngImage = try {
        Png.decode(files.readBytes(path))
    } catch (e: PngException) {
        throw PngException("${where(path)}: ${e.message}")
    }

    /** The frames in order, decoded one at a time. */
    override fun iterator(): Iterator<StreamFrame> = object : Iterator<StreamFrame> {
        private var next = 0
        override fun hasNext() = next < frames.size
        override fun next(): StreamFrame {
            if (!hasNext()) throw NoSuchElementException()
            return readFrame(next++)
        }
    }

    companion object {
        /** Largest time difference (seconds, exclusive) between a frame's intensity and depth images. */
        const val MAX_RGB_DEPTH_DT: Double = 0.02

        /**
         * Pairs [first] and [second] one-to-one like TUM's `associate.py` (and `ecvo-io`):
         * every pair closer than [maxDt] is a candidate, candidates are taken by increasing
         * difference (ties by index), each index once; the result is sorted by [first]'s time.
         */
        fun associate(first: DoubleArray, second: DoubleArray, maxDt: Double): List<Pair<Int, Int>> {
            val order = second.indices.filter { second[it].isFinite() }.sortedWith(compareBy<Int> { second[it] }.thenBy { it })
            val sorted = DoubleArray(order.size) { second[order[it]] }
            data class Cand(val d: Double, val i: Int, val j: Int)
            val cands = ArrayList<Cand>()
            for ((i, a) in first.withIndex()) {
                if (!a.isFinite()) continue
                // First k with sorted[k] > a - maxDt.
                var lo = 0
                var hi = sorted.size
                while (lo < hi) {
                    val mid = (lo + hi) ushr 1
                    if (sorted[mid] <= a - maxDt) lo = mid + 1 else hi = mid
                }
                for (k in lo until sorted.size) {
                    val b = sorted[k]
                    if (b - a >= maxDt) break
                    val d = kotlin.math.abs(a - b)
                    if (d < maxDt) cands += Cand(d, i, order[k])
                }
            }
            cands.sortWith(compareBy<Cand> { it.d }.thenBy { it.i }.thenBy { it.j })
            val usedA = BooleanArray(first.size)
            val usedB = BooleanArray(second.size)
            val pairs = ArrayList<Pair<Int, Int>>()
            for (c in cands) {
                if (!usedA[c.i] && !usedB[c.j]) {
                    usedA[c.i] = true; usedB[c.j] = true
                    pairs += c.i to c.j
                }
            }
            pairs.sortWith(compareBy<Pair<Int, Int>> { first[it.first] }.thenBy { it.first }.thenBy { it.second })
            return pairs
        }
    }
}
