package io.ecvo

import java.io.File
import java.nio.ByteBuffer
import java.nio.ByteOrder
import org.junit.Assert.assertEquals
import org.junit.Assume.assumeTrue

/**
 * The replay stream of scripts/jni-jvm-tests.sh (`--example jvm_test_data`), shared by the
 * JNI boundary tests. Environment:
 * - `ECVO_JNI_TEST_DATA`: folder with `meta.txt` (width height fx fy cx cy frames),
 *   `frames.bin` (per frame: i64 ns, width*height u16 depth, width*height u8 intensity,
 *   little-endian) and `expected.txt` (per frame: ns, 16 float bits of the column-major
 *   pose, 8 double bits of the trajectory row) produced by ecvo-pipeline in Rust.
 */
internal class JvmTestStream(
    val width: Int, val height: Int, val fx: Double, val fy: Double, val cx: Double, val cy: Double,
    val stamps: LongArray, val depth: List<ShortArray>, val intensity: List<ByteArray>,
    val expectedMatrices: List<FloatArray>, val expectedTrajectory: DoubleArray,
) {
    companion object {
        fun dataDir(): File? = System.getenv("ECVO_JNI_TEST_DATA")?.let(::File)

        /** Loads the stream; skips the calling test (an assumption) when the data is not set. */
        fun load(): JvmTestStream {
            val dir = dataDir()
            assumeTrue("ECVO_JNI_TEST_DATA is not set (run through tests/jvm.rs)", dir != null)
            val meta = File(dir, "meta.txt").readText().trim().split(Regex("\\s+"))
            val w = meta[0].toInt(); val h = meta[1].toInt(); val n = meta[6].toInt()
            val bytes = ByteBuffer.wrap(File(dir, "frames.bin").readBytes()).order(ByteOrder.LITTLE_ENDIAN)
            val stamps = LongArray(n)
            val depth = ArrayList<ShortArray>(); val intensity = ArrayList<ByteArray>()
            for (f in 0 until n) {
                stamps[f] = bytes.long
                val d = ShortArray(w * h); for (i in d.indices) d[i] = bytes.short
                val g = ByteArray(w * h); bytes.get(g)
                depth += d; intensity += g
            }
            val mats = ArrayList<FloatArray>(); val traj = ArrayList<Double>()
            File(dir, "expected.txt").readLines().filter { it.isNotBlank() }.forEachIndexed { i, line ->
                val v = line.trim().split(" ")
                assertEquals("expected.txt line $i timestamp", stamps[i], v[0].toLong())
                mats += FloatArray(16) { java.lang.Float.intBitsToFloat(v[1 + it].toInt()) }
                for (k in 0 until 8) traj += java.lang.Double.longBitsToDouble(v[17 + k].toLong())
            }
            return JvmTestStream(w, h, meta[2].toDouble(), meta[3].toDouble(), meta[4].toDouble(), meta[5].toDouble(),
                stamps, depth, intensity, mats, traj.toDoubleArray())
        }
    }
}
