//! Unit tests of MOTION: the Jacobians against finite differences, the bilinear lerps
//! and the normal equations. `loops.rs`: the structure-of-arrays loops against the
//! per-point loops they replaced.

use super::estimator::{Loops, Params};
use super::lanes::Lanes;
use super::reference::Reference;
use super::warp::NoiseGain;
use super::*;
use crate::camera::Camera;
use crate::config::{Config, DepthNoiseModel, Mode, Preset};
use crate::prepare::{ImageLevel, Preparer, simd};
use crate::scale::{self, Scale};
use crate::se3;
use ecvo_synth::{DepthNoise, SynthCamera, SynthSequence};
use nalgebra::Vector6;

mod loops;

/// A level whose intensity and depth are affine in the pixel coordinates, so that
/// central differences and bilinear interpolation are exact and finite
/// differences of the residuals must match the analytic Jacobians.
fn affine_level(fy: f64) -> ImageLevel {
    let cam = Camera {
        width: 64,
        height: 48,
        fx: 60.0,
        fy,
        cx: 31.5,
        cy: 23.5,
        depth_scale: 1000.0,
    };
    let (gx, gy, dx, dy) = (0.004f32, -0.003f32, 0.006f32, 0.004f32);
    let samples = (0..cam.pixels())
        .map(|i| {
            let (u, v) = ((i % cam.width) as f32, (i / cam.width) as f32);
            [
                0.3 + gx * u + gy * v,
                gx,
                gy,
                1.5 + dx * u + dy * v,
                dx,
                dy,
                0.0,
                0.0,
            ]
        })
        .collect();
    ImageLevel {
        camera: Some(cam),
        samples,
    }
}

fn params(weighting: Weighting, noise: DepthNoiseModel) -> Params {
    Params {
        nu: 5.0,
        lambda: 1.0,
        weighting,
        noise: NoiseGain::of(noise, 1.0),
        scale_tolerance: 1e-3,
        zz_floor: 0.0,
        photometric: true,
        rotation_prior: None,
    }
}

/// The residuals of the last warp: `(ri, rz)` of each point, in order.
fn residual_pairs(est: &MotionEstimator) -> Vec<(f32, f32)> {
    est.warped()
        .iter()
        .flat_map(|c| c.ri[..c.n].iter().copied().zip(c.rz[..c.n].iter().copied()))
        .collect()
}

#[test]
fn analytic_jacobians_match_finite_differences() {
    for fy in [58.0, -58.0] {
        let level = affine_level(fy);
        let cam = *level.camera();
        let points: Vec<[f32; 4]> = (0..40)
            .map(|k| {
                let (u, v, z) = (
                    10.0 + (k % 8) as f64 * 5.0,
                    8.0 + (k / 8) as f64 * 6.0,
                    1.2 + 0.02 * k as f64,
                );
                [
                    ((u - cam.cx) / cam.fx * z) as f32,
                    ((v - cam.cy) / cam.fy * z) as f32,
                    z as f32,
                    0.5,
                ]
            })
            .collect();
        let t = se3::exp(&Vector6::new(0.02, -0.01, 0.03, 0.01, -0.02, 0.015));
        let mut est = MotionEstimator::new();
        let params = params(Weighting::Bivariate, DepthNoiseModel::Constant);
        est.load(&points);
        let n = est.warp(&t, &level, &params);
        assert_eq!(n, points.len());
        // The analytic Jacobians of every point, lane by lane.
        let c = &est.warped()[0];
        let mut jac = Vec::new();
        let l = lanes::Base;
        for b in (0..c.padded()).step_by(lanes::LANES) {
            let v = |a: &Vec<f32>| l.load(a, b);
            let f = (l.splat(cam.fx as f32), l.splat(cam.fy as f32));
            let (ji, jz) = normal::jacobians(
                l,
                [v(&c.x), v(&c.y), v(&c.z)],
                [v(&c.gx), v(&c.gy)],
                [v(&c.dx), v(&c.dy)],
                v(&c.sz),
                f.0,
                f.1,
            );
            for k in 0..lanes::LANES {
                jac.push((ji.map(|j| l.to_array(j)[k]), jz.map(|j| l.to_array(j)[k])));
            }
        }
        let h = 1e-4;
        for k in 0..6 {
            let mut d = Vector6::zeros();
            d[k] = h;
            est.warp(&(se3::exp(&d) * t), &level, &params);
            let plus = residual_pairs(&est);
            est.warp(&(se3::exp(&-d) * t), &level, &params);
            let minus = residual_pairs(&est);
            for i in 0..n {
                let (ji, jz) = jac[i];
                let fd_i = (plus[i].0 - minus[i].0) as f64 / (2.0 * h);
                let fd_z = (plus[i].1 - minus[i].1) as f64 / (2.0 * h);
                assert!(
                    (fd_i - ji[k] as f64).abs() < 2e-3 * (1.0 + fd_i.abs()),
                    "fy {fy} J_I[{k}] point {i}: fd {fd_i} analytic {}",
                    ji[k]
                );
                assert!(
                    (fd_z - jz[k] as f64).abs() < 2e-3 * (1.0 + fd_z.abs()),
                    "fy {fy} J_Z[{k}] point {i}: fd {fd_z} analytic {}",
                    jz[k]
                );
            }
        }
    }
}

/// The warp's interpolation (three lerps, shared with the per-point reference) against
/// the four weighted corners it replaced: within rounding, exact at the corners, and
/// NaN wherever a corner of the channel is NaN.
#[test]
fn lerps_interpolate_like_weighted_corners() {
    let corner = |k: f32| -> crate::prepare::Sample {
        std::array::from_fn(|c| (c as f32 + 1.0) * (0.3 + k) - 0.7 * k * k)
    };
    let (p00, p01, p10, p11) = (corner(0.0), corner(1.0), corner(2.0), corner(3.5));
    for (ax, ay) in [
        (0.0, 0.0),
        (1.0, 0.0),
        (0.0, 1.0),
        (0.25, 0.75),
        (0.5, 0.5),
        (0.9, 0.1),
    ] {
        let got = warp::lerp_sample(&p00, &p01, &p10, &p11, ax, ay);
        let (w00, w01, w10, w11) = (
            (1.0 - ax) * (1.0 - ay),
            ax * (1.0 - ay),
            (1.0 - ax) * ay,
            ax * ay,
        );
        for c in 0..8 {
            let want = w00 * p00[c] + w01 * p01[c] + w10 * p10[c] + w11 * p11[c];
            assert!(
                (got[c] - want).abs() <= 1e-5 * want.abs().max(1.0),
                "({ax}, {ay}) channel {c}: {} against {want}",
                got[c]
            );
        }
    }
    assert_eq!(warp::lerp_sample(&p00, &p01, &p10, &p11, 1.0, 1.0), p11);
    let mut hole = p10;
    hole[3] = f32::NAN;
    let v = warp::lerp_sample(&p00, &p01, &hole, &p11, 0.5, 0.5);
    assert!(v[3].is_nan() && v[..3].iter().chain(&v[4..]).all(|x| x.is_finite()));
}

#[test]
fn normal_equations_merge_and_solve() {
    let mut a = NormalEquations::default();
    let mut k = 0;
    for r in 0..6 {
        for c in r..6 {
            a.h[k] = if r == c { 2.0 } else { 0.0 };
            k += 1;
        }
    }
    a.g = [2.0, -4.0, 0.0, 0.0, 6.0, 0.0];
    let b = a;
    a.merge(&b);
    let step = a.solve().unwrap();
    assert_eq!(step.as_slice(), &[-1.0, 2.0, 0.0, 0.0, -3.0, 0.0]);
    assert!(NormalEquations::default().solve().is_none());
}
