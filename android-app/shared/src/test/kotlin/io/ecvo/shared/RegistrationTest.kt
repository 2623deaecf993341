package io.ecvo.shared

import org.junit.Assert.assertArrayEquals
import org.junit.Assert.assertEquals
import org.junit.Assert.assertTrue
import org.junit.Test

class RegistrationTest {
    private val depthCam = CameraIntrinsics(320, 180, 250.0, 250.0, 159.5, 89.5, 1000.0)

    /** A plane whose value encodes the column (x % 256) and one that encodes the row. */
    private fun columns(w: Int, h: Int) = GrayPlane(ByteArray(w * h) { (it % w).toByte() }, w, h)
    private fun rows(w: Int, h: Int) = GrayPlane(ByteArray(w * h) { (it / w).toByte() }, w, h)

    @Test
    fun identityRegistrationCopiesThePlane() {
        val src = ByteArray(depthCam.pixels) { (it * 31 + it / 320).toByte() }
        val plane = GrayPlane(src, 320, 180)
        val depth = ShortArray(depthCam.pixels) { if (it % 3 == 0) 0 else 1200 }
        for (s in Sampling.entries) {
            val out = IntensityRegistration(depthCam, depthCam, sampling = s).register(depth, plane)
            assertArrayEquals("$s", src, out)
        }
    }

    @Test
    fun aTwiceLargerPlaneMatchesTheScaledCrop() {
        // A 640x360 Y plane with the same field of view: registration through intrinsics and
        // the simple scale mapping agree.
        val colourCam = depthCam.resized(640, 360)
        assertEquals(500.0, colourCam.fx, 1e-12)
        assertEquals(319.5, colourCam.cx, 1e-12)
        val w = 640
        val plane = GrayPlane(ByteArray(640 * 360) { i -> ((i % w) / 3 + (i / w) / 2).toByte() }, 640, 360)
        val depth = ShortArray(depthCam.pixels) { 900 }
        val viaPose = IntensityRegistration(depthCam, colourCam).register(depth, plane)
        val viaScale = ScaledCrop(320, 180, 2.0, 2.0).resample(plane)
        var maxDiff = 0
        for (i in viaPose.indices) maxDiff = maxOf(maxDiff, kotlin.math.abs((viaPose[i].toInt() and 0xFF) - (viaScale[i].toInt() and 0xFF)))
        assertTrue("max difference $maxDiff", maxDiff <= 1)
        // Centre-aligned: depth pixel u sees plane x = 2u + 0.5, between columns 2u and 2u+1.
        val cols = ScaledCrop(320, 180, 2.0, 2.0, sampling = Sampling.NEAREST).resample(columns(640, 360))
        assertEquals(2 * 10 + 1, cols[10].toInt() and 0xFF) // 20.5 rounds to 21
    }

    @Test
    fun aBaselineShiftsByFocalTimesBaselineOverDepth() {
        // Colour camera 5 cm to the left of the depth camera: points move +5 cm in x.
        val t = RigidTransform(doubleArrayOf(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), doubleArrayOf(0.05, 0.0, 0.0))
        val plane = columns(320, 180)
        for ((mm, shift) in listOf(1000 to 12.5, 2500 to 5.0)) {
            val depth = ShortArray(depthCam.pixels) { mm.toShort() }
            val out = IntensityRegistration(depthCam, depthCam, t).register(depth, plane)
            for (u in intArrayOf(0, 50, 200)) {
                val expect = Math.round(u + shift).toInt() // bilinear between two columns
                assertEquals("u=$u at $mm mm", expect, out[90 * 320 + u].toInt() and 0xFF)
            }
            // Columns whose point falls off the right edge get 0.
            assertEquals(0, out[90 * 320 + 319].toInt())
        }
        // Without depth the fallback distance is used.
        val out = IntensityRegistration(depthCam, depthCam, t, fallbackDepthM = 2.5).register(ShortArray(depthCam.pixels), plane)
        assertEquals(105, out[90 * 320 + 100].toInt() and 0xFF)
    }

    @Test
    fun fitCropsTheLongerSideOfA4by3Plane() {
        val fit = ScaledCrop.fit(640, 480, 320, 180, Sampling.NEAREST)
        assertEquals(2.0, fit.scaleX, 0.0)
        assertEquals(0.0, fit.offsetX, 0.0)
        assertEquals(60.0, fit.offsetY, 0.0)
        val out = fit.resample(rows(640, 480))
        // Row v sees plane row 2v + 0.5 + 60, nearest 2v + 61.
        assertEquals(61, out[0].toInt() and 0xFF)
        assertEquals(2 * 50 + 61, out[50 * 320 + 7].toInt() and 0xFF)
        // Bilinear interpolates exactly on a ramp.
        val bil = ScaledCrop.fit(640, 480, 320, 180).resample(rows(640, 480))
        assertEquals(Math.round(2 * 20 + 60.5).toInt(), bil[20 * 320].toInt() and 0xFF)
    }

    @Test
    fun depthIsResampledByNearestPixel() {
        val src = ShortArray(640 * 360) { i -> ((i % 640) + 1000 * ((i / 640) % 10)).toShort() }
        val out = DepthResample.nearest(src, 640, 360, 320, 180)
        // Output pixel (u, v) takes source (2u + 1, 2v + 1).
        assertEquals(src[(2 * 7 + 1) * 640 + 2 * 5 + 1], out[7 * 320 + 5])
        assertArrayEquals(src, DepthResample.nearest(src, 640, 360, 640, 360))
        // Upsampling repeats pixels.
        val up = DepthResample.nearest(shortArrayOf(1, 2, 3, 4), 2, 2, 4, 4)
        assertArrayEquals(shortArrayOf(1, 1, 2, 2, 1, 1, 2, 2, 3, 3, 4, 4, 3, 3, 4, 4), up)
    }

    @Test
    fun intrinsicsResizeAndCrop() {
        val half = CameraIntrinsics(640, 480, 517.3, 516.5, 318.6, 255.3, 5000.0).resized(320, 240)
        // The TUM half-resolution values of the shared datasets.
        assertEquals(258.65, half.fx, 1e-12)
        assertEquals(159.05, half.cx, 1e-12)
        assertEquals(127.4, half.cy, 1e-12)
        val crop = half.cropped(0, 30, 320, 180)
        assertEquals(97.4, crop.cy, 1e-12)
        assertEquals(180, crop.height)
        // A 16:9 output of a 4:3 sensor: rows cropped equally, then scaled.
        val sensor = CameraIntrinsics(4000, 3000, 3000.0, 3000.0, 1999.5, 1499.5)
        val out = sensor.forOutput(1280, 720)
        assertEquals(960.0, out.fx, 1e-9) // scale 1280 / 4000
        assertEquals(639.5, out.cx, 1e-9)
        assertEquals(359.5, out.cy, 1e-9) // centred stays centred
        // Same aspect: plain resize.
        assertEquals(sensor.resized(640, 480), sensor.forOutput(640, 480))
        // A point 100 px below the sensor centre is 32 px below the output's.
        val p = CameraIntrinsics(4000, 3000, 3000.0, 3000.0, 1999.5, 1599.5).forOutput(1280, 720)
        assertEquals(359.5 + 32.0, p.cy, 1e-9)
    }
}

class LensPoseTest {
    @Test
    fun depthToColourComposesTheTwoPoses() {
        val id = LensPose.depthToColour(null, null, null, null)
        assertArrayEquals(doubleArrayOf(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), id.rotation, 1e-12)
        assertArrayEquals(DoubleArray(3), id.translation, 1e-12)
        // Same orientation, depth camera 2 cm right of the colour camera: p_c = p_d + (0.02, 0, 0).
        val q = floatArrayOf(0f, 0f, 0f, 1f)
        val t = LensPose.depthToColour(q, floatArrayOf(0.03f, 0f, 0f), q, floatArrayOf(0.01f, 0f, 0f))
        assertArrayEquals(doubleArrayOf(0.02, 0.0, 0.0), t.translation, 1e-7)
        // Both cameras rotated the same way: the relative rotation is the identity, and the
        // offset is expressed in the colour camera's axes.
        val h = Math.sqrt(0.5).toFloat()
        val yaw = floatArrayOf(0f, h, 0f, h) // 90 degrees about y
        val r = LensPose.depthToColour(yaw, floatArrayOf(0.02f, 0f, 0f), yaw, FloatArray(3))
        assertArrayEquals(doubleArrayOf(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), r.rotation, 1e-6)
        // R_y(90°) maps x to -z.
        assertArrayEquals(doubleArrayOf(0.0, 0.0, -0.02), r.translation, 1e-7)
        // Check p_c = R_c (R_dᵀ p_d + t_d - t_c) on a point, for different rotations.
        val qd = floatArrayOf(0.1f, 0.2f, 0.3f, 0.9f)
        val qc = floatArrayOf(-0.2f, 0.1f, 0.05f, 0.97f)
        val td = floatArrayOf(0.01f, -0.02f, 0.003f)
        val tc = floatArrayOf(-0.01f, 0.005f, 0.0f)
        val x = LensPose.depthToColour(qd, td, qc, tc)
        val rd = LensPose.rotation(qd)
        val rc = LensPose.rotation(qc)
        val pd = doubleArrayOf(0.3, -0.1, 1.7)
        val pref = DoubleArray(3) { i -> rd[i] * pd[0] + rd[3 + i] * pd[1] + rd[6 + i] * pd[2] + td[i] - tc[i] }
        val expect = DoubleArray(3) { i -> rc[3 * i] * pref[0] + rc[3 * i + 1] * pref[1] + rc[3 * i + 2] * pref[2] }
        val got = DoubleArray(3) { i -> x.rotation[3 * i] * pd[0] + x.rotation[3 * i + 1] * pd[1] + x.rotation[3 * i + 2] * pd[2] + x.translation[i] }
        assertArrayEquals(expect, got, 1e-6)
    }
}
