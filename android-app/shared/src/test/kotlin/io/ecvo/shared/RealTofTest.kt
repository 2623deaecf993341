package io.ecvo.shared

import java.io.File
import java.nio.ByteBuffer
import java.nio.ByteOrder
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertTrue
import org.junit.Assume.assumeTrue
import org.junit.Test

/**
 * The two real DEPTH16 frames of `phone_tof_samples` (240x180, little-endian) through the
 * app's own path: plane reading, the confidence policy and the native-size remap (240x180
 * stays 240x180).
 * Skipped without the datasets, a failure with ECVO_REQUIRE_DATASETS=1.
 */
class RealTofTest {
    private fun plane(name: String): ByteBuffer? {
        val f = File(TestSupport.datasets, "phone_tof_samples/$name")
        if (!f.isFile) {
            if (System.getenv("ECVO_REQUIRE_DATASETS") == "1") throw AssertionError("$f is missing and ECVO_REQUIRE_DATASETS=1")
            assumeTrue("$f is missing", false)
        }
        val b = f.readBytes()
        assertEquals(2 * 240 * 180, b.size)
        return ByteBuffer.allocateDirect(b.size).order(ByteOrder.LITTLE_ENDIAN).put(b).also { it.clear() }
    }

    /** A phone-like depth camera for the 240x180 stream. */
    private val depthCam = CameraIntrinsics(240, 180, 192.0, 192.0, 119.5, 89.5)

    /** The DEPTH16 sizes such a phone lists; the app picks the native one. */
    private val listed = listOf(StreamSize(240, 180), StreamSize(160, 120))

    /** The app's path: the stream at its native size, remapped only to undo distortion (none here). */
    private fun nativeRemap(): DepthRemap {
        val size = StreamSizes.nativeDepth(listed)!!
        return DepthRemap.create(depthCam.forOutput(size.width, size.height), size.width, size.height)
    }

    private fun decodeAndRemap(name: String, decoder: DepthDecoder): ShortArray {
        val p = plane(name)!!
        val mm = decoder.decodePlane(p, 480, 240, 180, order = ByteOrder.LITTLE_ENDIAN)
        return nativeRemap().apply(mm)
    }

    @Test
    fun a240x180FrameIsTrackedAt240x180WithItsOwnIntrinsics() {
        assertEquals(StreamSize(240, 180), StreamSizes.nativeDepth(listed))
        val remap = nativeRemap()
        assertEquals(depthCam, remap.camera) // no crop, no scale: the stream's own intrinsics
        for (name in listOf("00000012_depth16.bin", "00003795_depth16.bin")) {
            val p = plane(name)!!
            val mm = DepthDecoder().decodePlane(p, 480, 240, 180, order = ByteOrder.LITTLE_ENDIAN)
            val out = remap.apply(mm)
            assertEquals(240 * 180, out.size)
            assertArrayEquals(name, mm, out) // every measured pixel reaches the tracker
        }
        // What the 16:9 path did: 240x135 of the 180 rows reached the tracker (a quarter lost).
        val old = DepthRemap.create(depthCam, 320, 180)
        val used = HashSet<Int>()
        for (i in 0 until 320 * 180) old.sourceIndex(i).let { if (it >= 0) used += it }
        assertTrue("${used.size}", used.size <= 240 * 136)
    }

    private fun validFraction(d: ShortArray) = d.count { it.toInt() != 0 }.toDouble() / d.size

    @Test
    fun theDocumentedRuleThrowsAwayMostOfOneRealFrame() {
        val strict = DepthDecoder(ConfidencePolicy.DOCUMENTED, 1)
        decodeAndRemap("00003795_depth16.bin", strict)
        assertTrue("kept ${strict.lastKept} of ${strict.lastRanged}", strict.lastKept < strict.lastRanged / 4)
        val strictA = DepthDecoder(ConfidencePolicy.DOCUMENTED, 1)
        decodeAndRemap("00000012_depth16.bin", strictA)
        assertTrue(strictA.lastKept > strictA.lastRanged * 95 / 100)
    }

    @Test
    fun theDefaultPolicyKeepsEnoughDepthOnBothRealFramesToTrack() {
        for (name in listOf("00000012_depth16.bin", "00003795_depth16.bin")) {
            val d = DepthDecoder() // the app's default: AUTO, level 1
            val out = decodeAndRemap(name, d)
            println("$name: kept ${d.lastKept} of ${d.lastRanged} ranged (codes ignored: ${d.codesIgnored}); ${"%.1f".format(100 * validFraction(out))} % of 240x180 valid")
            assertTrue(name, d.lastKept >= d.lastRanged * 8 / 10)
            assertTrue(name, validFraction(out) > 0.75)
            // Ranges a phone sees indoors: a median between 0.3 m and 4 m.
            val sorted = out.filter { it.toInt() != 0 }.map { it.toInt() }.sorted()
            assertTrue(name, sorted[sorted.size / 2] in 300..4000)
        }
    }

    @Test
    fun autoSticksToItsVerdictForTheSession() {
        val d = DepthDecoder()
        decodeAndRemap("00003795_depth16.bin", d)
        assertTrue(d.codesIgnored)
        decodeAndRemap("00000012_depth16.bin", d)
        assertTrue(d.codesIgnored)
        assertEquals(d.lastRanged, d.lastKept)
        val fresh = DepthDecoder()
        decodeAndRemap("00000012_depth16.bin", fresh)
        assertFalse(fresh.codesIgnored)
    }

    @Test
    fun paddedPlanesDecodeLikePackedOnes() {
        val p = plane("00000012_depth16.bin")!!
        val packed = DepthDecoder(ConfidencePolicy.IGNORE).decodePlane(p, 480, 240, 180, order = ByteOrder.LITTLE_ENDIAN)
        val stride = 512
        val padded = ByteBuffer.allocateDirect(stride * 179 + 480).order(ByteOrder.LITTLE_ENDIAN)
        for (y in 0 until 180) for (x in 0 until 240) padded.putShort(y * stride + 2 * x, p.getShort(y * 480 + 2 * x))
        val out = DepthDecoder(ConfidencePolicy.IGNORE).decodePlane(padded, stride, 240, 180, order = ByteOrder.LITTLE_ENDIAN)
        assertArrayEquals(packed, out)
    }
}
