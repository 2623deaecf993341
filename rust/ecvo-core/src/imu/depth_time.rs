//! Depth turned to the intensity image's time. An RGB-D camera whose depth and colour
//! streams are not triggered together stamps the two images of a frame apart: up to
//! 19 ms in the TUM recordings (`docs/imu.md`), 1° of a 57 °/s pan, 9 pixels at
//! 640x480. Each intensity pixel is then paired with the depth of another ray. With
//! a gyroscope the camera's rotation between the two times is known: over such an
//! interval the camera's translation moves the image far less than its rotation, and
//! a pure rotation moves every pixel by the same homography `K R K⁻¹` whatever its
//! depth, so the depth image can be resampled to the intensity's time before it is
//! prepared ([`crate::Preparer::prepare_turned_into`]).
//!
//! The rotation comes from the raw gyro, without the bias estimate (which lives in
//! the tracker, behind the pipeline's filter stage): a turn-on bias of 3 °/s over
//! 20 ms is 0.06°, half a pixel at 640x480. [`DepthClock`] keeps its own ring of the
//! samples pushed, so that the sequential engine and the pipeline compute the same
//! rotation for a frame from the samples pushed before it.

use nalgebra::{UnitQuaternion, Vector3};

use super::{Coverage, GyroRing, GyroSample, ImuCalibration, integrate};
use crate::camera::Camera;
use crate::prepare::simd::multiversion;

/// Samples [`DepthClock`] keeps: 0.64 s at 400 Hz, 8 KiB, allocated at the first
/// push. The interval it integrates is at most [`MAX_DEPTH_TIME_GAP_S`] back from the
/// newest frame.
pub const DEPTH_CLOCK_CAPACITY: usize = 256;

/// The largest gap between a frame's depth and intensity times that is turned,
/// seconds: the frame readers pair images at most 20 ms apart; beyond 50 ms the
/// frame's depth is left as it is and counted.
pub const MAX_DEPTH_TIME_GAP_S: f64 = 0.05;

/// What became of a frame's depth time ([`crate::PreparedFrame::depth_time`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum DepthTime {
    /// Depth and intensity have the same time (or no depth time was given).
    #[default]
    Same,
    /// The depth was turned by the gyro's rotation between the two times.
    Turned(UnitQuaternion<f64>),
    /// The times differ, but no gyro sample was pushed: the depth was left as it is.
    NoGyro,
    /// The times differ and the samples do not cover the interval (or it is longer
    /// than [`MAX_DEPTH_TIME_GAP_S`]): the depth was left as it is.
    Uncovered,
}

/// The raw gyro samples pushed, for the rotation between a frame's depth and
/// intensity times.
#[derive(Clone, Debug)]
pub struct DepthClock {
    calibration: ImuCalibration,
    ring: GyroRing,
}

impl DepthClock {
    /// A clock for an IMU with `calibration`, with no sample yet (nothing allocated).
    pub fn new(calibration: ImuCalibration) -> Self {
        DepthClock {
            calibration,
            ring: GyroRing::new(DEPTH_CLOCK_CAPACITY),
        }
    }

    /// Takes finite `samples` in time order (checked by the caller); one not after
    /// the last one taken is skipped (the tracker counts it).
    pub fn push(&mut self, samples: &[GyroSample]) {
        for s in samples {
            if self.ring.last().is_none_or(|l| s.t > l.t) {
                self.ring.push(*s);
            }
        }
    }

    /// What to do with a frame whose intensity is stamped `intensity_t` and depth
    /// `depth_t` (frames' clock): with a different time, the rotation `R_{d←c}`
    /// taking a ray of the camera at the intensity's time into the camera at the
    /// depth's time, in the camera's frame.
    pub fn depth_time(&self, intensity_t: f64, depth_t: f64) -> DepthTime {
        if depth_t == intensity_t || !depth_t.is_finite() {
            return DepthTime::Same;
        }
        if self.ring.pushed() == 0 {
            return DepthTime::NoGyro;
        }
        if (depth_t - intensity_t).abs() > MAX_DEPTH_TIME_GAP_S {
            return DepthTime::Uncovered;
        }
        let off = self.calibration.time_offset;
        let (a, b) = (depth_t.min(intensity_t) - off, depth_t.max(intensity_t) - off);
        let q = match integrate(&self.ring, a, b, &Vector3::zeros()) {
            Ok(q) => q,
            Err(Coverage::Late | Coverage::Missing | Coverage::Empty) => {
                return DepthTime::Uncovered;
            }
        };
        // `integrate` gives R_{a←b}: the depth's frame at `a` when it came first.
        let q = if depth_t < intensity_t { q } else { q.inverse() };
        let c = self.calibration.camera_from_imu;
        let mut r = c * q * c.inverse();
        r.renormalize();
        DepthTime::Turned(r)
    }
}

/// Resamples raw depth `src` (captured by the camera turned by `r` = `R_{d←c}` from
/// the intensity's pose) into `dst` as the camera at the intensity's time would
/// have seen it: for each pixel, the ray `K⁻¹ u` turned into the depth camera, the
/// nearest depth pixel there, and its depth along the new optical axis. Pixels whose
/// ray leaves the depth image, or lands on no measurement, get 0 (missing). `dst`
/// is resized to the image (no allocation once it has the capacity).
pub fn turn_depth(camera: &Camera, r: &UnitQuaternion<f64>, src: &[u16], dst: &mut Vec<u16>) {
    let (w, h) = (camera.width, camera.height);
    dst.clear();
    dst.resize(w * h, 0);
    let m = *r.to_rotation_matrix().matrix();
    let (fx, fy, cx, cy) = (camera.fx, camera.fy, camera.cx, camera.cy);
    // q(x) = M [(x - cx)/fx, ry, 1] = base + x * step along a row, in f32.
    let step = (m.column(0) / fx).map(|v| v as f32);
    let k = [fx as f32, fy as f32, cx as f32, cy as f32];
    for (y, row) in dst.chunks_exact_mut(w).enumerate() {
        let ry = (y as f64 - cy) / fy;
        let base = (m * Vector3::new(-cx / fx, ry, 1.0)).map(|v| v as f32);
        turn_row(src, w, h, base.into(), step.into(), k, row);
    }
}

/// `x` rounded to the nearest integer (ties to even) for `|x| < 2²²`: the mantissa of
/// `x + 1.5·2²³` (whose unit in the last place is 1), less 2²², which vectorises
/// where `as i32` (saturating, NaN to 0) does not. Garbage outside that range (the
/// callers mask it).
#[inline(always)]
fn nearest(x: f32) -> i32 {
    ((x + 12_582_912.0).to_bits() & 0x7F_FFFF) as i32 - 0x40_0000
}

/// Pixels a pass of [`turn_row_kernel`] projects before it looks them up.
const CHUNK: usize = 64;

multiversion! {
    /// One output row of [`turn_depth`].
    fn turn_row(
        src: &[u16],
        w: usize,
        h: usize,
        base: [f32; 3],
        step: [f32; 3],
        k: [f32; 4],
        row: &mut [u16],
    ) = turn_row_kernel;
}

/// In chunks: a pass that projects (and vectorises, division included), then the
/// lookups, rounding to the nearest pixel ([`nearest`]); a pixel whose ray leaves the
/// image looks up pixel 0 with a scale of 0, which writes 0.
#[inline(always)]
fn turn_row_kernel(
    src: &[u16],
    w: usize,
    h: usize,
    base: [f32; 3],
    step: [f32; 3],
    k: [f32; 4],
    row: &mut [u16],
) {
    let [fx, fy, cx, cy] = k;
    let (wf, hf) = (w as f32 - 0.5, h as f32 - 0.5);
    let mut at = [0i32; CHUNK];
    let mut scale = [0f32; CHUNK];
    for (c, out) in row.chunks_mut(CHUNK).enumerate() {
        let x0 = (c * CHUNK) as f32;
        let n = out.len();
        for (j, (a, s)) in at[..n].iter_mut().zip(&mut scale[..n]).enumerate() {
            let xf = x0 + j as f32;
            let qx = base[0] + step[0] * xf;
            let qy = base[1] + step[1] * xf;
            let qz = base[2] + step[2] * xf;
            let inv = 1.0 / qz;
            let u = fx * qx * inv + cx;
            let v = fy * qy * inv + cy;
            let inside = qz > 0.0 && u >= -0.5 && v >= -0.5 && u < wf && v < hf;
            // Wrapping: garbage outside the image, masked just below.
            let i = nearest(v).wrapping_mul(w as i32).wrapping_add(nearest(u));
            *a = if inside { i } else { 0 };
            *s = if inside { inv } else { 0.0 };
        }
        for ((o, &a), &s) in out.iter_mut().zip(&at[..n]).zip(&scale[..n]) {
            // The point d·q/q_z in the depth camera; along the intensity camera's
            // axis (its ray has z = 1) its depth is d / q_z (saturating at u16::MAX;
            // 0 stays 0).
            *o = nearest(src[a as usize] as f32 * s).min(i32::from(u16::MAX)) as u16;
        }
    }
    debug_assert!(src.len() >= w * h);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        crate::camera::tum_fr1_half()
    }

    /// A plane of depth seen by the camera turned by a small yaw: turning it back
    /// gives the plane as the untuned camera sees it, to the rounding of a pixel.
    #[test]
    fn turning_undoes_a_pure_rotation() {
        let c = cam();
        let (w, h) = (c.width, c.height);
        // A fronto-parallel wall at 2 m, with a textured depth (a ramp in x) so that a
        // shift shows: depth(X) = 2 + 0.1 * X (metres).
        let depth_of = |ray: Vector3<f64>| {
            // Intersect the ray with the plane z = 2 + 0.1 x  →  t (z - 0.1 x) = 2.
            let t = 2.0 / (ray.z - 0.1 * ray.x);
            ray * t
        };
        let r = UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 1.0f64.to_radians(), 0.0));
        // The depth camera is turned by R_{d←c} = r: its ray q sees the world point
        // along R_{c←d} q = r⁻¹ q in the intensity camera's frame.
        let mut src = vec![0u16; w * h];
        for y in 0..h {
            for x in 0..w {
                let q = Vector3::new((x as f64 - c.cx) / c.fx, (y as f64 - c.cy) / c.fy, 1.0);
                let p = depth_of(r.inverse() * q);
                let pd = r * p;
                src[y * w + x] = (pd.z * c.depth_scale).round() as u16;
            }
        }
        let mut dst = Vec::new();
        turn_depth(&c, &r, &src, &mut dst);
        // Every kernel copy (baseline, AVX2, AVX-512) gives the same bits.
        crate::prepare::simd::on_each_path(|path| {
            let mut other = Vec::new();
            turn_depth(&c, &r, &src, &mut other);
            assert!(other == dst, "the {path} copy differs");
        });
        let mut checked = 0;
        for y in 10..h - 10 {
            for x in 20..w - 20 {
                let q = Vector3::new((x as f64 - c.cx) / c.fx, (y as f64 - c.cy) / c.fy, 1.0);
                let want = depth_of(q).z * c.depth_scale;
                let got = dst[y * w + x] as f64;
                // A pixel's rounding: the ramp changes by 0.1 * z / fx per pixel.
                assert!((got - want).abs() < 0.1 * 2.2 / c.fx * c.depth_scale + 2.0, "{x},{y}: {got} vs {want}");
                checked += 1;
            }
        }
        assert!(checked > 50_000);
        // Without the turn the centre pixel sees a point 2 m · 1° = 35 mm aside: 3.5 mm
        // of the ramp, 17.5 raw units, against at most 6.3 turned.
        let (x, y) = (w / 2, h / 2);
        let q = Vector3::new((x as f64 - c.cx) / c.fx, (y as f64 - c.cy) / c.fy, 1.0);
        let want = depth_of(q).z * c.depth_scale;
        assert!((src[y * w + x] as f64 - want).abs() > 12.0);
    }

    /// [`nearest`] rounds as `f32::round_ties_even` over the range it serves.
    #[test]
    fn nearest_rounds_to_the_nearest_integer() {
        for x in [-0.5f32, -0.49, -0.2, 0.0, 0.49, 0.5, 0.51, 1.5, 2.5, 319.4, 319.6, 65535.4, 78000.7] {
            assert_eq!(nearest(x), x.round_ties_even() as i32, "{x}");
        }
    }

    /// Pixels turned out of the depth image, and missing depth, stay missing.
    #[test]
    fn rays_leaving_the_image_are_missing() {
        let c = cam();
        let src = vec![5000u16; c.pixels()];
        let r = UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 5f64.to_radians(), 0.0));
        let mut dst = Vec::new();
        turn_depth(&c, &r, &src, &mut dst);
        let w = c.width;
        // A 5° yaw about y shifts the image by fx tan 5° ≈ 22.6 px: one border's
        // columns are missing, the other's are not.
        let missing_left = (0..c.height).all(|y| dst[y * w] == 0);
        let missing_right = (0..c.height).all(|y| dst[y * w + w - 1] == 0);
        assert!(missing_left != missing_right);
        assert!(dst[(c.height / 2) * w + w / 2] > 0);
        let zeros = vec![0u16; c.pixels()];
        turn_depth(&c, &r, &zeros, &mut dst);
        assert!(dst.iter().all(|&d| d == 0));
    }

    /// The clock: the same time, no gyro, uncovered and turned, with the turn's sense
    /// following which image came first.
    #[test]
    fn the_clock_says_what_it_can() {
        let mut k = DepthClock::new(ImuCalibration::default());
        assert_eq!(k.depth_time(1.0, 1.0), DepthTime::Same);
        assert_eq!(k.depth_time(1.0, 1.01), DepthTime::NoGyro);
        let w = [0.0, 1.0, 0.0];
        let samples: Vec<GyroSample> = (0..100).map(|i| GyroSample { t: 0.5 + i as f64 * 0.005, w }).collect();
        k.push(&samples);
        // Depth 10 ms after the intensity: the camera turned +0.01 rad about y from
        // the one to the other, so a ray of the intensity camera is at -0.01 rad in
        // the depth camera.
        let DepthTime::Turned(r) = k.depth_time(0.7, 0.71) else { panic!("turned") };
        let a = r.scaled_axis();
        assert!((a - Vector3::new(0.0, -0.01, 0.0)).norm() < 1e-9, "{a:?}");
        let DepthTime::Turned(r2) = k.depth_time(0.71, 0.70) else { panic!("turned") };
        assert!((r2.scaled_axis() + a).norm() < 1e-9, "the other order turns the other way");
        assert_eq!(k.depth_time(0.7, 0.8), DepthTime::Uncovered, "beyond the gap");
        assert_eq!(k.depth_time(5.0, 5.01), DepthTime::Uncovered, "no samples then");
    }
}
