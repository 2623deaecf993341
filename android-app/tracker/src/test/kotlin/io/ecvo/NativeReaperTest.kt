package io.ecvo

import java.io.File
import java.net.URLClassLoader
import java.util.concurrent.CountDownLatch
import java.util.concurrent.TimeUnit
import java.util.concurrent.atomic.AtomicInteger
import java.util.zip.ZipFile
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Test

/** Touches `java.lang.ref.Cleaner` when initialised: proves [HidingLoader] hides it. */
object CleanerProbe {
    @JvmField val cleaner: Any = java.lang.ref.Cleaner.create()
}

/**
 * Loads `io.ecvo.*` from [urls] itself (child first) and refuses `java.lang.ref.Cleaner`,
 * as an Android runtime before API 33 has none.
 */
private class HidingLoader(urls: Array<java.net.URL>, parent: ClassLoader) : URLClassLoader(urls, parent) {
    override fun loadClass(name: String, resolve: Boolean): Class<*> {
        if (name == "java.lang.ref.Cleaner" || name.startsWith("java.lang.ref.Cleaner$")) throw ClassNotFoundException("$name (hidden: API 33)")
        if (!name.startsWith("io.ecvo.")) return super.loadClass(name, resolve)
        synchronized(getClassLoadingLock(name)) {
            val c = findLoadedClass(name) ?: findClass(name)
            if (resolve) resolveClass(c)
            return c
        }
    }
}

class NativeReaperTest {
    private fun collectUntil(latch: CountDownLatch) {
        val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(20)
        while (latch.count > 0 && System.nanoTime() < deadline) {
            System.gc()
            // Garbage to make a collection likely on every JVM.
            @Suppress("UNUSED_VARIABLE") val junk = ByteArray(1 shl 20)
            latch.await(50, TimeUnit.MILLISECONDS)
        }
    }

    /** Registers an owner in a frame of its own, so that nothing on this stack keeps it. */
    private fun registerDropped(reaper: NativeReaper, action: Runnable) {
        reaper.register(Any(), action)
    }

    @Test
    fun theActionOfADroppedOwnerRunsOnceOnTheReaperThread() {
        val reaper = NativeReaper("test-reaper")
        val latch = CountDownLatch(1)
        val runs = AtomicInteger()
        val thread = arrayOfNulls<String>(1)
        registerDropped(reaper) {
            thread[0] = Thread.currentThread().name
            runs.incrementAndGet()
            latch.countDown()
        }
        assertEquals(1, reaper.pendingCount)
        collectUntil(latch)
        assertEquals("the handle of a dropped owner was not released", 0L, latch.count)
        Thread.sleep(50)
        assertEquals(1, runs.get())
        assertEquals(0, reaper.pendingCount)
        assertTrue(thread[0] == "test-reaper" || thread[0] == Thread.currentThread().name)
    }

    @Test
    fun cleanRunsTheActionNowAndNeverAgain() {
        val reaper = NativeReaper("test-reaper-2")
        val runs = AtomicInteger()
        val owner = Any()
        val c = reaper.register(owner) { runs.incrementAndGet() }
        c.clean()
        c.clean()
        assertEquals(1, runs.get())
        assertEquals(0, reaper.pendingCount)
    }

    @Test
    fun aThrowingActionDoesNotStopTheReaper() {
        val reaper = NativeReaper("test-reaper-3")
        registerDropped(reaper) { throw IllegalStateException("boom") }
        val latch = CountDownLatch(1)
        registerDropped(reaper) { latch.countDown() }
        collectUntil(latch)
        assertEquals(0L, latch.count)
    }

    private val trackerJar: File get() = File(Tracker::class.java.protectionDomain.codeSource.location.toURI())

    @Test
    fun noClassOfTheTrackerModuleReferencesCleaner() {
        val jar = trackerJar
        val classes = ArrayList<Pair<String, ByteArray>>()
        if (jar.isFile) {
            ZipFile(jar).use { z ->
                for (e in z.entries()) if (e.name.endsWith(".class")) classes += e.name to z.getInputStream(e).readBytes()
            }
        } else {
            jar.walkTopDown().filter { it.name.endsWith(".class") }.forEach { classes += it.path to it.readBytes() }
        }
        assertTrue("found no classes in $jar", classes.any { it.first.endsWith("io/ecvo/Tracker.class") })
        for ((name, bytes) in classes) {
            // Class files name referenced classes in their constant pool as UTF-8 internal names.
            assertTrue("$name references java/lang/ref/Cleaner", String(bytes, Charsets.ISO_8859_1).indexOf("java/lang/ref/Cleaner") < 0)
        }
    }

    @Test
    fun trackerInitialisesWhereCleanerDoesNotExist() {
        val parent = NativeReaperTest::class.java.classLoader
        val probeDir = File(CleanerProbe::class.java.protectionDomain.codeSource.location.toURI())
        HidingLoader(arrayOf(probeDir.toURI().toURL()), parent).use { l ->
            // The loader does hide Cleaner: the probe fails as the old Tracker did on API 26-32.
            try {
                Class.forName("io.ecvo.CleanerProbe", true, l)
                fail("the hiding class loader let java.lang.ref.Cleaner through")
            } catch (e: NoClassDefFoundError) {
                assertTrue(e.toString(), e.toString().contains("Cleaner"))
            }
        }
        HidingLoader(arrayOf(trackerJar.toURI().toURL()), parent).use { l ->
            val tracker = Class.forName("io.ecvo.Tracker", true, l) // runs the companion's initialiser
            assertEquals(l, tracker.classLoader)
            Class.forName("io.ecvo.NativeReaper", true, l)
            val noPose = tracker.getField("NO_POSE").getLong(null)
            assertEquals(Long.MIN_VALUE, noPose)
        }
    }
}
