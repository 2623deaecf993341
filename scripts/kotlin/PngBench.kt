package io.ecvo.bench

import io.ecvo.shared.DirectoryFiles
import io.ecvo.shared.Png
import io.ecvo.shared.PngFilter
import io.ecvo.shared.StreamReader
import java.io.File
import java.util.zip.Deflater

/**
 * Times the recorder's per-frame PNG encodes (8-bit intensity + 16-bit depth) for a few
 * filter / compression settings on the frames of a real stream, at its size and halved.
 * Usage: PngBench STREAM_DIR [FRAMES] [REPEATS]. Prints median, mean, p95 (ms per frame)
 * and bytes per frame, and the ratio of each median to the first setting's (the old default).
 * Run (after scripts/kotlin/test-kotlin.sh built target/kotlin/shared.jar and tracker.jar), K being kotlinc's
 * npm folder (~/.cache/ecvo/kotlinc/node_modules/kotlin-compiler):
 *   $K/bin/kotlinc -jvm-target 17 -cp target/kotlin/shared.jar:target/kotlin/tracker.jar \
 *     -d target/kotlin/bench scripts/kotlin/PngBench.kt
 *   java -cp target/kotlin/bench:target/kotlin/shared.jar:target/kotlin/tracker.jar:$K/lib/kotlin-stdlib.jar \
 *     io.ecvo.bench.PngBenchKt /work/shared/datasets/tum_fr1_xyz_full300 30 3
 */
fun main(args: Array<String>) {
    val dir = File(args.getOrNull(0) ?: error("usage: PngBench STREAM_DIR [FRAMES] [REPEATS]"))
    val count = args.getOrNull(1)?.toInt() ?: 30
    val repeats = args.getOrNull(2)?.toInt() ?: 3
    val reader = StreamReader(DirectoryFiles(dir))
    val w = reader.camera.width
    val h = reader.camera.height
    val frames = reader.take(count).map { it.depth.copyOf() to it.intensity.copyOf() }
    val half = frames.map { (d, g) ->
        ShortArray((w / 2) * (h / 2)) { i -> d[(2 * (i / (w / 2)) + 1) * w + 2 * (i % (w / 2)) + 1] } to
            ByteArray((w / 2) * (h / 2)) { i -> g[(2 * (i / (w / 2)) + 1) * w + 2 * (i % (w / 2)) + 1] }
    }
    class Setting(val name: String, val filter: PngFilter, val level: Int, val strategy: Int = Deflater.DEFAULT_STRATEGY)
    val settings = listOf(
        Setting("adaptive, level 1 (old default)", PngFilter.ADAPTIVE, 1),
        Setting("sub, level 1", PngFilter.SUB, 1),
        Setting("up, level 1", PngFilter.UP, 1),
        Setting("sub, huffman only", PngFilter.SUB, 1, Deflater.HUFFMAN_ONLY),
        Setting("up, huffman only", PngFilter.UP, 1, Deflater.HUFFMAN_ONLY),
        Setting("none, level 0 (stored)", PngFilter.NONE, 0),
    )
    for ((label, set, fw, fh) in listOf(Quad("native", frames, w, h), Quad("halved", half, w / 2, h / 2))) {
        println("$label ${fw}x$fh, ${set.size} frames x $repeats repeats (${System.getProperty("java.vm.name")} ${System.getProperty("java.version")})")
        var base = 0.0
        for (s in settings) {
            val times = ArrayList<Double>()
            var bytes = 0L
            repeat(repeats + 1) { r ->
                for ((d, g) in set) {
                    val t0 = System.nanoTime()
                    val a = Png.encodeGray8(g, fw, fh, s.filter, s.level, s.strategy)
                    val b = Png.encodeGray16(d, fw, fh, s.filter, s.level, s.strategy)
                    val ms = (System.nanoTime() - t0) / 1e6
                    if (r > 0) { times += ms; bytes += a.size + b.size } // the first pass warms the JIT
                }
            }
            times.sort()
            val median = times[times.size / 2]
            val mean = times.average()
            val p95 = times[(times.size * 95 / 100).coerceAtMost(times.size - 1)]
            if (base == 0.0) base = median
            println(String.format(java.util.Locale.ROOT, "  %-34s median %6.2f  mean %6.2f  p95 %6.2f ms  %7d B/frame  median ratio %.2f",
                s.name, median, mean, p95, bytes / times.size, median / base))
        }
    }
}

private data class Quad(val label: String, val frames: List<Pair<ShortArray, ByteArray>>, val w: Int, val h: Int)
