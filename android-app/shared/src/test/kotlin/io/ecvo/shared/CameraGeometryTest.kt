package io.ecvo.shared

import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNotNull
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test
import kotlin.math.abs

class CameraGeometryTest {
    private fun cal(pre: SensorRect?, active: SensorRect? = pre, k: FloatArray? = floatArrayOf(200f, 201f, 121f, 88f, 0f), corrected: Boolean = false, dist: FloatArray? = null) =
        CameraCalibration(pre, active, k, dist, 2.0f, 4.0f, 3.0f, corrected)

    @Test
    fun calibrationIsRelativeToThePreCorrectionArrayAndNotShiftedAgain() {
        // The pre-correction array starts 8 px into the pixel array: its own coordinates already.
        val c = cal(SensorRect(8, 4, 240, 180), SensorRect(10, 6, 236, 176)).sensorIntrinsics()
        assertEquals(240, c.width); assertEquals(180, c.height)
        assertEquals(121.0, c.cx, 1e-9); assertEquals(88.0, c.cy, 1e-9)
        assertEquals(200.0, c.fx, 1e-6); assertEquals(201.0, c.fy, 1e-6)
        // A corrected output is cut from the active array, 2 px further in.
        val k = cal(SensorRect(8, 4, 240, 180), SensorRect(10, 6, 236, 176), corrected = true).sensorIntrinsics()
        assertEquals(236, k.width)
        assertEquals(119.0, k.cx, 1e-9); assertEquals(86.0, k.cy, 1e-9)
    }

    @Test
    fun withoutCalibrationTheLensAndSensorSizeGiveTheFocalLength() {
        val c = cal(SensorRect(0, 0, 240, 180), k = null)
        assertFalse(c.calibrated)
        val k = c.sensorIntrinsics()
        assertEquals(2.0 / 4.0 * 240, k.fx, 1e-9)
        assertEquals(2.0 / 3.0 * 180, k.fy, 1e-9)
        assertEquals(119.5, k.cx, 1e-9)
    }

    @Test
    fun fourThreeDepthIsCentreCroppedTo16by9NotStretched() {
        val src = CameraIntrinsics(240, 180, 200.0, 200.0, 121.0, 88.0)
        val remap = DepthRemap.create(src, 320, 180)
        val out = remap.camera
        // Uniform scale 4/3 (no stretch): fx and fy scale alike, 22.5 rows cropped off the top.
        assertEquals(200.0 * 4 / 3, out.fx, 1e-9)
        assertEquals(out.fx, out.fy, 1e-9)
        assertEquals((121.0 + 0.5) * 4 / 3 - 0.5, out.cx, 1e-9)
        assertEquals((88.0 - 22.5 + 0.5) * 4 / 3 - 0.5, out.cy, 1e-9)
        // Every output pixel reads the source pixel its ray hits (nearest), so geometry is kept.
        for (v in 0 until 180 step 7) for (u in 0 until 320 step 11) {
            val x = (u - out.cx) / out.fx; val y = (v - out.cy) / out.fy
            val sx = src.fx * x + src.cx; val sy = src.fy * y + src.cy
            val j = remap.sourceIndex(v * 320 + u)
            assertTrue("($u,$v)", j >= 0)
            assertTrue("($u,$v) -> ${j % 240},${j / 240} vs $sx,$sy", abs(j % 240 - sx) <= 0.5 + 1e-9 && abs(j / 240 - sy) <= 0.5 + 1e-9)
        }
        // Rows 0..21 and 158.. of the source are never read.
        val rows = (0 until 320 * 180).map { remap.sourceIndex(it) / 240 }.toSet()
        assertEquals(22, rows.min()); assertEquals(157, rows.max())
        val d = ShortArray(240 * 180) { (it / 240).toShort() }
        assertEquals(22.toShort(), remap.apply(d)[0])
    }

    @Test
    fun lensDistortionIsUndoneBySamplingTheDistortedPosition() {
        val src = CameraIntrinsics(320, 180, 250.0, 250.0, 159.5, 89.5)
        val k = floatArrayOf(-0.2f, 0.05f, 0f, 0.001f, -0.002f)
        val calib = CameraCalibration(SensorRect(0, 0, 320, 180), null, floatArrayOf(250f, 250f, 159.5f, 89.5f, 0f), k, null, null, null)
        val dist = assertNotNullAnd(calib.effectiveDistortion)
        val remap = DepthRemap.create(src, 320, 180, dist)
        assertTrue(remap.undistorts)
        // The corner's ideal ray is sampled where the documented model puts it, inside the image.
        val x = (0 - 159.5) / 250.0; val y = (0 - 89.5) / 250.0
        val r2 = x * x + y * y
        val radial = 1 + k[0] * r2 + k[1] * r2 * r2
        val xc = x * radial + 2 * k[3] * x * y + k[4] * (r2 + 2 * x * x)
        val yc = y * radial + k[3] * (r2 + 2 * y * y) + 2 * k[4] * x * y
        val j = remap.sourceIndex(0)
        assertEquals(Math.floor(250.0 * xc + 159.5 + 0.5).toInt(), j % 320)
        assertEquals(Math.floor(250.0 * yc + 89.5 + 0.5).toInt(), j / 320)
        assertTrue("barrel distortion pulls the corner inwards", j % 320 > 0 && j / 320 > 0)
        // The centre is not moved.
        assertEquals(90 * 320 + 160, remap.sourceIndex(90 * 320 + 160))
        // All-zero coefficients, or corrected outputs, mean nothing to undo.
        assertNull(CameraCalibration(null, null, null, FloatArray(5), null, null, null).effectiveDistortion)
        assertNull(CameraCalibration(null, null, null, k, null, null, null, outputsCorrected = true).effectiveDistortion)
    }

    private fun <T> assertNotNullAnd(v: T?): T { assertNotNull(v); return v!! }

    @Test
    fun aVgaStreamTrackedHalvedHasHalfTheSizeAndMatchingIntrinsics() {
        val vga = StreamSize(640, 480)
        assertEquals(StreamSize(320, 240), TrackingResolution.HALF.frameSize(vga))
        assertEquals(StreamSize(320, 240), TrackingResolution.AUTO.frameSize(vga))
        assertEquals(vga, TrackingResolution.NATIVE.frameSize(vga))
        // A 240x180 ToF stream stays native in auto.
        assertEquals(StreamSize(240, 180), TrackingResolution.AUTO.frameSize(StreamSize(240, 180)))
        assertEquals(StreamSize(120, 90), TrackingResolution.HALF.frameSize(StreamSize(240, 180)))

        val src = CameraIntrinsics(640, 480, 500.0, 505.0, 319.2, 241.7)
        val half = TrackingResolution.HALF.frameSize(vga)
        val remap = DepthRemap.create(src, half.width, half.height)
        val cam = remap.camera
        assertEquals(320, cam.width); assertEquals(240, cam.height)
        assertEquals(250.0, cam.fx, 1e-12); assertEquals(252.5, cam.fy, 1e-12)
        assertEquals((319.2 + 0.5) / 2 - 0.5, cam.cx, 1e-12); assertEquals((241.7 + 0.5) / 2 - 0.5, cam.cy, 1e-12)
        // A 3D point lands where the full-size pixel's centre lands, scaled: (u + 0.5) / 2 - 0.5.
        val (x, y, z) = Triple(0.3, -0.2, 1.5)
        val uFull = src.fx * x / z + src.cx
        val vFull = src.fy * y / z + src.cy
        assertEquals((uFull + 0.5) / 2 - 0.5, cam.fx * x / z + cam.cx, 1e-9)
        assertEquals((vFull + 0.5) / 2 - 0.5, cam.fy * y / z + cam.cy, 1e-9)
        // Each tracker pixel reads one of the 2x2 stream pixels it covers (nearest depth, no mixing across edges).
        val seen = HashSet<Int>()
        for (v in 0 until 240) for (u in 0 until 320) {
            val j = remap.sourceIndex(v * 320 + u)
            assertTrue("($u, $v) reads $j", j % 640 in 2 * u..2 * u + 1 && j / 640 in 2 * v..2 * v + 1)
            assertTrue(seen.add(j))
        }
        val depth = ShortArray(640 * 480) { (it % 640 + 1).toShort() }
        val out = remap.apply(depth)
        assertEquals(320 * 240, out.size)
        assertTrue(out[5].toInt() in 11..12)
    }

    @Test
    fun streamSizesAvoidUpsamplingAndPreferTheAspect() {
        val sizes = listOf(StreamSize(240, 180), StreamSize(640, 480), StreamSize(320, 240), StreamSize(640, 360))
        // 640x360 is 16:9 and large enough; 320x240's 16:9 crop is 320x180 too, and smaller, but needs a crop.
        assertEquals(StreamSize(640, 360), StreamSizes.depth(sizes, 320, 180))
        assertEquals(StreamSize(320, 240), StreamSizes.depth(sizes - StreamSize(640, 360), 320, 180))
        // Only small sizes: the one whose crop is largest.
        assertEquals(StreamSize(240, 180), StreamSizes.depth(listOf(StreamSize(240, 180), StreamSize(160, 120)), 320, 180))
        assertNull(StreamSizes.depth(emptyList(), 320, 180))
        val yuv = listOf(StreamSize(1920, 1080), StreamSize(640, 480), StreamSize(800, 600), StreamSize(320, 240))
        assertEquals(StreamSize(640, 480), StreamSizes.colour(yuv, StreamSize(240, 180), 320))
        assertEquals(StreamSize(1920, 1080), StreamSizes.colour(yuv, StreamSize(640, 360), 320))
        // Native resolution: the largest size up to VGA, never cropped to 16:9.
        assertEquals(StreamSize(640, 480), StreamSizes.nativeDepth(sizes))
        assertEquals(StreamSize(240, 180), StreamSizes.nativeDepth(listOf(StreamSize(240, 180), StreamSize(160, 120))))
        assertEquals(StreamSize(1280, 720), StreamSizes.nativeDepth(listOf(StreamSize(1280, 720), StreamSize(1920, 1080))))
        assertNull(StreamSizes.nativeDepth(emptyList()))
        // A 240x180 stream's intensity: 4:3, at least twice as wide.
        assertEquals(StreamSize(640, 480), StreamSizes.colour(yuv, StreamSize(240, 180), 240))
    }
}
