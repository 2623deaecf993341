// Exercises kotlin-stdlib functions whose bodies bootstrap lambdas through LambdaMetafactory
// (the ones the app reaches, and a few more). test-desugar.sh runs it on the JVM with the
// original stdlib and with the LambdaDesugar'ed one: the outputs must be the same.
package desugarprobe

import java.io.File

data class P(val a: Int, val b: String)

fun main() {
    val ps = listOf(P(2, "x"), P(1, "z"), P(2, "a"), P(1, "b"))
    println(ps.sortedWith(compareBy({ it.a }, { it.b })))
    println("a,b;;c,d".split(',', ';'))
    println("k=v, k2=v2".split(", ").map { it.split('=') })
    println(ps.joinToString(" | ") { it.b })
    println(ps.map { it.a }.toString())
    println(ArrayDeque(listOf(1, 2, 3)).toString()) // kotlin.collections.AbstractCollection-based
    println(setOf(3, 1, 2).toString())
    println(Regex("[0-9]+").findAll("a1b22c333").map { it.value }.toList())
    println("  trim me ".trim().lines())
    val dir = File(System.getProperty("java.io.tmpdir"), "desugar-probe-" + ProcessHandle.current().pid())
    val src = File(dir, "src/sub").apply { mkdirs() }
    File(src, "f.txt").writeText("hello")
    File(dir, "src").copyRecursively(File(dir, "dst"), overwrite = true)
    println(File(dir, "dst/sub/f.txt").readText())
    dir.deleteRecursively()
}
