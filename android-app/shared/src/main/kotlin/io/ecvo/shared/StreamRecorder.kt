package io.ecvo.shared

import io.ecvo.TimedPose
import java.io.File
import java.io.FileOutputStream
import java.io.IOException
import java.io.OutputStreamWriter
import java.io.Writer

/**
 * Records frames into a new stream folder in the layout `ecvo run` reads (the same as
 * `ecvo-io`'s `SequenceWriter`): `camera.json`, `rgb.txt` and `depth.txt`
 * (`timestamp filename` lines under `#` headers, timestamps in seconds with 6 decimals),
 * `rgb/<ts>.png` (8-bit gray intensity), `depth/<ts>.png` (16-bit gray, [camera]'s
 * `depthScale` units per metre; millimetres for a phone) and optionally
 * `groundtruth.txt`. With an IMU, `camera.json` carries its calibration ([imu]) and the
 * session writes `imu.txt` beside the lists ([ImuRecorder]).
 *
 * Each frame's PNGs are written before its list lines, and the lists are flushed after
 * every frame, so a recording cut short is still a readable stream up to its last
 * complete frame. Not thread-safe: write from one thread (the app records through
 * [AsyncRecorder], on a thread of its own).
 *
 * @throws IOException if [dir] already holds a stream (`rgb.txt` or `depth.txt`) or
 *   cannot be created.
 */
class StreamRecorder(
    override val dir: File,
    val camera: CameraIntrinsics,
    /** The IMU's calibration, written into `camera.json` when the session records `imu.txt` ([ImuRecorder]). */
    val imu: ImuCalibration? = null,
) : FrameRecorder {
    private val rgbList: Writer
    private val depthList: Writer
    private val rgbOut: FileOutputStream
    private val depthOut: FileOutputStream
    private var lastMicros = Long.MIN_VALUE
    private var closed = false

    /** Frames written so far. */
    override var framesWritten: Int = 0
        private set

    init {
        try {
            camera.validate()
        } catch (e: IllegalArgumentException) {
            throw IOException("camera for $dir: ${e.message}")
        }
        for (name in listOf("rgb.txt", "depth.txt")) {
            val f = File(dir, name)
            if (f.exists()) throw IOException("$f already exists; refusing to overwrite a stream")
        }
        for (d in listOf(dir, File(dir, "rgb"), File(dir, "depth"))) {
            if (!d.isDirectory && !d.mkdirs()) throw IOException("cannot create folder $d")
        }
        File(dir, CameraIntrinsics.FILE_NAME).writeText(camera.toJson(imu))
        rgbOut = FileOutputStream(File(dir, "rgb.txt"))
        depthOut = FileOutputStream(File(dir, "depth.txt"))
        rgbList = OutputStreamWriter(rgbOut, Charsets.UTF_8)
        depthList = OutputStreamWriter(depthOut, Charsets.UTF_8)
        rgbList.write(RGB_HEADER); rgbList.flush()
        depthList.write(DEPTH_HEADER); depthList.flush()
    }

    /**
     * Writes one frame taken at [timestampNs]: [depth] and [intensity] hold
     * `width * height` values, row-major. The timestamp, rounded to microseconds, must
     * be after the previous frame's; otherwise IllegalArgumentException.
     */
    override fun writeFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray) {
        check(!closed) { "StreamRecorder for $dir is closed" }
        require(timestampNs >= 0) { "$dir: timestamp $timestampNs ns is negative" }
        val n = camera.pixels
        require(depth.size == n) { "$dir: depth has ${depth.size} values, expected $n (${camera.width}x${camera.height})" }
        require(intensity.size == n) { "$dir: intensity has ${intensity.size} values, expected $n (${camera.width}x${camera.height})" }
        val micros = Timestamps.roundToMicros(timestampNs)
        val name = Timestamps.formatSeconds(timestampNs)
        require(micros > lastMicros) { "$dir: timestamp $name is not after the previous frame's" }
        val rgbRel = "rgb/$name.png"
        val depthRel = "depth/$name.png"
        File(dir, rgbRel).writeBytes(Png.encodeGray8(intensity, camera.width, camera.height, FILTER, 1, STRATEGY))
        File(dir, depthRel).writeBytes(Png.encodeGray16(depth, camera.width, camera.height, FILTER, 1, STRATEGY))
        rgbList.write("$name $rgbRel\n"); rgbList.flush()
        depthList.write("$name $depthRel\n"); depthList.flush()
        lastMicros = micros
        framesWritten++
    }

    /** Writes `groundtruth.txt` (TUM trajectory format) beside the lists. */
    fun writeGroundtruth(poses: List<TimedPose>) = TumTrajectory.write(File(dir, "groundtruth.txt"), poses)

    /** Flushes and syncs the lists and closes them; calling it again does nothing. */
    override fun close() {
        if (closed) return
        closed = true
        try {
            rgbList.flush(); rgbOut.fd.sync()
            depthList.flush(); depthOut.fd.sync()
        } finally {
            rgbList.close()
            depthList.close()
        }
    }

    companion object {
        /**
         * The recorder's PNG settings: the SUB filter and Huffman-only deflate. On the
         * 640x480 frames of TUM fr1/xyz this encodes a frame's two PNGs in 0.38x-0.39x the
         * median time of adaptive filtering at deflate level 1 (the old setting), at about the
         * same size (`scripts/kotlin/PngBench.kt`; figures in `android-app/README.md`).
         */
        val FILTER: PngFilter = PngFilter.SUB
        const val STRATEGY: Int = java.util.zip.Deflater.HUFFMAN_ONLY

        /** Header of `rgb.txt`, as the host tools write it. */
        const val RGB_HEADER: String = "# color images (8-bit gray)\n# file: 'ecvo recording'\n# timestamp filename\n"

        /** Header of `depth.txt`, as the host tools write it. */
        const val DEPTH_HEADER: String = "# depth maps\n# file: 'ecvo recording'\n# timestamp filename\n"
    }
}
