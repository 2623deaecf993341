package io.ecvo.shared

import io.ecvo.TimedPose
import java.io.File
import java.io.IOException
import kotlin.math.sqrt

/**
 * Trajectories in the TUM format that `ecvo`, evo and the TUM tools read: one
 * `timestamp tx ty tz qx qy qz qw` line per pose, `#` comments allowed.
 */
object TumTrajectory {
    /** Header line written before the poses. */
    const val HEADER: String = "# timestamp tx ty tz qx qy qz qw"

    /** The text of a trajectory file: header, then every number in plain decimal with round-trip precision. */
    fun format(poses: List<TimedPose>): String = buildString {
        append(HEADER).append('\n')
        for (p in poses) {
            listOf(p.timestamp, p.tx, p.ty, p.tz, p.qx, p.qy, p.qz, p.qw).joinTo(this, " ") { Timestamps.plain(it) }
            append('\n')
        }
    }

    /** Writes [poses] to [file]. */
    fun write(file: File, poses: List<TimedPose>) = file.writeText(format(poses))

    /**
     * Parses trajectory text: 8 numbers per data line, strictly increasing timestamps,
     * quaternions normalised (a near-zero quaternion is an error). [source] names the
     * file in error messages.
     */
    fun parse(text: String, source: String): List<TimedPose> {
        val out = ArrayList<TimedPose>()
        var prev = Double.NEGATIVE_INFINITY
        for ((line, fields) in records(text)) {
            if (fields.size != 8) throw IOException("$source:$line: expected `timestamp tx ty tz qx qy qz qw`, found ${fields.size} field(s)")
            val v = DoubleArray(8) { k -> parseNumber(fields[k], source, line) }
            if (v[0] <= prev) throw IOException("$source:$line: timestamp ${fields[0]} is not after the previous one")
            prev = v[0]
            val n = sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7])
            if (n < 1e-6) throw IOException("$source:$line: quaternion is (near) zero")
            out += TimedPose(v[0], v[1], v[2], v[3], v[4] / n, v[5] / n, v[6] / n, v[7] / n)
        }
        return out
    }

    /** Reads a trajectory file. */
    fun read(file: File): List<TimedPose> = parse(file.readText(), file.path)

    /** The data lines of [text] with their 1-based numbers: blank lines and `#` comments skipped. */
    internal fun records(text: String): List<Pair<Int, List<String>>> =
        text.lines().mapIndexedNotNull { i, l ->
            val t = l.trim()
            if (t.isEmpty() || t.startsWith("#")) null else (i + 1) to t.split(Regex("\\s+"))
        }

    internal fun parseNumber(s: String, source: String, line: Int): Double {
        val v = s.toDoubleOrNull() ?: throw IOException("$source:$line: `$s` is not a number")
        if (!v.isFinite()) throw IOException("$source:$line: `$s` is not finite")
        return v
    }
}
