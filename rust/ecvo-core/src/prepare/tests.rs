//! The fused preparation against the bilateral filter as first written and against
//! the old pixel-by-pixel preparation, bit for bit, on both SIMD paths.

use super::reference::OldPreparer;
use super::{ImageLevel, PreparedFrame, Template};
use crate::camera::{Camera, FrameView};
use crate::config::Config;
use crate::config::{BilateralConfig, Mode, Preset};
use crate::prepare::{Preparer, bilateral, simd};
use ecvo_synth::{SynthCamera, SynthSequence};
use std::sync::atomic::Ordering;

/// The bilateral filter as first written: pixel after pixel, its window clipped at
/// the image border.
fn clipped_reference(
    depth: &[f32],
    w: usize,
    h: usize,
    spatial: &[f32],
    r: usize,
    sr: f32,
) -> Vec<f32> {
    let side = 2 * r + 1;
    let z0: Vec<f32> = depth
        .iter()
        .map(|&z| if z.is_finite() { z } else { 0.0 })
        .collect();
    let mut out = vec![f32::NAN; w * h];
    for y in 0..h {
        for x in 0..w {
            let zc = z0[y * w + x];
            if zc == 0.0 {
                continue;
            }
            let s = sr * zc;
            let quarter_inv = 0.25 / (2.0 * s * s);
            let (mut acc, mut wsum) = (0.0f32, 0.0f32);
            for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                    let z = z0[yy * w + xx];
                    let d = z - zc;
                    let t = (1.0 - d * d * quarter_inv).max(0.0);
                    let t2 = t * t;
                    let wgt = spatial[(yy + r - y) * side + (xx + r - x)] * t2 * t2;
                    acc += wgt * z;
                    wsum += wgt;
                }
            }
            out[y * w + x] = acc / wsum;
        }
    }
    out
}

fn camera(w: usize, h: usize) -> Camera {
    Camera {
        width: w,
        height: h,
        fx: 100.0,
        fy: 100.0,
        cx: w as f64 / 2.0,
        cy: h as f64 / 2.0,
        depth_scale: 1000.0,
    }
}

#[test]
fn blocked_bilateral_equals_the_clipped_filter_bit_for_bit() {
    // Sizes around the 64-pixel blocks, holes, depth steps and slopes.
    for (w, h, r, sr) in [
        (37, 23, 1, 0.02),
        (150, 41, 2, 0.02),
        (64, 9, 3, 0.05),
        (129, 17, 2, 0.35),
    ] {
        let mut config = Config::new(camera(w, h), Preset::Pc, Mode::L2);
        config.filter.bilateral = Some(BilateralConfig {
            radius: r,
            sigma_space_px: 1.5,
            sigma_depth_rel: sr,
        });
        let spatial = Preparer::new(&config).spatial;
        let mut seed = 12345u32;
        let raw: Vec<u16> = (0..w * h)
            .map(|i| {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let (x, y) = (i % w, i / w);
                if seed >> 28 == 0 || x == 5 {
                    0
                } else {
                    let step = if x > w / 2 { 1200 } else { 0 };
                    (800 + 10 * y + step + (seed >> 29) as usize) as u16
                }
            })
            .collect();
        let range = bilateral::DepthRange {
            scale: 1.0 / 1000.0,
            lo: 0.1,
            hi: 10.0,
        };
        let mut depth = vec![0.0; w * h];
        bilateral::load_plain(&raw, range, &mut depth);
        let want = clipped_reference(&depth, w, h, &spatial, r, sr);
        for baseline in [false, true] {
            simd::BASELINE_ONLY.store(baseline, Ordering::Relaxed);
            let mut padded = Vec::new();
            bilateral::load_padded(&raw, w, h, r, range, &mut padded);
            let mut got = vec![0.0; w * h];
            bilateral::filter(&padded, &spatial, w, r, sr, &mut got);
            for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                assert_eq!(
                    a.to_bits(),
                    b.to_bits(),
                    "{w}x{h} r {r} baseline {baseline}: pixel {i}: {a} vs {b}"
                );
            }
        }
        simd::BASELINE_ONLY.store(false, Ordering::Relaxed);
    }
}

fn bits3(v: &[[f32; 3]]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn same(a: &PreparedFrame, b: &PreparedFrame, what: &str) {
    assert_eq!(a.timestamp.to_bits(), b.timestamp.to_bits(), "{what}");
    assert_eq!(a.valid_depth, b.valid_depth, "{what}: valid_depth");
    assert_eq!(a.textured_pixels, b.textured_pixels, "{what}: textured");
    assert_eq!(
        a.removed_by_normal, b.removed_by_normal,
        "{what}: by normal"
    );
    assert_eq!(
        a.removed_by_contour, b.removed_by_contour,
        "{what}: by contour"
    );
    assert!(bits3(&a.normals) == bits3(&b.normals), "{what}: normals");
    assert_eq!(a.levels.len(), b.levels.len(), "{what}: levels");
    for (k, (la, lb)) in a.levels.iter().zip(&b.levels).enumerate() {
        assert_eq!(la.camera, lb.camera, "{what}: level {k} camera");
        let bits = |l: &ImageLevel| -> Vec<[u32; 8]> {
            l.samples.iter().map(|s| s.map(f32::to_bits)).collect()
        };
        assert!(bits(la) == bits(lb), "{what}: level {k} samples");
    }
    assert_eq!(a.templates.len(), b.templates.len(), "{what}: templates");
    for (k, (ta, tb)) in a.templates.iter().zip(&b.templates).enumerate() {
        assert_eq!(ta.pyramid_level, tb.pyramid_level, "{what}: template {k}");
        let bits = |t: &Template| -> Vec<[u32; 4]> {
            t.points.iter().map(|p| p.map(f32::to_bits)).collect()
        };
        assert!(bits(ta) == bits(tb), "{what}: template {k} points");
    }
}

#[test]
fn fused_passes_equal_the_old_preparation_bit_for_bit() {
    let phone = SynthCamera::phone_320x180();
    let odd = SynthCamera {
        width: 67,
        height: 45,
        fx: 60.0,
        fy: -58.0,
        cx: 33.0,
        cy: 21.7,
        depth_scale: 5000.0,
    };
    for cam in [phone, odd] {
        let mut seq = SynthSequence::phone_320x180(8, 3);
        seq.camera = cam;
        let c = crate::Camera {
            width: cam.width,
            height: cam.height,
            fx: cam.fx,
            fy: cam.fy,
            cx: cam.cx,
            cy: cam.cy,
            depth_scale: cam.depth_scale,
        };
        let mut configs = Vec::new();
        for preset in [Preset::Pc, Preset::Phone] {
            configs.push(Config::new(c, preset, Mode::L2));
        }
        let mut no_filters = Config::new(c, Preset::Pc, Mode::L2);
        no_filters.filter.bilateral = None;
        no_filters.filter.normal_max_angle_deg = None;
        configs.push(no_filters);
        let mut contour_only = Config::new(c, Preset::Pc, Mode::L2);
        contour_only.filter.normal_max_angle_deg = None;
        configs.push(contour_only);
        let mut normal_only = Config::new(c, Preset::Phone, Mode::L2);
        normal_only.filter.contour_angle_deg = None;
        configs.push(normal_only);
        for (k, config) in configs.iter().enumerate() {
            let mut old = OldPreparer::new(config);
            let mut new = Preparer::new(config);
            // Reused outputs, as in a frame pool.
            let (mut want, mut got) = (PreparedFrame::default(), PreparedFrame::default());
            for i in [0, 5, 6] {
                let f = seq.frame(i);
                let view = FrameView {
                    timestamp: f.timestamp,
                    intensity: &f.intensity,
                    depth: &f.depth,
                };
                old.prepare_into(view, &mut want).unwrap();
                for baseline in [false, true] {
                    simd::BASELINE_ONLY.store(baseline, Ordering::Relaxed);
                    new.prepare_into(view, &mut got).unwrap();
                    let what = format!(
                        "{}x{} config {k} frame {i} baseline {baseline}",
                        cam.width, cam.height
                    );
                    same(&got, &want, &what);
                }
                simd::BASELINE_ONLY.store(false, Ordering::Relaxed);
            }
        }
    }
}

#[test]
fn fused_passes_equal_the_old_preparation_on_small_random_frames() {
    // The fuzz target's sizes (from 8x8): rows and columns that are all border,
    // odd sizes at every pyramid level, random holes and depth steps.
    let mut seed = 987_654_321u32;
    let mut next = move || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        seed
    };
    for (w, h) in [(8, 8), (9, 11), (13, 8), (17, 9), (64, 48)] {
        let c = Camera {
            width: w,
            height: h,
            fx: 20.0,
            fy: 21.0,
            cx: w as f64 / 2.0 - 0.3,
            cy: h as f64 / 2.0 + 0.2,
            depth_scale: 1000.0,
        };
        for preset in [Preset::Pc, Preset::Phone] {
            let config = Config::new(c, preset, Mode::L2);
            let (mut old, mut new) = (OldPreparer::new(&config), Preparer::new(&config));
            let (mut want, mut got) = (PreparedFrame::default(), PreparedFrame::default());
            for k in 0..6 {
                let intensity: Vec<u8> = (0..w * h).map(|_| (next() >> 24) as u8).collect();
                let depth: Vec<u16> = (0..w * h)
                    .map(|i| {
                        let r = next();
                        if r >> 29 == 0 {
                            0
                        } else {
                            let step = if (i % w) > w / 2 { 700 } else { 0 };
                            (900 + step + (r >> 26)) as u16
                        }
                    })
                    .collect();
                let view = FrameView {
                    timestamp: k as f64,
                    intensity: &intensity,
                    depth: &depth,
                };
                old.prepare_into(view, &mut want).unwrap();
                new.prepare_into(view, &mut got).unwrap();
                same(&got, &want, &format!("{w}x{h} {preset:?} frame {k}"));
            }
        }
    }
}
