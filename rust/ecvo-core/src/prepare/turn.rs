//! A frame's raw depth turned to its intensity's time ([`crate::imu::depth_time`]):
//! the resampling kernel and [`Preparer::prepare_turned_into`].

use nalgebra::{UnitQuaternion, Vector3};

use super::PreparedFrame;
use super::Preparer;
use super::simd::multiversion;
use crate::camera::{Camera, FrameView};
use crate::error::Result;
use crate::imu::depth_time::DepthTime;

impl Preparer {
    /// [`Preparer::prepare_into`] for a frame whose depth was captured at another time
    /// than its intensity ([`crate::imu::depth_time`]): with
    /// [`DepthTime::Turned`], the depth is first resampled to the intensity's time
    /// ([`turn_depth`]); otherwise it is used as it is. `out.depth_time` says which.
    pub fn prepare_turned_into(
        &mut self,
        view: FrameView<'_>,
        depth_time: DepthTime,
        out: &mut PreparedFrame,
    ) -> Result<()> {
        view.validate(&self.camera)?;
        out.depth_time = depth_time;
        if let DepthTime::Turned(r) = depth_time {
            let mut turned = std::mem::take(&mut self.turned);
            turn_depth(&self.camera, &r, view.depth, &mut turned);
            let r = self.prepare_checked(
                FrameView {
                    depth: &turned,
                    ..view
                },
                out,
            );
            self.turned = turned;
            return r;
        }
        self.prepare_checked(view, out)
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
    assert_eq!(src.len(), w * h, "the depth image is the camera's size");
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
                assert!(
                    (got - want).abs() < 0.1 * 2.2 / c.fx * c.depth_scale + 2.0,
                    "{x},{y}: {got} vs {want}"
                );
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
        for x in [
            -0.5f32, -0.49, -0.2, 0.0, 0.49, 0.5, 0.51, 1.5, 2.5, 319.4, 319.6, 65535.4, 78000.7,
        ] {
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
}
