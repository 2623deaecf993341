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
 * app's own path: plane reading, the confidence policy and the 16:9 remap to 320x180.
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

    private fun decodeAndRemap(name: String, decoder: DepthDecoder): ShortArray {
        val p = plane(name)!!
        val mm = decoder.decodePlane(p, 480, 240, 180, order = ByteOrder.LITTLE_ENDIAN)
        return DepthRemap.create(depthCam, 320, 180).apply(mm)
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
            println("$name: kept ${d.lastKept} of ${d.lastRanged} ranged (codes ignored: ${d.codesIgnored}); ${"%.1f".format(100 * validFraction(out))} % of 320x180 valid")
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
