package io.ecvo.shared

import java.io.ByteArrayOutputStream
import java.io.File
import java.io.IOException
import java.util.zip.CRC32
import java.util.zip.DataFormatException
import java.util.zip.Deflater
import java.util.zip.Inflater

/** A PNG could not be decoded or is of a kind this codec does not read. */
class PngException(message: String) : IOException(message)

/**
 * A decoded, non-interlaced PNG with 8- or 16-bit samples: [data] holds the unfiltered
 * rows (`height * width * channels * bitDepth / 8` bytes, 16-bit samples big-endian as
 * in the file).
 */
class PngImage(
    val width: Int,
    val height: Int,
    /** 8 or 16. */
    val bitDepth: Int,
    /** PNG colour type: 0 gray, 2 RGB, 4 gray + alpha, 6 RGBA. */
    val colorType: Int,
    val data: ByteArray,
) {
    /** Samples per pixel. */
    val channels: Int get() = Png.channels(colorType)

    /** A short description such as "16-bit gray", for error messages. */
    val description: String get() = Png.describe(colorType, bitDepth)

    /**
     * The image as 8-bit gray, as the host tools read intensity: 8-bit gray is copied,
     * gray + alpha keeps the gray, RGB and RGBA become `(299 R + 587 G + 114 B + 500) / 1000`
     * (rounded, as `ecvo-io`'s `rgb_to_gray`). 16-bit images are rejected.
     */
    fun toGray8(): ByteArray {
        if (bitDepth != 8) throw PngException("intensity PNG is $description; expected 8-bit gray, RGB or RGBA")
        val n = width * height
        val ch = channels
        if (ch == 1) return data.copyOf()
        val out = ByteArray(n)
        for (i in 0 until n) {
            val o = i * ch
            out[i] = if (ch == 2) data[o] else {
                val r = data[o].toInt() and 0xFF
                val g = data[o + 1].toInt() and 0xFF
                val b = data[o + 2].toInt() and 0xFF
                ((299 * r + 587 * g + 114 * b + 500) / 1000).toByte()
            }
        }
        return out
    }

    /** The image as 16-bit gray samples (read them with `toInt() and 0xFFFF`); anything else is rejected. */
    fun toGray16(): ShortArray {
        if (bitDepth != 16 || colorType != 0) throw PngException("depth PNG is $description; expected 16-bit gray")
        val out = ShortArray(width * height)
        for (i in out.indices) {
            out[i] = (((data[2 * i].toInt() and 0xFF) shl 8) or (data[2 * i + 1].toInt() and 0xFF)).toShort()
        }
        return out
    }
}

/** Row filters of PNG (filter method 0); [ADAPTIVE] picks one per row. */
enum class PngFilter(val type: Int) {
    NONE(0), SUB(1), UP(2), AVERAGE(3), PAETH(4),

    /** Per row, the filter with the smallest sum of absolute filtered bytes (the usual heuristic). */
    ADAPTIVE(-1),
}

/**
 * A small PNG codec for the images of RGB-D streams (Android has no javax.imageio):
 * writes 8-bit and 16-bit gray; reads non-interlaced 8/16-bit gray, gray + alpha, RGB
 * and RGBA with any of the five row filters, checking every chunk's CRC.
 */
object Png {
    private val SIGNATURE = byteArrayOf(0x89.toByte(), 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A)

    /** Largest width or height accepted when decoding (guards against absurd headers). */
    const val MAX_SIDE: Int = 1 shl 14

    internal fun channels(colorType: Int) = when (colorType) {
        0 -> 1; 2 -> 3; 4 -> 2; 6 -> 4
        else -> throw PngException("unsupported PNG colour type $colorType")
    }

    internal fun describe(colorType: Int, bitDepth: Int): String = "$bitDepth-bit " + when (colorType) {
        0 -> "gray"; 2 -> "RGB"; 3 -> "palette"; 4 -> "gray with alpha"; 6 -> "RGBA"; else -> "colour type $colorType"
    }

    /** Encodes `width * height` 8-bit gray values (row-major) as a PNG. */
    fun encodeGray8(
        pixels: ByteArray, width: Int, height: Int,
        filter: PngFilter = PngFilter.ADAPTIVE, level: Int = Deflater.BEST_SPEED, strategy: Int = Deflater.DEFAULT_STRATEGY,
    ): ByteArray {
        require(pixels.size == width * height) { "gray image has ${pixels.size} values, expected ${width * height} (${width}x$height)" }
        return encode(pixels, width, height, 8, 0, filter, level, strategy)
    }

    /** Encodes `width * height` unsigned 16-bit gray values (row-major) as a PNG with big-endian samples. */
    fun encodeGray16(
        pixels: ShortArray, width: Int, height: Int,
        filter: PngFilter = PngFilter.ADAPTIVE, level: Int = Deflater.BEST_SPEED, strategy: Int = Deflater.DEFAULT_STRATEGY,
    ): ByteArray {
        require(pixels.size == width * height) { "16-bit image has ${pixels.size} values, expected ${width * height} (${width}x$height)" }
        val raw = ByteArray(pixels.size * 2)
        for (i in pixels.indices) {
            val v = pixels[i].toInt()
            raw[2 * i] = (v ushr 8).toByte()
            raw[2 * i + 1] = v.toByte()
        }
        return encode(raw, width, height, 16, 0, filter, level, strategy)
    }

    /**
     * Encodes already laid-out rows ([raw], big-endian samples) of any supported colour
     * type, deflated at [level] with [strategy] (`Deflater.DEFAULT_STRATEGY`,
     * `FILTERED`, `HUFFMAN_ONLY`).
     */
    fun encode(
        raw: ByteArray, width: Int, height: Int, bitDepth: Int, colorType: Int, filter: PngFilter, level: Int,
        strategy: Int = Deflater.DEFAULT_STRATEGY,
    ): ByteArray {
        require(width in 1..Int.MAX_VALUE / 8 && height >= 1) { "${width}x$height is not a valid PNG size" }
        require(bitDepth == 8 || bitDepth == 16) { "bit depth $bitDepth is not 8 or 16" }
        val bpp = channels(colorType) * bitDepth / 8
        val stride = width * bpp
        require(raw.size == stride * height) { "image data has ${raw.size} bytes, expected ${stride * height}" }

        val filtered = ByteArray((stride + 1) * height)
        val candidate = ByteArray(stride)
        val best = ByteArray(stride)
        for (y in 0 until height) {
            val cur = y * stride
            val prev = if (y == 0) -1 else cur - stride
            val o = y * (stride + 1)
            val type = if (filter != PngFilter.ADAPTIVE) {
                filterRow(filter.type, raw, cur, prev, stride, bpp, filtered, o + 1)
                filter.type
            } else {
                var bestType = 0
                var bestCost = Long.MAX_VALUE
                for (t in 0..4) {
                    filterRow(t, raw, cur, prev, stride, bpp, candidate, 0)
                    var cost = 0L
                    for (b in candidate) cost += kotlin.math.abs(b.toInt())
                    if (cost < bestCost) { bestCost = cost; bestType = t; candidate.copyInto(best) }
                }
                best.copyInto(filtered, o + 1)
                bestType
            }
            filtered[o] = type.toByte()
        }

        val out = ByteArrayOutputStream(filtered.size / 2 + 64)
        out.write(SIGNATURE)
        val ihdr = ByteArray(13)
        putInt(ihdr, 0, width); putInt(ihdr, 4, height)
        ihdr[8] = bitDepth.toByte(); ihdr[9] = colorType.toByte() // compression, filter method, interlace: 0
        writeChunk(out, "IHDR", ihdr, ihdr.size)
        val deflater = Deflater(level)
        try {
            deflater.setStrategy(strategy)
            deflater.setInput(filtered)
            deflater.finish()
            val buf = ByteArray(64 * 1024)
            while (!deflater.finished()) {
                val n = deflater.deflate(buf)
                if (n > 0) writeChunk(out, "IDAT", buf, n)
            }
        } finally {
            deflater.end()
        }
        writeChunk(out, "IEND", ByteArray(0), 0)
        return out.toByteArray()
    }

    /** Writes `filter(raw[cur until cur + stride])` of [type] into out[o until o + stride]. */
    private fun filterRow(type: Int, raw: ByteArray, cur: Int, prev: Int, stride: Int, bpp: Int, out: ByteArray, o: Int) {
        for (i in 0 until stride) {
            val x = raw[cur + i].toInt() and 0xFF
            val a = if (i >= bpp) raw[cur + i - bpp].toInt() and 0xFF else 0
            val b = if (prev >= 0) raw[prev + i].toInt() and 0xFF else 0
            val c = if (prev >= 0 && i >= bpp) raw[prev + i - bpp].toInt() and 0xFF else 0
            out[o + i] = when (type) {
                0 -> x
                1 -> x - a
                2 -> x - b
                3 -> x - ((a + b) ushr 1)
                4 -> x - paeth(a, b, c)
                else -> throw IllegalArgumentException("filter type $type")
            }.toByte()
        }
    }

    private fun paeth(a: Int, b: Int, c: Int): Int {
        val p = a + b - c
        val pa = kotlin.math.abs(p - a)
        val pb = kotlin.math.abs(p - b)
        val pc = kotlin.math.abs(p - c)
        return if (pa <= pb && pa <= pc) a else if (pb <= pc) b else c
    }

    private fun putInt(b: ByteArray, o: Int, v: Int) {
        b[o] = (v ushr 24).toByte(); b[o + 1] = (v ushr 16).toByte(); b[o + 2] = (v ushr 8).toByte(); b[o + 3] = v.toByte()
    }

    private fun getInt(b: ByteArray, o: Int): Int =
        ((b[o].toInt() and 0xFF) shl 24) or ((b[o + 1].toInt() and 0xFF) shl 16) or
            ((b[o + 2].toInt() and 0xFF) shl 8) or (b[o + 3].toInt() and 0xFF)

    private fun writeChunk(out: ByteArrayOutputStream, type: String, data: ByteArray, len: Int) {
        val header = ByteArray(8)
        putInt(header, 0, len)
        for (i in 0..3) header[4 + i] = type[i].code.toByte()
        val crc = CRC32()
        crc.update(header, 4, 4)
        crc.update(data, 0, len)
        out.write(header)
        out.write(data, 0, len)
        val c = ByteArray(4)
        putInt(c, 0, crc.value.toInt())
        out.write(c)
    }

    /** Width and height from the header of [bytes], without decoding the image. */
    fun size(bytes: ByteArray): Pair<Int, Int> {
        checkSignature(bytes)
        if (bytes.size < 33 || String(bytes, 12, 4, Charsets.US_ASCII) != "IHDR") throw PngException("PNG does not start with IHDR")
        return getInt(bytes, 16) to getInt(bytes, 20)
    }

    private fun checkSignature(bytes: ByteArray) {
        if (bytes.size < 8 || !bytes.copyOfRange(0, 8).contentEquals(SIGNATURE)) throw PngException("not a PNG file (bad signature)")
    }

    /** Decodes a PNG file; errors name the file. */
    fun decode(file: File): PngImage = try {
        decode(file.readBytes())
    } catch (e: PngException) {
        throw PngException("$file: ${e.message}")
    }

    /** Decodes a PNG held in memory. */
    fun decode(bytes: ByteArray): PngImage {
        checkSignature(bytes)
        var pos = 8
        var width = 0
        var height = 0
        var bitDepth = 0
        var colorType = 0
        var sawHeader = false
        var sawEnd = false
        val idat = ByteArrayOutputStream()
        val crc = CRC32()
        while (pos + 12 <= bytes.size && !sawEnd) {
            val len = getInt(bytes, pos)
            if (len < 0 || len > bytes.size - pos - 12) throw PngException("truncated PNG (chunk of $len bytes at offset $pos)")
            val type = String(bytes, pos + 4, 4, Charsets.US_ASCII)
            crc.reset()
            crc.update(bytes, pos + 4, 4 + len)
            if (crc.value.toInt() != getInt(bytes, pos + 8 + len)) throw PngException("bad CRC in $type chunk")
            val d = pos + 8
            if (!sawHeader && type != "IHDR") throw PngException("PNG does not start with IHDR")
            when (type) {
                "IHDR" -> {
                    if (len != 13) throw PngException("IHDR has $len bytes, expected 13")
                    width = getInt(bytes, d); height = getInt(bytes, d + 4)
                    bitDepth = bytes[d + 8].toInt() and 0xFF
                    colorType = bytes[d + 9].toInt() and 0xFF
                    val compression = bytes[d + 10].toInt()
                    val filterMethod = bytes[d + 11].toInt()
                    val interlace = bytes[d + 12].toInt()
                    if (width !in 1..MAX_SIDE || height !in 1..MAX_SIDE) throw PngException("PNG size ${width}x$height is out of range")
                    if (compression != 0 || filterMethod != 0) throw PngException("unknown PNG compression or filter method")
                    if (interlace != 0) throw PngException("interlaced PNGs are not supported")
                    if (colorType !in intArrayOf(0, 2, 4, 6) || (bitDepth != 8 && bitDepth != 16)) {
                        throw PngException("PNG is ${describe(colorType, bitDepth)}; only 8/16-bit gray, gray+alpha, RGB and RGBA are supported")
                    }
                    sawHeader = true
                }
                "IDAT" -> idat.write(bytes, d, len)
                "IEND" -> sawEnd = true
                else -> if ((bytes[pos + 4].toInt() and 0x20) == 0) throw PngException("unsupported critical chunk $type")
            }
            pos += 12 + len
        }
        if (!sawHeader) throw PngException("PNG has no IHDR")
        if (!sawEnd) throw PngException("truncated PNG (no IEND)")

        val bpp = channels(colorType) * bitDepth / 8
        val stride = width * bpp
        val filtered = ByteArray((stride + 1) * height)
        val inflater = Inflater()
        try {
            inflater.setInput(idat.toByteArray())
            var n = 0
            while (n < filtered.size) {
                val k = inflater.inflate(filtered, n, filtered.size - n)
                if (k == 0 && (inflater.finished() || inflater.needsInput() || inflater.needsDictionary())) break
                n += k
            }
            if (n < filtered.size) throw PngException("image data ends early ($n of ${filtered.size} bytes)")
        } catch (e: DataFormatException) {
            throw PngException("corrupt image data: ${e.message}")
        } finally {
            inflater.end()
        }

        val data = ByteArray(stride * height)
        for (y in 0 until height) {
            val f = y * (stride + 1)
            val type = filtered[f].toInt() and 0xFF
            val cur = y * stride
            val prev = cur - stride
            for (i in 0 until stride) {
                val x = filtered[f + 1 + i].toInt() and 0xFF
                val a = if (i >= bpp) data[cur + i - bpp].toInt() and 0xFF else 0
                val b = if (y > 0) data[prev + i].toInt() and 0xFF else 0
                val v = when (type) {
                    0 -> x
                    1 -> x + a
                    2 -> x + b
                    3 -> x + ((a + b) ushr 1)
                    4 -> x + paeth(a, b, if (y > 0 && i >= bpp) data[prev + i - bpp].toInt() and 0xFF else 0)
                    else -> throw PngException("bad filter type $type in row $y")
                }
                data[cur + i] = v.toByte()
            }
        }
        return PngImage(width, height, bitDepth, colorType, data)
    }
}
