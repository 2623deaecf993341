// The JVM test runner of scripts/kotlin/test-kotlin.sh: runs every JUnit 4 test class found
// under the given class folders and ends with the line `N passed, N failed`, which CI reads.
// Exit status: 0 if everything passed (and at least one test ran), 1 otherwise.
package io.ecvo.testmain

import java.io.File
import java.lang.reflect.Modifier
import org.junit.runner.Description
import org.junit.runner.JUnitCore
import org.junit.runner.Request
import org.junit.runner.notification.Failure
import org.junit.runner.notification.RunListener

private fun testClasses(root: File, loader: ClassLoader): List<Class<*>> =
    root.walkTopDown()
        .filter { it.isFile && it.name.endsWith(".class") && '$' !in it.name }
        .map { it.relativeTo(root).path.removeSuffix(".class").replace(File.separatorChar, '.') }
        .sorted()
        .mapNotNull { name -> runCatching { Class.forName(name, false, loader) }.getOrNull() }
        .filter { c ->
            !Modifier.isAbstract(c.modifiers) && c.methods.any { it.isAnnotationPresent(org.junit.Test::class.java) }
        }
        .toList()

fun main(args: Array<String>) {
    // Usage: TestMain <test-classes-dir>... [--filter SUBSTRING]
    val dirs = mutableListOf<File>()
    var filter: String? = null
    var i = 0
    while (i < args.size) {
        if (args[i] == "--filter") { filter = args.getOrNull(i + 1); i += 2 } else { dirs += File(args[i]); i++ }
    }
    val loader = Thread.currentThread().contextClassLoader
    val classes = dirs.flatMap { testClasses(it, loader) }
    var passed = 0
    var failed = 0
    val failedTests = HashSet<Description>()
    val core = JUnitCore()
    core.addListener(object : RunListener() {
        override fun testFailure(failure: Failure) {
            failed++
            failedTests += failure.description
            println("FAIL ${failure.description.displayName}")
            println(failure.trimmedTrace.prependIndent("    "))
        }

        override fun testAssumptionFailure(failure: Failure) {
            failedTests += failure.description
            println("SKIP ${failure.description.displayName}: ${failure.message}")
        }

        override fun testIgnored(description: Description) {
            println("SKIP ${description.displayName} (@Ignore)")
        }

        override fun testFinished(description: Description) {
            if (description !in failedTests) {
                passed++
                println("ok   ${description.displayName}")
            }
        }
    })
    for (c in classes) {
        var request = Request.aClass(c)
        if (filter != null) {
            val f = filter
            request = request.filterWith(object : org.junit.runner.manipulation.Filter() {
                override fun shouldRun(d: Description) = d.isSuite || d.displayName.contains(f)
                override fun describe() = "contains $f"
            })
        }
        core.run(request)
    }
    if (classes.isEmpty()) println("no test classes found under ${dirs.joinToString()}")
    println("$passed passed, $failed failed")
    kotlin.system.exitProcess(if (failed == 0 && passed > 0) 0 else 1)
}
