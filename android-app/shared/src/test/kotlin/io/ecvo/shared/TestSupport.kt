package io.ecvo.shared

import java.io.File
import java.nio.file.Files
import org.junit.Assert.fail

/** Helpers shared by the tests of this module. */
object TestSupport {
    /** The repository root (the test script passes -Decvo.repo; Gradle runs from the module folder). */
    val repo: File by lazy {
        System.getProperty("ecvo.repo")?.let { return@lazy File(it) }
        var d: File? = File("").absoluteFile
        while (d != null && !File(d, "Cargo.toml").isFile) d = d.parentFile
        d ?: File("").absoluteFile
    }

    /** The shared RGB-D datasets beside the repository (may be missing on other machines). */
    val datasets: File by lazy {
        System.getenv("ECVO_DATASETS")?.let { return@lazy File(it) }
        listOf(File(repo, "../shared/datasets"), File("/work/shared/datasets")).firstOrNull { it.isDirectory } ?: File(repo, "../shared/datasets")
    }

    fun tempDir(): File = Files.createTempDirectory("ecvo-test").toFile().also { it.deleteOnExit() }

    inline fun <reified E : Throwable> assertThrows(block: () -> Unit): E {
        try {
            block()
        } catch (e: Throwable) {
            if (e is E) return e
            throw AssertionError("expected ${E::class.simpleName}, got $e", e)
        }
        fail("expected ${E::class.simpleName}, nothing thrown")
        throw IllegalStateException()
    }
}
