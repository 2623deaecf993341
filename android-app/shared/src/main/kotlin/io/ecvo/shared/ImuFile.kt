package io.ecvo.shared

import java.io.BufferedReader
import java.io.ByteArrayInputStream
import java.io.File
import java.io.FileOutputStream
import java.io.IOException
import java.io.InputStream
import java.io.InputStreamReader
import java.io.OutputStreamWriter
import java.io.Writer

/**
 * The samples of a stream's `imu.txt`: [count] samples, each a timestamp (nanoseconds, on
 * the frames' clock) and a gyroscope reading (rad/s, the IMU's axes), with an
 * accelerometer reading (m/s²) when the file has one on every line.
 */
class ImuData(
    val timestampsNs: LongArray,
    /** wx, wy, wz per sample (3 * [count] values). */
    val gyro: DoubleArray,
    /** ax, ay, az per sample, or null when the file has none. */
    val accel: DoubleArray?,
) {
    init {
        require(gyro.size == 3 * timestampsNs.size) { "gyro has ${gyro.size} values for ${timestampsNs.size} samples" }
        require(accel == null || accel.size == gyro.size) { "accel has ${accel?.size} values for ${timestampsNs.size} samples" }
    }

    val count: Int get() = timestampsNs.size
}

/**
 * `imu.txt`, the IMU stream beside a recording's frames (issue 47): one line per sample,
 * `timestamp wx wy wz [ax ay az]`, the timestamp in seconds on the frames' clock, angular
 * rate in rad/s and acceleration in m/s² in the IMU's frame (for a phone, Android's
 * sensor axes), `#` comments. Its calibration (the camera-from-IMU rotation, the time
 * offset) is in `camera.json` ([ImuCalibration]).
 *
 * [parse] and [read] follow the other readers' rules for hostile input: a size limit
 * checked before anything is read ([MAX_BYTES]), then line by line (no copy of the whole
 * text), every field a finite number, timestamps strictly increasing, the same number of
 * fields (4 or 7) on every line, readings within what a sensor can report
 * ([MAX_RATE_RAD_S], [MAX_ACCEL_M_S2]); an IOException names the file and line.
 */
object ImuFile {
    /** Name of the file inside a stream folder. */
    const val FILE_NAME: String = "imu.txt"

    /** Header written before the samples. */
    const val HEADER: String = "# imu: gyroscope (rad/s) in the IMU's axes, timestamps on the frames' clock\n" +
        "# file: 'ecvo recording'\n# timestamp wx wy wz\n"

    /** Largest `imu.txt` read: 64 MiB, about half an hour at 400 Hz (ecvo-io's `MAX_IMU_BYTES`). */
    const val MAX_BYTES: Long = 64L shl 20

    /** Largest angular rate read (rad/s): phone gyroscopes saturate at about 35 (2000 °/s); as ecvo-io. */
    const val MAX_RATE_RAD_S: Double = 100.0

    /** Largest acceleration read (m/s²): phone accelerometers saturate at about 160 (16 g); as ecvo-io. */
    const val MAX_ACCEL_M_S2: Double = 1000.0

    /** Longest line read (characters), so that a file without newlines cannot fill memory. */
    const val MAX_LINE_CHARS: Int = 4096

    /** One sample's line: the timestamp with 9 decimals (exact nanoseconds), the rates with float precision. */
    fun line(timestampNs: Long, wx: Float, wy: Float, wz: Float): String =
        "${formatSeconds9(timestampNs)} $wx $wy $wz\n"

    /** [ns] as seconds with exactly 9 decimals; negative values keep their sign. */
    fun formatSeconds9(ns: Long): String {
        val neg = ns < 0
        val a = if (neg) -ns else ns
        return (if (neg) "-" else "") + "${a / 1_000_000_000}.${(a % 1_000_000_000).toString().padStart(9, '0')}"
    }

    /** Parses `imu.txt` text; [source] names the file in errors. */
    fun parse(text: String, source: String = FILE_NAME): ImuData {
        val bytes = text.toByteArray(Charsets.UTF_8)
        return read(ByteArrayInputStream(bytes), bytes.size.toLong(), source)
    }

    /** Reads an `imu.txt` file. */
    fun read(file: File): ImuData {
        if (!file.isFile) throw IOException("${file.path}: not a regular file")
        return file.inputStream().use { read(it, file.length(), file.path) }
    }

    /** Reads the `imu.txt` of the stream in [files], or null when it has none. */
    fun read(files: StreamFiles): ImuData? {
        if (!files.exists(FILE_NAME)) return null
        val bytes = files.readBytes(FILE_NAME)
        return read(ByteArrayInputStream(bytes), bytes.size.toLong(), "${files.description}/$FILE_NAME")
    }

    /** Reads [length] bytes of `imu.txt` from [input]. */
    fun read(input: InputStream, length: Long, source: String): ImuData {
        if (length > MAX_BYTES) throw IOException("$source: $length bytes, more than the $MAX_BYTES an imu.txt may have")
        val r = BufferedReader(InputStreamReader(LimitedInput(input, MAX_BYTES, source), Charsets.UTF_8))
        var n = 0
        var ts = LongArray(1024)
        var gyro = DoubleArray(3 * 1024)
        var accel: DoubleArray? = null
        var fields = 0
        var lineNo = 0
        val buf = StringBuilder()
        while (true) {
            buf.setLength(0)
            if (!readLine(r, buf, source, lineNo + 1)) break
            lineNo++
            val t = buf.trim()
            if (t.isEmpty() || t.startsWith("#")) continue
            val f = t.split(WHITESPACE)
            if (f.size != 4 && f.size != 7) throw IOException("$source:$lineNo: expected `timestamp wx wy wz [ax ay az]`, found ${f.size} field(s)")
            if (fields == 0) {
                fields = f.size
                if (fields == 7) accel = DoubleArray(gyro.size)
            } else if (f.size != fields) {
                throw IOException("$source:$lineNo: ${f.size} fields, but the first sample had $fields")
            }
            val tNs = try {
                Timestamps.parseSecondsToNs(f[0])
            } catch (e: ArithmeticException) {
                throw IOException("$source:$lineNo: timestamp ${f[0]} is out of range")
            } catch (e: NumberFormatException) {
                throw IOException("$source:$lineNo: `${f[0]}` is not a number")
            }
            if (n > 0 && tNs <= ts[n - 1]) throw IOException("$source:$lineNo: timestamp ${f[0]} is not after the previous one")
            if (n == ts.size) {
                ts = ts.copyOf(2 * n)
                gyro = gyro.copyOf(6 * n)
                accel = accel?.copyOf(6 * n)
            }
            ts[n] = tNs
            for (k in 0 until 3) {
                val w = TumTrajectory.parseNumber(f[1 + k], source, lineNo)
                if (kotlin.math.abs(w) > MAX_RATE_RAD_S) throw IOException("$source:$lineNo: angular rate ${f[1 + k]} rad/s is beyond any gyroscope ($MAX_RATE_RAD_S)")
                gyro[3 * n + k] = w
            }
            accel?.let { a ->
                for (k in 0 until 3) {
                    val v = TumTrajectory.parseNumber(f[4 + k], source, lineNo)
                    if (kotlin.math.abs(v) > MAX_ACCEL_M_S2) throw IOException("$source:$lineNo: acceleration ${f[4 + k]} m/s² is beyond any accelerometer ($MAX_ACCEL_M_S2)")
                    a[3 * n + k] = v
                }
            }
            n++
        }
        return ImuData(ts.copyOf(n), gyro.copyOf(3 * n), accel?.copyOf(3 * n))
    }

    /** Reads one line into [out]; false at the end of the input. Refuses lines longer than [MAX_LINE_CHARS]. */
    private fun readLine(r: BufferedReader, out: StringBuilder, source: String, lineNo: Int): Boolean {
        var c = r.read()
        if (c < 0) return false
        while (c >= 0 && c != '\n'.code) {
            if (out.length == MAX_LINE_CHARS) throw IOException("$source:$lineNo: line longer than $MAX_LINE_CHARS characters")
            out.append(c.toChar())
            c = r.read()
        }
        return true
    }

    private val WHITESPACE = Regex("\\s+")

    /** An input that refuses to give more than [limit] bytes (a file that grows while it is read). */
    private class LimitedInput(private val input: InputStream, private val limit: Long, private val source: String) : InputStream() {
        private var read = 0L

        override fun read(): Int {
            val b = input.read()
            if (b >= 0) count(1)
            return b
        }

        override fun read(b: ByteArray, off: Int, len: Int): Int {
            val n = input.read(b, off, len)
            if (n > 0) count(n.toLong())
            return n
        }

        private fun count(n: Long) {
            read += n
            if (read > limit) throw IOException("$source: more than the $limit bytes an imu.txt may have")
        }
    }
}

/**
 * Writes a recording's `imu.txt` ([ImuFile]) as samples come: [write] appends a batch
 * (one sensor callback's worth, or what a frame drained) and flushes it, so a recording
 * cut short keeps its samples up to the last batch. Samples must come in increasing time;
 * one not after the previous is skipped and counted in [samplesRefused]. Thread-safe.
 */
class ImuRecorder(val dir: File) : AutoCloseable {
    private val out: FileOutputStream
    private val writer: Writer
    private var last = Long.MIN_VALUE
    private var closed = false

    /** Samples written. */
    @get:Synchronized
    var samplesWritten: Long = 0
        private set

    /** Samples skipped because their timestamp was not after the previous one's. */
    @get:Synchronized
    var samplesRefused: Long = 0
        private set

    init {
        val f = File(dir, ImuFile.FILE_NAME)
        if (f.exists()) throw IOException("$f already exists; refusing to overwrite it")
        out = FileOutputStream(f)
        writer = OutputStreamWriter(out, Charsets.UTF_8)
        writer.write(ImuFile.HEADER)
        writer.flush()
    }

    /** Appends samples `0 until n`: timestamps [timestampsNs] (frames' clock), rates [gyro] (3 per sample). */
    @Synchronized
    fun write(timestampsNs: LongArray, gyro: FloatArray, n: Int) {
        check(!closed) { "ImuRecorder for $dir is closed" }
        require(n in 0..timestampsNs.size && 3 * n <= gyro.size) { "$n samples do not fit the arrays (${timestampsNs.size}, ${gyro.size})" }
        for (i in 0 until n) {
            val t = timestampsNs[i]
            if (t <= last) {
                samplesRefused++
                continue
            }
            writer.write(ImuFile.line(t, gyro[3 * i], gyro[3 * i + 1], gyro[3 * i + 2]))
            last = t
            samplesWritten++
        }
        writer.flush()
    }

    /** Flushes, syncs and closes; calling it again does nothing. */
    @Synchronized
    override fun close() {
        if (closed) return
        closed = true
        try {
            writer.flush(); out.fd.sync()
        } finally {
            writer.close()
        }
    }
}
