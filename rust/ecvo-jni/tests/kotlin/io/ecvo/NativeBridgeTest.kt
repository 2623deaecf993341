package io.ecvo

import java.io.File
import java.nio.ByteBuffer
import java.nio.ByteOrder
import java.util.concurrent.CountDownLatch
import java.util.concurrent.atomic.AtomicInteger
import java.util.concurrent.atomic.AtomicReference
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Assert.fail
import org.junit.Assume.assumeTrue
import org.junit.Test

/**
 * The JNI boundary of libecvo_jni, run on a real JVM with -Xcheck:jni by
 * `rust/ecvo-jni/tests/jvm.rs` (through scripts/kotlin/test-kotlin.sh --native-lib).
 *
 * Environment set by that test:
 * - `ECVO_JNI_TEST_DATA`: folder with `meta.txt` (width height fx fy cx cy frames),
 *   `frames.bin` (per frame: i64 ns, width*height u16 depth, width*height u8 intensity,
 *   little-endian) and `expected.txt` (per frame: ns, 16 float bits of the column-major
 *   pose, 8 double bits of the trajectory row) produced by ecvo-pipeline in Rust.
 * - `ECVO_JNI_TEST_HOOKS=1`: the library was built with the `test-hooks` feature.
 */
class NativeBridgeTest {
    private inline fun <reified E : Throwable> assertThrows(contains: String? = null, block: () -> Unit): E {
        try {
            block()
        } catch (e: Throwable) {
            if (e is E) {
                if (contains != null) {
                    assertTrue("message '${e.message}' should mention '$contains'", e.message?.contains(contains) == true)
                }
                return e
            }
            throw AssertionError("expected ${E::class.simpleName}, got $e", e)
        }
        fail("expected ${E::class.simpleName}, nothing thrown")
        throw IllegalStateException()
    }

    private fun dataDir(): File? = JvmTestStream.dataDir()

    private fun stream(): JvmTestStream = JvmTestStream.load()

    private fun config(s: JvmTestStream? = null, admission: Admission = Admission.OFFLINE) = TrackerConfig(
        width = s?.width ?: 320, height = s?.height ?: 180,
        fx = s?.fx ?: 250.0, fy = s?.fy ?: 250.0, cx = s?.cx ?: 159.5, cy = s?.cy ?: 89.5,
        preset = Preset.PHONE, mode = Mode.L2, admission = admission, threads = 2, pointCloud = true,
    )

    private val pixels = 320 * 180

    private fun directDepth(n: Int = pixels): ByteBuffer = ByteBuffer.allocateDirect(2 * n).order(ByteOrder.nativeOrder())
    private fun directGray(n: Int = pixels): ByteBuffer = ByteBuffer.allocateDirect(n)

    // --- replay: the JNI poses equal ecvo-pipeline's --------------------------------------

    @Test
    fun replayWithArraysMatchesTheRustPipeline() {
        val s = stream()
        Tracker(config(s)).use { t ->
            val m = FloatArray(16)
            assertEquals(Tracker.NO_POSE, t.getPose(m))
            assertEquals(TrackingState.INITIALISING, t.state)
            for (i in s.stamps.indices) {
                assertEquals(PushStatus.ACCEPTED, t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i]))
                t.flush()
                assertEquals("timestamp of frame $i", s.stamps[i], t.getPose(m))
                assertArrayEquals("pose of frame $i", s.expectedMatrices[i], m, 0f)
            }
            val traj = NativeBridgeAccess.trajectory(t)
            assertArrayEquals(s.expectedTrajectory, traj, 0.0)
            assertEquals(s.stamps.size, t.trajectory().size)
            val refs = t.references()
            assertTrue("references", refs.isNotEmpty() && refs.all { it.level in 1..2 })
            val stats = t.stats()
            assertEquals(s.stamps.size.toLong(), stats.framesPushed)
            assertEquals(s.stamps.size.toLong(), stats.framesTracked)
            assertEquals(0L, stats.framesDropped)
            assertTrue(stats.motionEstimations >= s.stamps.size - 1)
            val cloud = t.pointCloud(1000)
            assertTrue("cloud has points", cloud.isNotEmpty() && cloud.size <= 4000 && cloud.size % 4 == 0)
            for (p in cloud.indices step 4) assertTrue(cloud[p + 3] in 0f..1f)
            assertEquals(0, t.pointCloud(0).size)
            assertTrue(t.state != TrackingState.INITIALISING)
        }
    }

    @Test
    fun replayWithDirectBuffersMatchesTheRustPipeline() {
        val s = stream()
        val d = directDepth(s.width * s.height); val g = directGray(s.width * s.height)
        Tracker(config(s)).use { t ->
            for (i in s.stamps.indices) {
                d.clear(); d.asShortBuffer().put(s.depth[i])
                g.clear(); g.put(s.intensity[i]).rewind() // the frame lies from position() to limit()
                // The caller may scribble over its buffers once pushFrame returns.
                assertEquals(PushStatus.ACCEPTED, t.pushFrame(s.stamps[i], d, g))
                g.clear(); while (g.hasRemaining()) g.put(0x55)
            }
            t.flush()
            assertArrayEquals(s.expectedTrajectory, NativeBridgeAccess.trajectory(t), 0.0)
        }
    }

    @Test
    fun depth16WithFullConfidenceMatchesMillimetres() {
        val s = stream()
        assumeTrue("depth fits 13 bits", s.depth.all { f -> f.all { (it.toInt() and 0xFFFF) < 8192 } })
        val cfg = config(s).copy(depthFormat = DepthFormat.DEPTH16, minConfidence = 7)
        Tracker(cfg).use { t ->
            for (i in s.stamps.indices) t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i]) // raw confidence 0 = 100 %
            t.flush()
            assertArrayEquals(s.expectedTrajectory, NativeBridgeAccess.trajectory(t), 0.0)
        }
        // Raw confidence 1 (0 %) is below minConfidence 1: every pixel dropped, nothing registers.
        Tracker(cfg.copy(minConfidence = 1)).use { t ->
            for (i in 0 until 3) {
                val d = ShortArray(s.depth[i].size) { k -> (s.depth[i][k].toInt() or (1 shl 13)).toShort() }
                t.pushFrame(s.stamps[i], d, s.intensity[i])
            }
            t.flush()
            val st = t.stats()
            assertEquals(3L, st.framesPushed)
            assertTrue("no valid depth: frames lost or not tracked (${st})", st.lostFrames > 0 || st.framesTracked < 3)
        }
    }

    // --- incremental reads, strided planes, automatic confidence, the Cleaner ------------

    @Test
    fun trajectorySinceReturnsOnlyTheNewPoses() {
        val s = stream()
        Tracker(config(s)).use { t ->
            assertEquals(0, t.trajectorySince(0).size)
            val seen = ArrayList<TimedPose>()
            for (i in s.stamps.indices) {
                t.pushFrame(s.stamps[i], s.depth[i], s.intensity[i])
                if (i % 3 == 0) { t.flush(); seen += t.trajectorySince(seen.size) }
            }
            t.flush()
            seen += t.trajectorySince(seen.size)
            assertEquals(TimedPose.listFromArray(s.expectedTrajectory), seen)
            assertEquals(0, t.trajectorySince(seen.size + 5).size)
            assertEquals(seen.subList(seen.size - 2, seen.size), t.trajectorySince(seen.size - 2))
            assertThrows<IllegalArgumentException>("from") { NativeBridge.nativeTrajectorySince(handleOf(t), -1) }
        }
    }

    @Test
    fun paddedPlanesGiveTheSamePosesAsPackedOnes() {
        val s = stream()
        val w = s.width; val h = s.height
        val depthStride = 2 * w + 64; val grayStride = w + 32
        // Like an Image plane: padded rows, the last row without padding.
        val d = ByteBuffer.allocateDirect(depthStride * (h - 1) + 2 * w).order(ByteOrder.nativeOrder())
        val g = ByteBuffer.allocateDirect(grayStride * (h - 1) + w)
        Tracker(config(s)).use { t ->
            for (i in s.stamps.indices) {
                for (y in 0 until h) {
                    for (x in 0 until w) d.putShort(y * depthStride + 2 * x, s.depth[i][y * w + x])
                    for (x in 0 until w) g.put(y * grayStride + x, s.intensity[i][y * w + x])
                    if (y < h - 1) {
                        for (p in 2 * w until depthStride) d.put(y * depthStride + p, 0x7F) // padding is never read
                        for (p in w until grayStride) g.put(y * grayStride + p, 0x7F)
                    }
                }
                assertEquals(PushStatus.ACCEPTED, t.pushFrame(s.stamps[i], d, depthStride, g, grayStride))
            }
            t.flush()
            assertArrayEquals(s.expectedTrajectory, NativeBridgeAccess.trajectory(t), 0.0)
        }
    }

    @Test fun badRowStridesAreRejectedWithTheirBuffer(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("depth: row stride") { t.pushFrame(1, directDepth(), 2 * 320 - 2, directGray(), 320) }
        assertThrows<IllegalArgumentException>("intensity: row stride") { t.pushFrame(1, directDepth(), 640, directGray(), 100) }
        assertThrows<IllegalArgumentException>("negative") { t.pushFrame(1, directDepth(), -640, directGray(), 320) }
        // A padded stride needs a bigger buffer than the packed frame.
        assertThrows<IllegalArgumentException>("intensity: buffer holds") { t.pushFrame(1, directDepth(), 640, directGray(), 400) }
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(2, directDepth(), 640, directGray(400 * 179 + 320), 400))
    }

    @Test
    fun autoConfidenceKeepsASensorThatMarksEverythingZeroPercent() {
        val s = stream()
        assumeTrue("depth fits 13 bits", s.depth.all { f -> f.all { (it.toInt() and 0xFFFF) < 8192 } })
        val cfg = config(s).copy(depthFormat = DepthFormat.DEPTH16, minConfidence = TrackerConfig.AUTO_CONFIDENCE)
        Tracker(cfg).use { t ->
            for (i in s.stamps.indices) {
                val d = ShortArray(s.depth[i].size) { k -> (s.depth[i][k].toInt() or (1 shl 13)).toShort() } // code 1, "0 %"
                t.pushFrame(s.stamps[i], d, s.intensity[i])
            }
            t.flush()
            assertArrayEquals(s.expectedTrajectory, NativeBridgeAccess.trajectory(t), 0.0)
        }
    }

    @Test
    fun aTrackerLeftToTheGarbageCollectorIsReleased() {
        // Made in a function of its own, so that no local keeps the Tracker reachable.
        fun leak(): Any = NativeBridgeAccess.handleObject(Tracker(config()))
        val handle = leak()
        val h = NativeBridgeAccess.value(handle)
        assertTrue(h != 0L)
        val deadline = System.nanoTime() + 10_000_000_000L
        while (NativeBridgeAccess.value(handle) != 0L && System.nanoTime() < deadline) {
            System.gc()
            Thread.sleep(20)
        }
        assertEquals("the Cleaner released the native tracker", 0L, NativeBridgeAccess.value(handle))
        assertThrows<IllegalStateException>("released") { NativeBridge.nativeState(h) }
    }

    // --- misuse ---------------------------------------------------------------------------

    @Test fun nullDepthBuffer(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("depth") { NativeBridge.nativePushBuffers(handleOf(t), 1, null, directGray()) }
    }

    @Test fun nullIntensityBuffer(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("intensity") { NativeBridge.nativePushBuffers(handleOf(t), 1, directDepth(), null) }
    }

    @Test fun nonDirectBuffers(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("not direct") { t.pushFrame(1, ByteBuffer.allocate(2 * pixels), directGray()) }
        assertThrows<IllegalArgumentException>("not direct") { t.pushFrame(1, directDepth(), ByteBuffer.allocate(pixels)) }
    }

    @Test fun shortDepthBuffer(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("depth") { t.pushFrame(1, directDepth(pixels - 1), directGray()) }
        // One sample per pixel is not enough: depth is 2 bytes per pixel.
        assertThrows<IllegalArgumentException>("depth") { t.pushFrame(1, ByteBuffer.allocateDirect(pixels), directGray()) }
    }

    @Test fun shortIntensityBuffer(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("intensity") { t.pushFrame(1, directDepth(), directGray(pixels - 1)) }
    }

    @Test fun largerBuffersAreAccepted(): Unit = Tracker(config()).use { t ->
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(1, directDepth(pixels + 10), directGray(pixels + 10)))
    }

    @Test fun wrongArrayLengths(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("depth") { t.pushFrame(1, ShortArray(pixels - 1), ByteArray(pixels)) }
        assertThrows<IllegalArgumentException>("depth") { t.pushFrame(1, ShortArray(pixels + 1), ByteArray(pixels)) }
        assertThrows<IllegalArgumentException>("intensity") { t.pushFrame(1, ShortArray(pixels), ByteArray(0)) }
    }

    @Test fun nullArrays(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("depth") { NativeBridge.nativePushArrays(handleOf(t), 1, null, ByteArray(pixels)) }
        assertThrows<IllegalArgumentException>("intensity") { NativeBridge.nativePushArrays(handleOf(t), 1, ShortArray(pixels), null) }
    }

    @Test fun nanIntrinsics() {
        assertThrows<IllegalArgumentException>("fx") { Tracker(config().copy(fx = Double.NaN)) }
        assertThrows<IllegalArgumentException>("cy") { Tracker(config().copy(cy = Double.POSITIVE_INFINITY)) }
        assertThrows<IllegalArgumentException>("fy") { Tracker(config().copy(fy = 0.0)) }
    }

    @Test fun zeroOrNegativeSize() {
        assertThrows<IllegalArgumentException>("width") { Tracker(config().copy(width = 0)) }
        assertThrows<IllegalArgumentException>("height") { Tracker(config().copy(height = -5)) }
    }

    @Test fun badCodes() {
        fun init(format: Int = 0, preset: Int = 1, mode: Int = 2) =
            NativeBridge.nativeInit(320, 180, 250.0, 250.0, 159.5, 89.5, format, 1000.0, 0, preset, mode, true, 2, false)
        assertThrows<IllegalArgumentException>("depthFormat") { init(format = 3) }
        assertThrows<IllegalArgumentException>("preset") { init(preset = -1) }
        assertThrows<IllegalArgumentException>("mode") { init(mode = 7) }
        val h = init()
        assertTrue(h != 0L)
        NativeBridge.nativeRelease(h)
    }

    @Test fun badScaleConfidenceThreads() {
        assertThrows<IllegalArgumentException>("depthScale") { Tracker(config().copy(depthFormat = DepthFormat.CUSTOM_SCALE, depthScale = 0.0)) }
        assertThrows<IllegalArgumentException>("depthScale") { Tracker(config().copy(depthFormat = DepthFormat.CUSTOM_SCALE, depthScale = Double.NaN)) }
        assertThrows<IllegalArgumentException>("minConfidence") { Tracker(config().copy(depthFormat = DepthFormat.DEPTH16, minConfidence = 8)) }
        assertThrows<IllegalArgumentException>("threads") { Tracker(config().copy(threads = 0)) }
        assertThrows<IllegalArgumentException>("threads") { Tracker(config().copy(threads = -1)) }
        // Ignored by the millimetre formats.
        Tracker(config().copy(depthScale = -1.0, minConfidence = 99)).close()
    }

    @Test fun getPoseArguments(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("out") { NativeBridge.nativeGetPose(handleOf(t), null) }
        assertThrows<IllegalArgumentException>("16") { t.getPose(FloatArray(15)) }
        val m = FloatArray(20) { 42f }
        assertEquals(Tracker.NO_POSE, t.getPose(m))
        assertTrue("out untouched without a pose", m.all { it == 42f })
    }

    @Test fun negativeMaxPoints(): Unit = Tracker(config()).use { t ->
        assertThrows<IllegalArgumentException>("maxPoints") { t.pointCloud(-1) }
    }

    @Test fun nonFiniteTimestampIsImpossibleButHugeOnesWork(): Unit = Tracker(config(admission = Admission.LIVE)).use { t ->
        assertEquals(PushStatus.ACCEPTED, t.pushFrame(Long.MAX_VALUE, ShortArray(pixels), ByteArray(pixels)))
        t.flush()
        assertEquals(Long.MAX_VALUE, t.getPose(FloatArray(16)))
    }

    @Test fun timestampsAreIntegerNanosecondsAndNoPoseIsNotOne(): Unit = Tracker(config()).use { t ->
        fun frame(k: Int) = ShortArray(pixels) { 1000 } to ByteArray(pixels) { ((it * 7 + k) % 251).toByte() }
        assertThrows<IllegalArgumentException>("NO_POSE") { t.pushFrame(Long.MIN_VALUE, frame(0).first, frame(0).second) }
        val base = 9_000_000_000_000_000_000L
        // 1 ns apart: equal as double seconds, distinct as nanoseconds.
        assertEquals(PushStatus.ACCEPTED, frame(1).let { t.pushFrame(base, it.first, it.second) })
        assertEquals(PushStatus.ACCEPTED, frame(2).let { t.pushFrame(base + 1, it.first, it.second) })
        val e = assertThrows<IllegalArgumentException>("9000000000000000001 ns") {
            frame(3).let { t.pushFrame(base + 1, it.first, it.second) }
        }
        assertTrue("${e.message}", e.message!!.contains("not after"))
        t.flush()
        assertEquals(2L, t.stats().framesTracked)
        assertTrue(t.getPose(FloatArray(16)) != Tracker.NO_POSE)
    }

    @Test fun useAfterCloseAndDoubleClose() {
        val t = Tracker(config())
        t.close()
        t.close()
        assertTrue(t.isClosed)
        assertThrows<IllegalStateException> { t.pushFrame(1, ShortArray(pixels), ByteArray(pixels)) }
        assertThrows<IllegalStateException> { t.getPose(FloatArray(16)) }
        assertThrows<IllegalStateException> { t.state }
        assertThrows<IllegalStateException> { t.flush() }
        assertThrows<IllegalStateException> { t.stats() }
        assertThrows<IllegalStateException> { t.pointCloud(10) }
    }

    @Test fun staleAndBogusHandles() {
        val h = NativeBridge.nativeInit(320, 180, 250.0, 250.0, 159.5, 89.5, 0, 1000.0, 0, 1, 2, true, 1, false)
        NativeBridge.nativeRelease(h)
        NativeBridge.nativeRelease(h) // unknown handle: nothing
        NativeBridge.nativeRelease(0)
        for (bad in listOf(0L, h, 0x7777_7777_7777L, -1L)) {
            assertThrows<IllegalStateException> { NativeBridge.nativePushArrays(bad, 1, ShortArray(pixels), ByteArray(pixels)) }
            assertThrows<IllegalStateException> { NativeBridge.nativePushBuffers(bad, 1, directDepth(), directGray()) }
            assertThrows<IllegalStateException> { NativeBridge.nativeGetPose(bad, FloatArray(16)) }
            assertThrows<IllegalStateException> { NativeBridge.nativeState(bad) }
            assertThrows<IllegalStateException> { NativeBridge.nativeFlush(bad) }
            assertThrows<IllegalStateException> { NativeBridge.nativeSetIntrinsics(bad, 250.0, 250.0, 159.5, 89.5) }
            assertThrows<IllegalStateException> { NativeBridge.nativeTrajectory(bad) }
            assertThrows<IllegalStateException> { NativeBridge.nativeReferences(bad) }
            assertThrows<IllegalStateException> { NativeBridge.nativeStats(bad) }
            assertThrows<IllegalStateException> { NativeBridge.nativePointCloud(bad, 1) }
        }
    }

    // --- memory known at init, plausible intrinsics, the real minimum size ---------------

    private fun needed(w: Int, h: Int, live: Boolean = true, cloud: Boolean = false, fx: Double = 0.8 * maxOf(w, h)) =
        NativeBridge.nativeMemoryNeeded(w, h, fx, fx, (w - 1) / 2.0, (h - 1) / 2.0, 0, 1000.0, 0, 1, 2, live, 2, cloud)

    private fun initSize(w: Int, h: Int) =
        NativeBridge.nativeInit(w, h, 0.8 * maxOf(w, h), 0.8 * maxOf(w, h), (w - 1) / 2.0, (h - 1) / 2.0, 0, 1000.0, 0, 1, 2, true, 2, false)

    @Test fun memoryIsKnownBeforeInitAndInitRefusesAboveTheBudget() {
        val small = needed(320, 180)
        val vga = needed(640, 480)
        assertTrue("320x180 needs $small", small in (8L shl 20)..(64L shl 20))
        // 5.3 times the pixels, not 5.3 times the bytes: 640x480's finest level is not
        // tracked, so it keeps its planes but no samples.
        assertTrue("640x480 needs $vga, more than twice 320x180's $small", vga > 2 * small)
        val big2 = needed(1280, 960)
        assertTrue("1280x960 needs $big2, more than twice 640x480's $vga", big2 > 2 * vga)
        assertTrue(needed(320, 180, cloud = true) > small)
        // The default budget (512 MiB) refuses 4096x4096 at init, naming need and budget.
        val big = needed(4096, 4096)
        assertTrue(big > (512L shl 20))
        val e = assertThrows<IllegalArgumentException>("512.0 MB") { initSize(4096, 4096) }
        assertTrue("${e.message}", e.message!!.contains("%.1f MB".format(big / 1048576.0)))
        // The budget is settable; it applies to trackers created afterwards.
        val old = NativeBridge.nativeSetMemoryBudget(small - 1)
        try {
            assertEquals(512L shl 20, old)
            assertThrows<IllegalArgumentException>("budget") { initSize(320, 180) }
            NativeBridge.nativeSetMemoryBudget(small)
            NativeBridge.nativeRelease(initSize(320, 180))
            assertThrows<IllegalArgumentException>("memoryBudget") { NativeBridge.nativeSetMemoryBudget(0) }
            assertThrows<IllegalArgumentException>("memoryBudget") { NativeBridge.nativeSetMemoryBudget(-5) }
        } finally {
            NativeBridge.nativeSetMemoryBudget(old)
        }
        // Bad settings are refused by the cost query as by init.
        assertThrows<IllegalArgumentException>("fx") { needed(320, 180, fx = -250.0) }
        assertThrows<IllegalArgumentException>("width") { needed(0, 180) }
    }

    @Test fun implausibleIntrinsicsAreRefusedAtInitAndInSetIntrinsics() {
        assertThrows<IllegalArgumentException>("fx") { Tracker(config().copy(fx = -250.0)) }
        assertThrows<IllegalArgumentException>("fx") { Tracker(config().copy(fx = 1e-5)) }
        assertThrows<IllegalArgumentException>("fy") { Tracker(config().copy(fy = 1e300)) }
        assertThrows<IllegalArgumentException>("cx") { Tracker(config().copy(cx = 1e9)) }
        assertThrows<IllegalArgumentException>("cy") { Tracker(config().copy(cy = -1e9)) }
        assertThrows<IllegalArgumentException>("depthScale") {
            Tracker(config().copy(depthFormat = DepthFormat.CUSTOM_SCALE, depthScale = 4.9e-324))
        }
        // An ICL-NUIM-like flipped y axis stays accepted.
        Tracker(config().copy(fy = -250.0)).close()
        Tracker(config()).use { t ->
            assertThrows<IllegalArgumentException>("cx") { t.setIntrinsics(250.0, 250.0, 900.0, 89.5) }
            assertThrows<IllegalArgumentException>("fx") { t.setIntrinsics(-250.0, 250.0, 159.5, 89.5) }
            assertThrows<IllegalArgumentException>("fx") { t.setIntrinsics(1e-5, 250.0, 159.5, 89.5) }
            t.setIntrinsics(260.0, 260.0, 159.5, 89.5)
        }
    }

    @Test fun everySizeFromTheDocumentedMinimumInitialises() {
        for ((w, h) in listOf(8 to 8, 64 to 48, 96 to 72, 8192 to 8, 8 to 8192)) {
            val handle = initSize(w, h)
            try {
                val n = w * h
                assertEquals(0, NativeBridge.nativePushArrays(handle, 1_000_000L, ShortArray(n) { 1000 }, ByteArray(n) { (it % 251).toByte() }))
                NativeBridge.nativeFlush(handle)
            } finally {
                NativeBridge.nativeRelease(handle)
            }
        }
        assertThrows<IllegalArgumentException>("8x8") { initSize(7, 8) }
    }

    @Test fun intrinsicsChangeOrAreRefusedWithIllegalArgument(): Unit = Tracker(config()).use { t ->
        t.setIntrinsics(325.0, 325.0, 159.5, 89.5) // a 1.3x zoom
        t.setIntrinsics(250.0, 250.0, 160.0, 90.0)
        assertThrows<IllegalArgumentException> { t.setIntrinsics(0.0, 250.0, 159.5, 89.5) }
        assertThrows<IllegalArgumentException> { t.setIntrinsics(250.0, Double.NaN, 159.5, 89.5) }
        assertThrows<IllegalArgumentException> { t.setIntrinsics(250.0, 250.0, Double.POSITIVE_INFINITY, 89.5) }
        // Tracking goes on: frames pushed after the calls are accepted and tracked.
        for (i in 1..3) t.pushFrame(i * 33_000_000L, ShortArray(pixels) { 1000 }, ByteArray(pixels) { ((it + i) % 251).toByte() })
        t.flush()
        assertEquals(3L, t.stats().framesTracked)
    }

    @Test fun freshTrackerReportsZeros(): Unit = Tracker(config()).use { t ->
        assertEquals(TrackerStats.EMPTY, t.stats())
        assertEquals(0, t.trajectory().size)
        assertEquals(0, t.references().size)
        assertEquals(TrackingState.INITIALISING, t.state)
        assertEquals(TrackerStats.SIZE, NativeBridge.nativeStats(handleOf(t)).size)
    }

    @Test fun pushAndGetFromFourThreads() {
        val s = dataDir()?.let { stream() }
        val t = Tracker(config(s, Admission.LIVE))
        val errors = AtomicReference<Throwable?>(null)
        val start = CountDownLatch(1)
        val pushes = AtomicInteger()
        val others = AtomicInteger()
        val threads = (0 until 4).map { k ->
            Thread {
                try {
                    start.await()
                    val m = FloatArray(16)
                    val d = directDepth(); val g = directGray()
                    for (i in 0 until 40) {
                        if (k < 2) {
                            val f = if (s != null) i % s.stamps.size else 0
                            // Two threads pushing to one tracker race: a push whose timestamp
                            // is not after the one that got in first is refused, and the same
                            // buffers twice in a row are REPEATED; both are documented.
                            try {
                                val status = if (s != null && k == 0) t.pushFrame(1000L * i + k, s.depth[f], s.intensity[f])
                                else t.pushFrame(1000L * i + k, d, g)
                                if (status == PushStatus.ACCEPTED || status == PushStatus.DROPPED) pushes.incrementAndGet()
                                else { assertEquals(PushStatus.REPEATED, status); others.incrementAndGet() }
                            } catch (e: IllegalArgumentException) {
                                assertTrue(e.message, e.message!!.contains("is not after the previous frame"))
                                others.incrementAndGet()
                            }
                        } else {
                            t.getPose(m); t.state; t.stats()
                            if (i % 10 == 0) { t.trajectory(); t.pointCloud(100) }
                        }
                    }
                } catch (e: Throwable) {
                    errors.compareAndSet(null, e)
                }
            }
        }
        threads.forEach { it.start() }
        start.countDown()
        threads.forEach { it.join(60_000) }
        errors.get()?.let { throw AssertionError("a thread failed", it) }
        t.flush()
        assertEquals(80, pushes.get() + others.get())
        assertTrue("pushes accepted: ${pushes.get()}", pushes.get() >= 1)
        assertEquals(pushes.get().toLong(), t.stats().framesPushed)
        t.close()
    }

    @Test fun releaseRacingWithCallsOnOtherThreads() {
        // Bypasses Tracker's lock on purpose: the native side must cope on its own.
        repeat(5) {
            val h = NativeBridge.nativeInit(320, 180, 250.0, 250.0, 159.5, 89.5, 0, 1000.0, 0, 1, 2, true, 2, false)
            val start = CountDownLatch(1)
            val unexpected = AtomicReference<Throwable?>(null)
            val callers = (0 until 3).map { k ->
                Thread {
                    start.await()
                    val m = FloatArray(16)
                    try {
                        for (i in 0 until 200) {
                            if (k == 0) NativeBridge.nativePushArrays(h, i.toLong(), ShortArray(pixels), ByteArray(pixels))
                            else { NativeBridge.nativeGetPose(h, m); NativeBridge.nativeStats(h) }
                        }
                    } catch (e: IllegalStateException) {
                        // released meanwhile: the documented result
                    } catch (e: Throwable) {
                        unexpected.compareAndSet(null, e)
                    }
                }
            }
            callers.forEach { it.start() }
            start.countDown()
            Thread.sleep(5)
            NativeBridge.nativeRelease(h)
            callers.forEach { it.join(60_000) }
            unexpected.get()?.let { throw AssertionError("unexpected failure", it) }
            assertThrows<IllegalStateException> { NativeBridge.nativeState(h) }
        }
    }

    @Test fun injectedPanicBecomesRuntimeException() {
        assumeTrue("library built without test-hooks", System.getenv("ECVO_JNI_TEST_HOOKS") == "1")
        Tracker(config(admission = Admission.LIVE)).use { t ->
            val e = assertThrows<RuntimeException> { t.pushFrame(PANIC_TIMESTAMP_NS, ShortArray(pixels), ByteArray(pixels)) }
            assertTrue("a RuntimeException proper, not IAE/ISE: $e", e.javaClass == RuntimeException::class.java)
            assertTrue(e.message.orEmpty(), e.message.orEmpty().contains("panic"))
            // Still usable.
            assertEquals(PushStatus.ACCEPTED, t.pushFrame(5, ShortArray(pixels), ByteArray(pixels)))
            t.flush()
            assertEquals(5L, t.getPose(FloatArray(16)))
            assertThrows<RuntimeException> { t.pushFrame(PANIC_TIMESTAMP_NS, directDepth(), directGray()) }
            assertEquals(1L, t.stats().framesPushed)
        }
    }

    private fun handleOf(t: Tracker): Long = NativeBridgeAccess.handle(t)

    private companion object {
        /** `ecvo_jni::TEST_PANIC_TIMESTAMP_NS` (feature `test-hooks`). */
        const val PANIC_TIMESTAMP_NS: Long = -0x0EC0_DEADL
    }
}
