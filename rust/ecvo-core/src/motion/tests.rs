//! Unit tests of MOTION's pieces: the Jacobians and the normal equations.

use super::*;
use crate::camera::Camera;
use crate::prepare::ImageLevel;
use crate::se3;
use nalgebra::Vector6;

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
        let params = Params {
            nu: 5.0,
            lambda: 1.0,
            weighting: Weighting::Bivariate,
            quadratic_noise: false,
        };
        let n = est.residuals_at(&t, &points, &level, &params);
        assert_eq!(n, points.len());
        let base: Vec<Residual> = est.residuals().copied().collect();
        let h = 1e-4;
        for k in 0..6 {
            let mut d = Vector6::zeros();
            d[k] = h;
            let plus = {
                est.residuals_at(&(se3::exp(&d) * t), &points, &level, &params);
                est.residuals().copied().collect::<Vec<_>>()
            };
            let minus = {
                est.residuals_at(&(se3::exp(&-d) * t), &points, &level, &params);
                est.residuals().copied().collect::<Vec<_>>()
            };
            for (i, r) in base.iter().enumerate() {
                let (ji, jz) = jacobians(r, cam.fx as f32, cam.fy as f32);
                let fd_i = (plus[i].ri - minus[i].ri) as f64 / (2.0 * h);
                let fd_z = (plus[i].rz - minus[i].rz) as f64 / (2.0 * h);
                let jz = jz.expect("depth is valid everywhere");
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
