//! The fused preparation against the bilateral filter as first written and against
//! the old pixel-by-pixel preparation, bit for bit, on both SIMD paths.

use super::reference::OldPreparer;
use super::{ImageLevel, PreparedFrame, Template};
use crate::camera::{Camera, FrameView};
use crate::config::Config;
use crate::config::{BilateralConfig, Mode, Preset};
use crate::prepare::{Preparer, bilateral, simd};
use ecvo_synth::{SynthCamera, SynthSequence};

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

/// The default configuration with every frame prepared whole (the chain's): what
/// these tests compare.
fn whole_config(c: Camera, preset: Preset, mode: Mode) -> Config {
    Config {
        keyframes: false,
        ..Config::new(c, preset, mode)
    }
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
    // Sizes around the 16-pixel blocks, holes, depth steps and slopes.
    for (w, h, r, sr) in [
        (37, 23, 1, 0.02),
        (150, 41, 2, 0.02),
        (64, 9, 3, 0.05),
        (129, 17, 2, 0.35),
    ] {
        let mut config = whole_config(camera(w, h), Preset::Pc, Mode::L2);
        config.filter.bilateral = Some(BilateralConfig {
            radius: r,
            sigma_space_px: 1.5,
            sigma_depth_rel: sr,
        });
        let spatial = Preparer::whole(&config).spatial;
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
        simd::on_each_path(|path| {
            let mut padded = Vec::new();
            bilateral::load_padded(&raw, w, h, r, range, &mut padded);
            let mut got = vec![0.0; w * h];
            bilateral::filter(&padded, &spatial, w, r, sr, &mut got);
            for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                assert_eq!(
                    a.to_bits(),
                    b.to_bits(),
                    "{w}x{h} r {r} {path}: pixel {i}: {a} vs {b}"
                );
            }
        });
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
            configs.push(whole_config(c, preset, Mode::L2));
        }
        let mut no_filters = whole_config(c, Preset::Pc, Mode::L2);
        no_filters.filter.bilateral = None;
        no_filters.filter.normal_max_angle_deg = None;
        configs.push(no_filters);
        let mut contour_only = whole_config(c, Preset::Pc, Mode::L2);
        contour_only.filter.normal_max_angle_deg = None;
        configs.push(contour_only);
        let mut normal_only = whole_config(c, Preset::Phone, Mode::L2);
        normal_only.filter.contour_angle_deg = None;
        configs.push(normal_only);
        for (k, config) in configs.iter().enumerate() {
            let mut old = OldPreparer::new(config);
            let mut new = Preparer::whole(config);
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
                simd::on_each_path(|path| {
                    new.prepare_into(view, &mut got).unwrap();
                    let what = format!("{}x{} config {k} frame {i} {path}", cam.width, cam.height);
                    same(&got, &want, &what);
                });
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
            let config = whole_config(c, preset, Mode::L2);
            let (mut old, mut new) = (OldPreparer::new(&config), Preparer::whole(&config));
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

/// A 160x120 frame: the left half a textured poster on a flat wall at 2 m facing the
/// camera, the right half blank (one gray) with depth waves of 10 cm.
fn poster_and_waves() -> (Camera, Vec<u8>, Vec<u16>) {
    let (w, h) = (160, 120);
    let c = Camera {
        width: w,
        height: h,
        fx: 130.0,
        fy: 130.0,
        cx: 79.5,
        cy: 59.5,
        depth_scale: 1000.0,
    };
    let mut intensity = vec![128u8; w * h];
    let mut depth = vec![2000u16; w * h];
    for y in 0..h {
        for x in 0..w {
            if x < w / 2 {
                let v = ((x / 3 + y / 5) % 4) as u8 * 40 + ((x * 7 + y * 3) % 11) as u8 * 5;
                intensity[y * w + x] = 40 + v;
            } else {
                let t = x as f32 / 6.0 + y as f32 / 9.0;
                depth[y * w + x] = (2000.0 + 100.0 * t.sin()) as u16;
            }
        }
    }
    (c, intensity, depth)
}

fn prepare(config: &Config, intensity: &[u8], depth: &[u16]) -> PreparedFrame {
    let mut p = Preparer::whole(config);
    let mut out = PreparedFrame::for_config(config);
    let view = FrameView {
        timestamp: 0.0,
        intensity,
        depth,
    };
    p.prepare_into(view, &mut out).unwrap();
    out
}

fn budgeted(c: Camera, budget: Option<usize>) -> Config {
    let mut config = whole_config(c, Preset::Pc, Mode::L2);
    config.motion.set_point_budget(0, budget);
    config.motion.set_point_budget(1, budget);
    config
}

fn point_bits(t: &Template) -> Vec<[u32; 4]> {
    t.points.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn point_budget_keeps_at_most_the_budget_of_the_plain_points_in_order() {
    let (c, intensity, depth) = poster_and_waves();
    let plain = prepare(&budgeted(c, None), &intensity, &depth);
    for budget in [64, 300, 1000, 2500] {
        let config = budgeted(c, Some(budget));
        let got = prepare(&config, &intensity, &depth);
        for (k, (step, (t, p))) in config
            .motion
            .levels
            .iter()
            .zip(got.templates.iter().zip(&plain.templates))
            .enumerate()
        {
            let (tb, pb) = (point_bits(t), point_bits(p));
            match step.max_points {
                None => assert!(tb == pb, "step {k}: an unbudgeted step changed"),
                Some(n) => {
                    assert_eq!(tb.len(), n.min(pb.len()), "budget {n} step {k}");
                    // A subsequence of the plain template: same points, row-major.
                    let mut it = pb.iter();
                    assert!(
                        tb.iter().all(|q| it.any(|p| p == q)),
                        "budget {n} step {k}: not an ordered subset"
                    );
                }
            }
        }
    }
}

#[test]
fn a_budget_above_the_candidates_is_bit_identical_to_none() {
    let (c, intensity, depth) = poster_and_waves();
    let plain = prepare(&budgeted(c, None), &intensity, &depth);
    let big = prepare(&budgeted(c, Some(1 << 20)), &intensity, &depth);
    same(&big, &plain, "budget 2^20");
}

#[test]
fn selection_keeps_both_textured_and_depth_only_points_spread_out() {
    let (c, intensity, depth) = poster_and_waves();
    let budget = 600;
    let got = prepare(&budgeted(c, Some(budget)), &intensity, &depth);
    // Level 0 (stride 2): about 4,500 candidates, half of them on each side.
    let t = got.templates.last().unwrap();
    assert_eq!(t.pyramid_level, 0);
    assert_eq!(t.points.len(), budget);
    let left = t.points.iter().filter(|p| p[0] < 0.0).count();
    let right = budget - left;
    assert!(
        left >= budget / 4 && right >= budget / 4,
        "poster {left}, blank waves {right}"
    );
    // Spread: the points fall into most 10x10-pixel blocks of the image.
    let mut blocks = std::collections::HashSet::new();
    for p in &t.points {
        let x = (p[0] / p[2] * 130.0 + 79.5).round() as i32;
        let y = (p[1] / p[2] * 130.0 + 59.5).round() as i32;
        blocks.insert((x / 10, y / 10));
    }
    assert!(blocks.len() >= 16 * 12 * 3 / 4, "{} blocks", blocks.len());
}

#[test]
fn selection_finds_depth_structure_on_a_textureless_frame() {
    // One gray everywhere; a flat wall with a raised ramp in its middle third.
    let (w, h) = (160, 120);
    let (c, _, _) = poster_and_waves();
    let intensity = vec![90u8; w * h];
    let mut depth = vec![2500u16; w * h];
    for y in 0..h {
        for x in w / 3..2 * w / 3 {
            depth[y * w + x] = 2500 - (x - w / 3) as u16 * 8;
        }
    }
    let on_ramp = |p: &&[f32; 4]| {
        let x = p[0] / p[2] * 130.0 + 79.5;
        x > (w / 3) as f32 + 2.0 && x < (2 * w / 3) as f32 - 2.0
    };
    // The cell grid follows the budget (about one cell per point); the cells on the
    // ramp, a third of them, all keep a point before any cell of the blank wall.
    for budget in [128, 400] {
        let got = prepare(&budgeted(c, Some(budget)), &intensity, &depth);
        for t in &got.templates[2..] {
            assert_eq!(t.points.len(), budget);
            let n = t.points.iter().filter(on_ramp).count();
            assert!(
                n * 10 >= budget * 3,
                "level {}: {n} of {budget} on the ramp",
                t.pyramid_level
            );
        }
    }
}

#[test]
fn selection_is_deterministic_with_reused_buffers() {
    let (c, intensity, depth) = poster_and_waves();
    let config = budgeted(c, Some(700));
    let first = prepare(&config, &intensity, &depth);
    // A warm preparer and a reused output, with another frame in between.
    let mut p = Preparer::whole(&config);
    let mut out = PreparedFrame::for_config(&config);
    let flat = vec![100u8; intensity.len()];
    for (i, d) in [(&flat, &depth), (&intensity, &depth)] {
        let view = FrameView {
            timestamp: 0.0,
            intensity: i,
            depth: d,
        };
        p.prepare_into(view, &mut out).unwrap();
    }
    same(&out, &first, "reused");
}

/// The points `for_each_point` visits, as bits.
fn cloud_bits(f: &PreparedFrame) -> Vec<([u32; 3], [u32; 3], u8)> {
    let mut v = Vec::new();
    f.for_each_point(3, |p, n, i| {
        v.push((p.map(f32::to_bits), n.map(f32::to_bits), i))
    });
    v
}

/// A schedule that does not track level 0 (the default at 640x480) gets no samples
/// there, and nothing else changes: the other levels, the templates, the counts and
/// the cloud's points are those of a schedule that tracks it, bit for bit, in reused
/// pooled frames and on every SIMD path.
#[test]
fn an_untracked_level_gets_no_samples_and_changes_nothing_else() {
    let cam = SynthCamera::phone_320x180();
    let seq = SynthSequence::phone_320x180(8, 3);
    let c = Camera {
        width: cam.width,
        height: cam.height,
        fx: cam.fx,
        fy: cam.fy,
        cx: cam.cx,
        cy: cam.cy,
        depth_scale: cam.depth_scale,
    };
    let all = whole_config(c, Preset::Pc, Mode::L2);
    let mut coarse = all.clone();
    coarse.motion.levels = crate::parse_schedule("3/1/20,2/1/15,1/1/10", &c).unwrap();
    assert!(all.motion.levels.iter().any(|l| l.pyramid_level == 0));
    let (mut pa, mut pc) = (Preparer::whole(&all), Preparer::whole(&coarse));
    let (mut fa, mut fc) = (
        PreparedFrame::for_config(&all),
        PreparedFrame::for_config(&coarse),
    );
    for i in [0, 4, 5] {
        let f = seq.frame(i);
        let view = FrameView {
            timestamp: f.timestamp,
            intensity: &f.intensity,
            depth: &f.depth,
        };
        simd::on_each_path(|path| {
            pa.prepare_into(view, &mut fa).unwrap();
            pc.prepare_into(view, &mut fc).unwrap();
            let what = format!("frame {i} {path}");
            assert!(fc.levels[0].samples.is_empty(), "{what}");
            assert_eq!(
                fc.levels[0].samples.capacity(),
                0,
                "{what}: nothing reserved"
            );
            assert!(!fa.levels[0].samples.is_empty(), "{what}");
            assert_eq!(fc.textured_pixels, fa.textured_pixels, "{what}: textured");
            assert!(fa.textured_pixels > 0, "{what}");
            assert_eq!(fc.valid_depth, fa.valid_depth, "{what}");
            assert!(bits3(&fc.normals) == bits3(&fa.normals), "{what}: normals");
            for k in 1..fa.levels.len() {
                let bits = |l: &ImageLevel| -> Vec<[u32; 8]> {
                    l.samples.iter().map(|s| s.map(f32::to_bits)).collect()
                };
                assert!(
                    bits(&fc.levels[k]) == bits(&fa.levels[k]),
                    "{what}: level {k}"
                );
            }
            for t in &fc.templates {
                let same_step = fa
                    .templates
                    .iter()
                    .find(|u| u.pyramid_level == t.pyramid_level)
                    .unwrap();
                assert!(point_bits(t) == point_bits(same_step), "{what}: template");
            }
            let cloud = cloud_bits(&fc);
            assert!(!cloud.is_empty(), "{what}");
            assert!(cloud == cloud_bits(&fa), "{what}: cloud points");
        });
    }
}

/// A preparer that keeps no normals drops the same pixels and writes the same levels,
/// templates and counts as one that does, bit for bit, on every SIMD path and for
/// every filter setting; its frames have no normals, and turning them back on gives
/// them again.
#[test]
fn frames_without_normals_are_the_same_frames() {
    let cam = SynthCamera::phone_320x180();
    let seq = SynthSequence::phone_320x180(8, 3);
    let c = Camera {
        width: cam.width,
        height: cam.height,
        fx: cam.fx,
        fy: cam.fy,
        cx: cam.cx,
        cy: cam.cy,
        depth_scale: cam.depth_scale,
    };
    let mut configs = vec![
        whole_config(c, Preset::Pc, Mode::L2),
        whole_config(c, Preset::Phone, Mode::L2),
    ];
    let mut contour_only = whole_config(c, Preset::Pc, Mode::L2);
    contour_only.filter.normal_max_angle_deg = None;
    configs.push(contour_only);
    // Neither removal filter: the preparer without normals skips the pass.
    let mut no_removal = whole_config(c, Preset::Pc, Mode::L2);
    no_removal.filter.normal_max_angle_deg = None;
    no_removal.filter.contour_angle_deg = None;
    configs.push(no_removal);
    for (k, config) in configs.iter().enumerate() {
        let (mut with, mut without) = (Preparer::whole(config), Preparer::whole(config));
        without.set_normals(false);
        let (mut fw, mut fo) = (
            PreparedFrame::for_config(config),
            PreparedFrame::for_config(config),
        );
        for i in [0, 3, 4] {
            let f = seq.frame(i);
            let view = FrameView {
                timestamp: f.timestamp,
                intensity: &f.intensity,
                depth: &f.depth,
            };
            simd::on_each_path(|path| {
                with.prepare_into(view, &mut fw).unwrap();
                without.prepare_into(view, &mut fo).unwrap();
                let what = format!("config {k} frame {i} {path}");
                assert!(fo.normals.is_empty(), "{what}");
                assert!(fw.normals.iter().any(|n| n[0].is_finite()), "{what}");
                assert!(
                    fo.removed_by_normal + fo.removed_by_contour > 0 || k >= 2,
                    "{what}"
                );
                if k == 3 {
                    assert_eq!(fo.removed_by_normal + fo.removed_by_contour, 0, "{what}");
                }
                let mut fo_with = fo.clone();
                fo_with.normals = fw.normals.clone();
                same(&fo_with, &fw, &what);
            });
        }
        without.set_normals(true);
        let f = seq.frame(5);
        let view = FrameView {
            timestamp: f.timestamp,
            intensity: &f.intensity,
            depth: &f.depth,
        };
        with.prepare_into(view, &mut fw).unwrap();
        without.prepare_into(view, &mut fo).unwrap();
        same(&fo, &fw, &format!("config {k}, normals on again"));
    }
}
