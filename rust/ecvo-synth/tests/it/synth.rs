//! End-to-end properties of the synthetic renderer, noise model and paths.

use ecvo_synth::{
    CameraPath, DepthNoise, EdgeDropout, NO_SURFACE, Rendered, Scene, SynthCamera, SynthSequence,
    apply_noise, edge_mask, look_at, render, render_supersampled, to_raw_depth,
};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

fn pose_looking(eye: Point3<f64>, target: Point3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(eye.coords),
        UnitQuaternion::from_rotation_matrix(&look_at(&eye, &target)),
    )
}

fn percentile(mut v: Vec<f64>, p: f64) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[((v.len() - 1) as f64 * p).round() as usize]
}

#[test]
fn backprojected_depth_lies_on_the_surface_it_came_from() {
    let seq = SynthSequence::phone_320x180(1, 4);
    let cam = seq.camera;
    for i in [0usize, 77] {
        let pose = seq.pose(i);
        let r = seq.render_clean(i);
        let centre = Point3::from(pose.translation.vector);
        let mut checked = 0;
        for v in (0..cam.height).step_by(3) {
            for u in (0..cam.width).step_by(3) {
                let k = v * cam.width + u;
                assert_ne!(r.surface_id[k], NO_SURFACE);
                let z = r.depth_m[k] as f64;
                let x_world = pose * cam.backproject(u as f64, v as f64, z);
                // On the plane of the surface recorded for the pixel...
                let d = seq.scene.plane_distance(r.surface_id[k], &x_world);
                assert!(d.abs() < 1e-6, "pixel ({u},{v}) is {d} m off its plane");
                // ...and it is the first surface along the ray (re-cast).
                let hit = seq.scene.cast(&centre, &(x_world - centre)).unwrap();
                assert!((hit.point - x_world).norm() < 1e-6, "({u},{v})");
                assert_eq!(hit.surface, r.surface_id[k]);
                // Projects back to the pixel.
                let (pu, pv) = cam
                    .project(&pose.inverse_transform_point(&x_world))
                    .unwrap();
                assert!((pu - u as f64).abs() < 1e-6 && (pv - v as f64).abs() < 1e-6);
                checked += 1;
            }
        }
        assert!(checked > 5000);
    }
}

#[test]
fn negative_fy_flips_the_image_vertically() {
    let scene = Scene::room(2);
    let cam = SynthCamera::phone_320x180();
    let flipped = SynthCamera { fy: -cam.fy, ..cam };
    let pose = CameraPath::handheld(2).pose_at(1.0);
    let a = render(&scene, &cam, &pose);
    let b = render(&scene, &flipped, &pose);
    let (w, h) = (cam.width, cam.height);
    for v in 0..h {
        for u in 0..w {
            let (i, j) = (v * w + u, (h - 1 - v) * w + u);
            assert!((a.depth_m[i] - b.depth_m[j]).abs() < 1e-5);
            assert!((a.intensity_f32[i] - b.intensity_f32[j]).abs() < 1e-3);
        }
    }
}

/// Pixels of `r` whose 3x3 neighbourhood lies on one surface seen at < 70° incidence.
fn interior(r: &Rendered, u: usize, v: usize) -> bool {
    let s = r.surface_id[v * r.width + u];
    (v - 1..=v + 1).all(|y| (u - 1..=u + 1).all(|x| r.surface_id[y * r.width + x] == s))
        && r.normal_dot_view[v * r.width + u] > 0.35
}

#[test]
fn brightness_constancy_between_two_poses() {
    let seq = SynthSequence::phone_320x180(30, 6);
    let cam = seq.camera;
    for (ia, ib) in [(0usize, 10usize), (40, 45)] {
        let (pa, pb) = (seq.pose(ia), seq.pose(ib));
        let (ra, rb) = (seq.render_clean(ia), seq.render_clean(ib));
        let a_to_b = pb.inverse() * pa;
        let mut errors = Vec::new();
        for v in (1..cam.height - 1).step_by(2) {
            for u in (1..cam.width - 1).step_by(2) {
                if !interior(&ra, u, v) {
                    continue;
                }
                let k = v * cam.width + u;
                let xb = a_to_b * cam.backproject(u as f64, v as f64, ra.depth_m[k] as f64);
                let Some((ub, vb)) = cam.project(&xb) else {
                    continue;
                };
                if !(ub >= 1.0
                    && vb >= 1.0
                    && ub < (cam.width - 2) as f64
                    && vb < (cam.height - 2) as f64)
                {
                    continue;
                }
                let (x0, y0) = (ub.floor() as usize, vb.floor() as usize);
                if !interior(&rb, x0, y0) || !interior(&rb, x0 + 1, y0 + 1) {
                    continue;
                }
                if rb.surface_id[y0 * cam.width + x0] != ra.surface_id[k] {
                    continue; // occluded in B
                }
                let zb = rb.depth_bilinear(ub, vb).unwrap();
                assert!(
                    (zb - xb.z).abs() < 2e-3 * xb.z,
                    "depth mismatch {zb} vs {}",
                    xb.z
                );
                let ib_val = rb.intensity_bilinear(ub, vb).unwrap();
                errors.push((ra.intensity_f32[k] as f64 - ib_val).abs());
            }
        }
        assert!(errors.len() > 3000, "only {} correspondences", errors.len());
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        let p90 = percentile(errors.clone(), 0.9);
        eprintln!(
            "frames {ia}->{ib}: n={} mean {mean:.3} p90 {p90:.3}",
            errors.len()
        );
        assert!(mean < 1.0, "mean |ΔI| = {mean}");
        assert!(p90 < 2.0, "90th percentile |ΔI| = {p90}");
    }
}

/// Camera 2 m in front of the wall at y = 2.5, optical axis along +y.
fn wall_view() -> (Scene, SynthCamera, Rendered) {
    let scene = Scene::room(0);
    let cam = SynthCamera::phone_320x180();
    let eye = Point3::new(-1.0, 0.5, 1.6);
    let r = render(&scene, &cam, &pose_looking(eye, eye + Vector3::y()));
    (scene, cam, r)
}

#[test]
fn gaussian_depth_noise_has_the_requested_std_at_2m() {
    let (_, cam, r) = wall_view();
    let noise = DepthNoise {
        sigma_at_1m: 0.003,
        ..DepthNoise::none()
    };
    let (_, raw) = apply_noise(&r, &cam, &noise, 11);
    let diffs: Vec<f64> = (0..raw.len())
        .filter(|&i| r.surface_id[i] == 5)
        .map(|i| {
            assert!((r.depth_m[i] - 2.0).abs() < 1e-6);
            raw[i] as f64 / cam.depth_scale - r.depth_m[i] as f64
        })
        .collect();
    assert!(diffs.len() > 20_000);
    let n = diffs.len() as f64;
    let mean = diffs.iter().sum::<f64>() / n;
    let std = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
    let expected = 0.003 * 4.0;
    assert!(
        (std - expected).abs() < 0.2 * expected,
        "std {std} vs {expected}"
    );
    assert!(
        (std - expected).abs() < 0.03 * expected,
        "std {std} vs {expected}"
    );
    assert!(mean.abs() < 0.0005, "bias {mean}");
}

#[test]
fn disparity_quantisation_steps_grow_with_depth_squared() {
    let (_, cam, r) = wall_view();
    let noise = DepthNoise {
        sigma_at_1m: 0.005,
        quantisation: true,
        ..DepthNoise::kinect_like()
    };
    let noise = DepthNoise {
        grazing_max_angle_deg: 90.0,
        edge_dropout: None,
        random_dropout: 0.0,
        ..noise
    };
    let (_, raw) = apply_noise(&r, &cam, &noise, 3);
    let mut levels: Vec<u16> = (0..raw.len())
        .filter(|&i| r.surface_id[i] == 5)
        .map(|i| raw[i])
        .collect();
    levels.sort_unstable();
    levels.dedup();
    assert!(levels.len() >= 4, "levels {levels:?}");
    let step_mm = noise.disparity_quantum * 4.0 * 1000.0; // ≈ 11.5 mm at 2 m
    for pair in levels.windows(2) {
        let step = (pair[1] - pair[0]) as f64;
        assert!(
            (step - step_mm).abs() < 0.15 * step_mm + 1.0,
            "step {step} vs {step_mm}"
        );
    }
}

#[test]
fn grazing_dropout_removes_exactly_the_oblique_pixels() {
    let seq = SynthSequence::phone_320x180(1, 8);
    let r = seq.render_clean(0);
    let noise = DepthNoise {
        grazing_max_angle_deg: 60.0,
        ..DepthNoise::none()
    };
    let (_, raw) = apply_noise(&r, &seq.camera, &noise, 1);
    let cos_max = 60f64.to_radians().cos();
    let mut dropped = 0;
    for i in 0..raw.len() {
        let ndv = r.normal_dot_view[i] as f64;
        if (ndv - cos_max).abs() < 1e-6 {
            continue;
        }
        assert_eq!(raw[i] == 0, ndv < cos_max, "pixel {i}, ndv {ndv}");
        dropped += usize::from(raw[i] == 0);
    }
    assert!(
        dropped > 500 && dropped < raw.len() / 2,
        "dropped {dropped}"
    );
}

#[test]
fn edge_dropout_only_near_depth_discontinuities() {
    let seq = SynthSequence::phone_320x180(1, 9);
    let r = seq.render_clean(20);
    let edge = EdgeDropout {
        relative_jump: 0.05,
        radius_px: 2,
    };
    let noise = DepthNoise {
        edge_dropout: Some(edge),
        ..DepthNoise::none()
    };
    let (_, raw) = apply_noise(&r, &seq.camera, &noise, 1);
    assert_eq!(
        edge_mask(&r.depth_m, r.width, r.height, &edge),
        raw.iter().map(|&d| d == 0).collect::<Vec<_>>()
    );
    let (w, h) = (r.width, r.height);
    let mut dropped = 0;
    for v in 0..h {
        for u in 0..w {
            let i = v * w + u;
            let window = |rad: usize| {
                let (y0, y1) = (v.saturating_sub(rad), (v + rad).min(h - 1));
                let (x0, x1) = (u.saturating_sub(rad), (u + rad).min(w - 1));
                (y0..=y1).flat_map(move |y| (x0..=x1).map(move |x| y * w + x))
            };
            let max_jump = window(2)
                .map(|j| {
                    let (a, b) = (r.depth_m[i] as f64, r.depth_m[j] as f64);
                    (a - b).abs() / a.min(b)
                })
                .fold(0.0, f64::max);
            // Missing exactly where a jump of more than 5 % is within 2 pixels.
            assert_eq!(
                raw[i] == 0,
                max_jump > 0.05,
                "pixel ({u},{v}) jump {max_jump}"
            );
            if raw[i] == 0 {
                dropped += 1;
                // A depth jump always involves another surface.
                assert!(window(2).any(|j| r.surface_id[j] != r.surface_id[i]));
            }
        }
    }
    // Box outlines are long: a few hundred pixels at least, but far from everything.
    assert!(dropped > 300 && dropped < w * h / 5, "dropped {dropped}");
}

#[test]
fn random_dropout_fraction_and_noise_free_conversion() {
    let seq = SynthSequence::phone_320x180(1, 10);
    let r = seq.render_clean(0);
    let (gray, raw) = apply_noise(&r, &seq.camera, &DepthNoise::none(), 5);
    assert_eq!(gray, r.intensity);
    assert_eq!(raw, to_raw_depth(&r, &seq.camera));
    for (i, &d) in raw.iter().enumerate() {
        assert!((d as f64 - r.depth_m[i] as f64 * 1000.0).abs() <= 0.5 + 1e-3);
    }
    let noise = DepthNoise {
        random_dropout: 0.1,
        ..DepthNoise::none()
    };
    let (_, raw) = apply_noise(&r, &seq.camera, &noise, 5);
    let frac = raw.iter().filter(|&&d| d == 0).count() as f64 / raw.len() as f64;
    assert!((frac - 0.1).abs() < 0.01, "dropout fraction {frac}");
}

#[test]
fn intensity_noise_has_the_requested_std() {
    let seq = SynthSequence::phone_320x180(1, 10);
    let r = seq.render_clean(0);
    let noise = DepthNoise {
        intensity_noise_sigma: 3.0,
        ..DepthNoise::none()
    };
    let (gray, _) = apply_noise(&r, &seq.camera, &noise, 5);
    let d: Vec<f64> = (0..gray.len())
        .filter(|&i| (10.0..245.0).contains(&r.intensity_f32[i]))
        .map(|i| gray[i] as f64 - r.intensity_f32[i] as f64)
        .collect();
    let std = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    // Rounding adds 1/12 gray level² of variance.
    assert!(
        (std - (9.0f64 + 1.0 / 12.0).sqrt()).abs() < 0.1,
        "std {std}"
    );
}

#[test]
fn frames_are_deterministic_and_seeds_change_the_noise() {
    let a = SynthSequence::phone_320x180(10, 42);
    let b = SynthSequence::phone_320x180(10, 42);
    let f = a.frame(3);
    assert_eq!(f, a.frame(3));
    assert_eq!(f, b.frame(3));
    assert_eq!(f.index, 3);
    assert!((f.timestamp - 0.1).abs() < 1e-12);
    let r = a.render_clean(3);
    let (_, d1) = apply_noise(&r, &a.camera, &a.noise, 1);
    let (_, d2) = apply_noise(&r, &a.camera, &a.noise, 2);
    let both = (0..d1.len()).filter(|&i| d1[i] > 0 && d2[i] > 0);
    let differing = both.clone().filter(|&i| d1[i] != d2[i]).count();
    assert!(
        differing * 2 > both.count(),
        "seeds give nearly identical noise"
    );
    // Consecutive frames use different noise seeds.
    assert_ne!(a.frame_seed(3), a.frame_seed(4));
    // A different sequence seed changes the noise (and textures) of the same frame.
    assert_ne!(SynthSequence::phone_320x180(10, 43).frame(3).depth, f.depth);
}

/// Finite-difference linear (m/s) and angular (rad/s) speeds along a path at 30 fps.
fn speeds(path: &CameraPath, seconds: f64) -> Vec<(f64, f64)> {
    let dt = 1.0 / 30.0;
    let n = (seconds / dt) as usize;
    (0..n)
        .map(|i| {
            let (p0, p1) = (
                path.pose_at(i as f64 * dt),
                path.pose_at((i + 1) as f64 * dt),
            );
            let rel = p0.inverse() * p1;
            (
                rel.translation.vector.norm() / dt,
                rel.rotation.angle() / dt,
            )
        })
        .collect()
}

#[test]
fn handheld_path_is_smooth_plausible_and_inside_the_room() {
    let scene = Scene::room(0);
    for seed in 0..6 {
        let path = CameraPath::handheld(seed);
        let s = speeds(&path, 60.0);
        let n = s.len() as f64;
        let mean_v = s.iter().map(|x| x.0).sum::<f64>() / n;
        let mean_w = s.iter().map(|x| x.1).sum::<f64>() / n;
        let max_v = s.iter().map(|x| x.0).fold(0.0, f64::max);
        let max_w = s.iter().map(|x| x.1).fold(0.0, f64::max);
        eprintln!(
            "seed {seed}: v mean {mean_v:.3} max {max_v:.3} m/s, w mean {:.1} max {:.1} deg/s",
            mean_w.to_degrees(),
            max_w.to_degrees()
        );
        assert!((0.1..0.4).contains(&mean_v), "mean speed {mean_v}");
        assert!(max_v < 0.5, "max speed {max_v}");
        assert!((5f64.to_radians()..30f64.to_radians()).contains(&mean_w));
        assert!(
            max_w < 40f64.to_radians(),
            "max angular speed {}",
            max_w.to_degrees()
        );
        // Smooth: speed changes little from one frame to the next (bounded acceleration).
        for pair in s.windows(2) {
            assert!((pair[1].0 - pair[0].0).abs() * 30.0 < 1.5);
            assert!((pair[1].1 - pair[0].1).abs() * 30.0 < 1.5);
        }
        for i in 0..1800 {
            let t = i as f64 / 30.0;
            let pose = path.pose_at(t);
            let eye = Point3::from(pose.translation.vector);
            let c = scene.clearance(&eye);
            assert!(c > 0.8, "seed {seed}, t {t}: clearance {c} at {eye}");
            // Looks towards the central boxes.
            let axis = pose.rotation * Vector3::z();
            let to_boxes = (Point3::new(0.0, 0.0, 0.4) - eye).normalize();
            assert!(axis.dot(&to_boxes) > 30f64.to_radians().cos());
            // Roll stays small: image x axis nearly horizontal.
            assert!((pose.rotation * Vector3::x()).z.abs() < 0.15);
        }
    }
}

#[test]
fn handheld_path_envelope_keeps_clear_of_every_surface() {
    // Whatever the seed and time, the camera stays within the wobble amplitudes of the
    // orbit ellipse; check the whole envelope against the room geometry.
    let scene = Scene::room(0);
    for seed in 0..20 {
        let path = CameraPath::handheld(seed);
        let amp = |h: &[ecvo_synth::Harmonic]| h.iter().map(|x| x.amplitude.abs()).sum::<f64>();
        let [wx, wy, wz] = &path.position_wobble;
        let (ax, ay, az) = (amp(wx), amp(wy), amp(wz));
        // Clearance is 1-Lipschitz: nominal clearance minus the offset radius bounds it.
        let radius = (ax * ax + ay * ay + az * az).sqrt();
        for k in 0..1440 {
            let theta = k as f64 * std::f64::consts::TAU / 1440.0;
            let p = Point3::new(
                path.orbit_centre.x + path.radius_x * theta.cos(),
                path.orbit_centre.y + path.radius_y * theta.sin(),
                path.height,
            );
            let c = scene.clearance(&p) - radius;
            assert!(c > 0.8, "seed {seed}: clearance bound {c} near {p}");
        }
    }
}

#[test]
fn smooth_orbit_has_constant_speed_and_looks_at_the_centre() {
    let centre = Point3::new(0.0, 0.0, 0.5);
    let path = CameraPath::smooth_orbit(centre, 2.0, 1.5, 0.1);
    for (v, w) in speeds(&path, 10.0) {
        assert!((v - 0.2).abs() < 1e-3, "speed {v}");
        assert!(w > 0.0 && w < 0.2);
    }
    let pose = path.pose_at(3.0);
    let c = pose.inverse_transform_point(&centre);
    assert!(c.x.abs() < 1e-9 && c.y.abs() < 1e-9 && c.z > 0.0);
}

#[test]
fn phone_preset_has_valid_depth_and_texture() {
    for seed in [1u64, 2] {
        let seq = SynthSequence::phone_320x180(300, seed);
        let (w, h) = (seq.camera.width, seq.camera.height);
        for i in [0usize, 150, 299] {
            let f = seq.frame(i);
            assert_eq!(f.depth.len(), w * h);
            let valid = f.depth.iter().filter(|&&d| d > 0).count() as f64 / (w * h) as f64;
            assert!(valid > 0.8, "seed {seed} frame {i}: valid depth {valid}");
            let min_mm = f.depth.iter().filter(|&&d| d > 0).min().unwrap();
            assert!(*min_mm > 500, "too close: {min_mm} mm");
            let mut grad = 0.0;
            for v in 0..h - 1 {
                for u in 0..w - 1 {
                    let p = f.intensity[v * w + u] as f64;
                    grad += (f.intensity[v * w + u + 1] as f64 - p).abs()
                        + (f.intensity[(v + 1) * w + u] as f64 - p).abs();
                }
            }
            let grad = grad / (2 * (w - 1) * (h - 1)) as f64;
            let mean = f.intensity.iter().map(|&x| x as f64).sum::<f64>() / (w * h) as f64;
            let std = (f
                .intensity
                .iter()
                .map(|&x| (x as f64 - mean).powi(2))
                .sum::<f64>()
                / (w * h) as f64)
                .sqrt();
            eprintln!("seed {seed} frame {i}: valid {valid:.3} mean|grad| {grad:.2} std {std:.1}");
            assert!(grad > 4.0, "mean |grad I| = {grad}");
            assert!(std > 35.0, "intensity std {std}");
        }
    }
}

#[test]
fn supersampling_variants_agree_on_smooth_regions() {
    let seq = SynthSequence::phone_320x180(1, 3);
    let pose = seq.pose(0);
    let a = render(&seq.scene, &seq.camera, &pose);
    let b = render_supersampled(&seq.scene, &seq.camera, &pose, 3);
    assert_eq!(a.depth_m, b.depth_m);
    let d: Vec<f64> = (0..a.intensity_f32.len())
        .map(|i| (a.intensity_f32[i] - b.intensity_f32[i]).abs() as f64)
        .collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    assert!(mean < 1.0, "mean difference {mean}");
}

#[test]
fn rendering_is_fast_enough() {
    let seq = SynthSequence::phone_320x180(1, 3);
    let pose = seq.pose(0);
    let t = std::time::Instant::now();
    let _ = render(&seq.scene, &seq.camera, &pose);
    let ms = t.elapsed().as_secs_f64() * 1e3;
    eprintln!("render 320x180: {ms:.1} ms");
    // Loose bound (test profile, shared machine); release is typically ~20-30 ms.
    assert!(ms < 1000.0, "{ms} ms");
}
