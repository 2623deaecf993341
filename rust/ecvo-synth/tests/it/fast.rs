//! The fast hand-held path (`CameraPath::fast_handheld`, `SynthSequence::fast_320x180`):
//! the requested peak speeds are reached, the viewing depth is the requested one, the
//! camera keeps clear of the geometry, and both noise models leave depth and texture.

use ecvo_synth::{
    CameraPath, DepthNoise, FAST_PERIOD_S, Scene, SynthSequence, apply_noise, render,
};
use nalgebra::{Point3, Vector3};

/// Peak linear (m/s) and angular (rad/s) speeds between consecutive 30 Hz frames.
fn peak_frame_speeds(seq: &SynthSequence) -> (f64, f64) {
    let (mut v, mut w) = (0.0f64, 0.0f64);
    for i in 0..seq.frames - 1 {
        let rel = seq.pose(i).inverse() * seq.pose(i + 1);
        let dt = seq.timestamp(i + 1) - seq.timestamp(i);
        v = v.max(rel.translation.vector.norm() / dt);
        w = w.max(rel.rotation.angle() / dt);
    }
    (v, w)
}

/// Mean rendered depth (metres, pixels that hit something) over every 10th frame.
fn mean_viewing_depth(seq: &SynthSequence) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in (0..seq.frames).step_by(10) {
        let r = seq.render_clean(i);
        for &z in r.depth_m.iter().filter(|&&z| z > 0.0) {
            sum += z as f64;
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn fast_streams_reach_the_requested_peak_speeds_at_the_requested_depth() {
    // (seed, depth m, deg/s, m/s): the suite's defaults and two other requests.
    let cases = [
        (1u64, 0.6, 90.0f64, 1.0),
        (2, 1.0, 90.0, 1.0),
        (3, 2.0, 90.0, 1.0),
        (4, 4.0, 90.0, 1.0),
        (5, 1.5, 45.0, 0.5),
        (6, 3.0, 120.0, 0.3),
    ];
    for (seed, depth, deg_s, m_s) in cases {
        let seq = SynthSequence::fast_handheld_320x180(150, seed, depth, deg_s.to_radians(), m_s);
        let (v, w) = peak_frame_speeds(&seq);
        let z = mean_viewing_depth(&seq);
        eprintln!(
            "seed {seed} depth {depth}: peak {v:.3} m/s (asked {m_s}), {:.1} deg/s (asked {deg_s}), mean depth {z:.2} m",
            w.to_degrees()
        );
        // The path is scaled so that no 30 Hz frame pair goes faster than asked; 150
        // frames (one period) sampled at 30 Hz come within 2 % of it.
        assert!(
            v <= m_s * 1.001 && v >= m_s * 0.98,
            "seed {seed}: peak linear speed {v} m/s, asked {m_s}"
        );
        let w_deg = w.to_degrees();
        assert!(
            w_deg <= deg_s * 1.001 && w_deg >= deg_s * 0.98,
            "seed {seed}: peak angular speed {w_deg} deg/s, asked {deg_s}"
        );
        assert!(
            (z / depth - 1.0).abs() < 0.12,
            "seed {seed}: mean viewing depth {z} m, asked {depth}"
        );
    }
}

#[test]
fn the_default_fast_sequence_is_fast_and_the_slow_one_is_not() {
    let fast = SynthSequence::fast_320x180(150, 1, 2.0);
    let (v, w) = peak_frame_speeds(&fast);
    assert!(
        v > 0.98 && w.to_degrees() > 88.0,
        "{v} m/s, {} deg/s",
        w.to_degrees()
    );
    let slow = SynthSequence::phone_320x180(150, 1);
    assert_eq!(slow.path, CameraPath::handheld(1));
    let (v, w) = peak_frame_speeds(&slow);
    assert!(v < 0.5 && w.to_degrees() < 40.0);
}

#[test]
fn fast_path_is_periodic_and_keeps_clear_of_the_geometry() {
    let scene = Scene::room(0);
    for seed in 0..8 {
        for depth in [0.5, 0.6, 1.0, 2.0, 3.0, 4.0] {
            let path = CameraPath::fast_handheld(seed, depth, 90f64.to_radians(), 1.0);
            let mut min_clearance = f64::INFINITY;
            for i in 0..1500 {
                let t = i as f64 * FAST_PERIOD_S / 1500.0;
                let pose = path.pose_at(t);
                let later = path.pose_at(t + FAST_PERIOD_S);
                assert!((pose.translation.vector - later.translation.vector).norm() < 1e-9);
                assert!(pose.rotation.angle_to(&later.rotation) < 1e-9);
                let eye = Point3::from(pose.translation.vector);
                min_clearance = min_clearance.min(scene.clearance(&eye));
                // Looks roughly at the wall x = 3, upright.
                let axis = pose.rotation * Vector3::z();
                assert!(
                    axis.x > 45f64.to_radians().cos(),
                    "seed {seed} t {t}: {axis}"
                );
                assert!((pose.rotation * Vector3::x()).z.abs() < 0.5);
            }
            // Never inside geometry, nor nearer than 40 cm to it (or 90 % of the depth).
            assert!(
                min_clearance > (0.9 * depth).min(0.4),
                "seed {seed} depth {depth}: clearance {min_clearance}"
            );
        }
    }
}

#[test]
fn fast_streams_have_depth_and_texture_with_both_noise_models() {
    for (seed, depth) in [(1u64, 0.6), (2, 1.0), (3, 2.0), (4, 4.0)] {
        let seq = SynthSequence::fast_320x180(150, seed, depth);
        let (w, h) = (seq.camera.width, seq.camera.height);
        for i in [0usize, 37, 75, 112, 149] {
            let r = render(&seq.scene, &seq.camera, &seq.pose(i));
            let near = r
                .depth_m
                .iter()
                .filter(|&&z| z > 0.0)
                .fold(f32::INFINITY, |a, &z| a.min(z));
            // Nothing in view much nearer than the wall (far off, the floor comes near).
            let limit = (0.75 * depth).min(0.45);
            assert!(near as f64 > limit, "frame {i}: nearest {near} m");
            for (name, noise) in [
                ("kinect", DepthNoise::kinect_like()),
                ("phone", DepthNoise::phone_like()),
            ] {
                let (intensity, raw) = apply_noise(&r, &seq.camera, &noise, seq.frame_seed(i));
                let valid = raw.iter().filter(|&&d| d > 0).count() as f64 / (w * h) as f64;
                let mut grad = 0.0;
                for v in 0..h - 1 {
                    for u in 0..w - 1 {
                        let p = intensity[v * w + u] as f64;
                        grad += (intensity[v * w + u + 1] as f64 - p).abs()
                            + (intensity[(v + 1) * w + u] as f64 - p).abs();
                    }
                }
                let grad = grad / (2 * (w - 1) * (h - 1)) as f64;
                eprintln!(
                    "depth {depth} frame {i} {name}: valid {valid:.3}, mean |grad| {grad:.2}"
                );
                assert!(valid > 0.7, "depth {depth} frame {i} {name}: valid {valid}");
                assert!(grad > 2.0, "depth {depth} frame {i} {name}: |grad| {grad}");
            }
        }
    }
}
