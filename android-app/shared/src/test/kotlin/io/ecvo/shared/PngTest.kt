package io.ecvo.shared

import io.ecvo.shared.TestSupport.assertThrows
import java.awt.image.DataBufferByte
import java.awt.image.DataBufferUShort
import java.io.ByteArrayInputStream
import java.io.File
import javax.imageio.ImageIO
import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Assume.assumeTrue
import org.junit.Test

/**
 * The PNG codec: round trips through every filter, and files written by other tools.
 * javax.imageio (desktop JVM only, never in the app) serves as an independent decoder.
 */
class PngTest {
    private fun gray8(w: Int, h: Int) = ByteArray(w * h) { i -> ((i * 37 + (i / w) * 11) xor (i shr 3)).toByte() }
    private fun gray16(w: Int, h: Int) = ShortArray(w * h) { i ->
        when (i % 7) {
            0 -> 0; 1 -> 65535; else -> (i * 977 + (i / w) * 3001)
        }.toShort()
    }

    @Test
    fun gray8RoundTripsThroughEveryFilter() {
        for ((w, h) in listOf(1 to 1, 7 to 3, 320 to 180)) {
            val px = gray8(w, h)
            for (f in PngFilter.entries) {
                val png = Png.encodeGray8(px, w, h, f)
                val img = Png.decode(png)
                assertEquals(w, img.width); assertEquals(h, img.height)
                assertEquals(8, img.bitDepth); assertEquals(0, img.colorType)
                assertArrayEquals("$f ${w}x$h", px, img.toGray8())
                assertEquals(w to h, Png.size(png))
            }
        }
    }

    @Test
    fun gray16RoundTripsThroughEveryFilter() {
        for ((w, h) in listOf(1 to 1, 5 to 4, 320 to 180)) {
            val px = gray16(w, h)
            for (f in PngFilter.entries) {
                val img = Png.decode(Png.encodeGray16(px, w, h, f, level = 6))
                assertEquals(16, img.bitDepth)
                assertArrayEquals("$f ${w}x$h", px, img.toGray16())
            }
        }
    }

    @Test
    fun ourPngsDecodeWithAnIndependentDecoder() {
        val (w, h) = 33 to 17
        val px8 = gray8(w, h)
        val px16 = gray16(w, h)
        for (f in PngFilter.entries) {
            val a = ImageIO.read(ByteArrayInputStream(Png.encodeGray8(px8, w, h, f)))
            assertArrayEquals(px8, (a.raster.dataBuffer as DataBufferByte).data)
            val b = ImageIO.read(ByteArrayInputStream(Png.encodeGray16(px16, w, h, f)))
            assertArrayEquals(px16, (b.raster.dataBuffer as DataBufferUShort).data)
        }
    }

    @Test
    fun colourAndAlphaBecomeGrayLikeTheHostTools() {
        // One RGB row and one RGBA row written with the raw encoder (Paeth, to exercise bpp 3 and 4).
        val rgb = byteArrayOf(0, 0, 0, -1, -1, -1, -1, 0, 0, 0, -1, 0, 0, 0, -1, 10, 20, 30)
        val img = Png.decode(Png.encode(rgb, 6, 1, 8, 2, PngFilter.PAETH, 6))
        assertEquals(3, img.channels)
        assertArrayEquals(byteArrayOf(0, -1, 76, -106, 29, 18), img.toGray8()) // 150 = -106 as a byte
        val rgba = byteArrayOf(255.toByte(), 0, 0, 7, 10, 20, 30, 9)
        assertArrayEquals(byteArrayOf(76, 18), Png.decode(Png.encode(rgba, 2, 1, 8, 6, PngFilter.AVERAGE, 6)).toGray8())
        val ga = byteArrayOf(42, 0, 43, 1)
        assertArrayEquals(byteArrayOf(42, 43), Png.decode(Png.encode(ga, 2, 1, 8, 4, PngFilter.SUB, 6)).toGray8())
        // Depth must be 16-bit gray, intensity 8-bit.
        assertThrows<PngException> { img.toGray16() }
        assertThrows<PngException> { Png.decode(Png.encodeGray16(ShortArray(4), 2, 2)).toGray8() }
    }

    @Test
    fun corruptFilesAreRejected() {
        val png = Png.encodeGray8(gray8(16, 16), 16, 16)
        val badCrc = png.copyOf().also { it[20] = (it[20] + 1).toByte() } // inside IHDR
        assertTrue(assertThrows<PngException> { Png.decode(badCrc) }.message!!.contains("CRC"))
        assertThrows<PngException> { Png.decode(png.copyOf(png.size - 20)) }
        assertThrows<PngException> { Png.decode(byteArrayOf(1, 2, 3)) }
        // Interlaced: flip the interlace byte and fix the CRC by re-encoding the header chunk.
        val interlaced = png.copyOf()
        interlaced[28] = 1
        val crc = java.util.zip.CRC32().apply { update(interlaced, 12, 17) }.value.toInt()
        for (k in 0..3) interlaced[29 + k] = (crc ushr (24 - 8 * k)).toByte()
        assertTrue(assertThrows<PngException> { Png.decode(interlaced) }.message!!.contains("interlaced"))
    }

    private fun tumFile(kind: String): File {
        val dir = File(TestSupport.datasets, "tum_fr1_xyz_half/$kind")
        assumeTrue("no TUM dataset at $dir", dir.isDirectory)
        return dir.listFiles()!!.filter { it.name.endsWith(".png") }.minByOrNull { it.name }!!
    }

    @Test
    fun decodesTumDepthWrittenByOtherTools() {
        val f = tumFile("depth")
        val img = Png.decode(f)
        assertEquals(320, img.width); assertEquals(240, img.height); assertEquals(16, img.bitDepth)
        val d = img.toGray16()
        val valid = d.map { it.toInt() and 0xFFFF }.filter { it > 0 }
        // fr1/xyz looks at a desk from about 0.5-2.5 m: 5000 units per metre.
        assertTrue("valid fraction ${valid.size}", valid.size > d.size / 2)
        val meanM = valid.average() / 5000.0
        assertTrue("mean depth $meanM m", meanM in 0.5..2.5)
        assertTrue(valid.max() / 5000.0 < 6.0)
        // Identical to an independent decoder, pixel for pixel.
        val ref = (ImageIO.read(f).raster.dataBuffer as DataBufferUShort).data
        assertArrayEquals(ref, d)
    }

    @Test
    fun decodesTumIntensityWrittenByOtherTools() {
        val f = tumFile("rgb")
        val img = Png.decode(f)
        assertEquals(320, img.width); assertEquals(240, img.height); assertEquals(8, img.bitDepth)
        val g = img.toGray8()
        val mean = g.map { it.toInt() and 0xFF }.average()
        assertTrue("mean gray $mean", mean in 30.0..220.0)
        assertTrue("some contrast", g.map { it.toInt() and 0xFF }.toSet().size > 100)
        assertArrayEquals((ImageIO.read(f).raster.dataBuffer as DataBufferByte).data, g)
    }

    @Test
    fun decodesTumColourPngs() {
        val dir = File(TestSupport.datasets, "tum_fr1_desk_clip9/rgb")
        assumeTrue("no fr1/desk clip at $dir", dir.isDirectory)
        val f = dir.listFiles()!!.filter { it.name.endsWith(".png") }.minByOrNull { it.name }!!
        val img = Png.decode(f)
        assertEquals(640, img.width); assertEquals(480, img.height); assertEquals(3, img.channels)
        val gray = img.toGray8()
        val ref = ImageIO.read(f)
        for (i in intArrayOf(0, 12345, 640 * 240 + 320, 640 * 480 - 1)) {
            val p = ref.getRGB(i % 640, i / 640)
            val expect = (299 * ((p shr 16) and 0xFF) + 587 * ((p shr 8) and 0xFF) + 114 * (p and 0xFF) + 500) / 1000
            assertEquals(expect, gray[i].toInt() and 0xFF)
        }
    }
}
