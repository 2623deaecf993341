//! The far-depth orbit (`Scene::hall`, `CameraPath::far_orbit`,
//! `SynthSequence::orbit_320x180`): the requested peak rotation per frame is reached and
//! held on average, the mean viewing depth is the requested one at 320x180 and
//! 640x480, the camera keeps clear of the geometry, and the path is deterministic in
//! its seed.

use ecvo_synth::{ORBIT_RADIUS_M, SynthCamera, SynthSequence, hall_apothem};

/// Per-frame rotation angles (radians) and linear steps (metres) of a sequence.
fn steps(seq: &SynthSequence) -> (Vec<f64>, Vec<f64>) {
    (0..seq.frames - 1)
        .map(|i| {
            let rel = seq.pose(i).inverse() * seq.pose(i + 1);
            (rel.rotation.angle(), rel.translation.vector.norm())
        })
        .unzip()
}

/// Mean rendered depth (metres, pixels that hit something) over every `every`th frame.
fn mean_viewing_depth(seq: &SynthSequence, every: usize) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for i in (0..seq.frames).step_by(every) {
        let r = seq.render_clean(i);
        for &z in r.depth_m.iter().filter(|&&z| z > 0.0) {
            sum += z as f64;
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn per_frame_rotation_peaks_at_the_requested_rate_and_stays_near_it() {
    for (deg_per_frame, depth, seed) in [(1.0, 2.0, 3u64), (2.0, 4.0, 5), (1.5, 3.0, 7)] {
        let w = (deg_per_frame * 30.0f64).to_radians();
        let seq = SynthSequence::orbit_320x180(150, seed, depth, w);
        let (rot, lin) = steps(&seq);
        let peak = rot.iter().cloned().fold(0.0, f64::max).to_degrees();
        let mean = (rot.iter().sum::<f64>() / rot.len() as f64).to_degrees();
        let min = rot
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min)
            .to_degrees();
        let vmax = lin.iter().cloned().fold(0.0, f64::max) * 30.0;
        println!(
            "{deg_per_frame} deg/frame at {depth} m: peak {peak:.3} mean {mean:.3} \
             min {min:.3} deg/frame, peak {vmax:.2} m/s"
        );
        assert!(
            (peak - deg_per_frame).abs() < 0.02 * deg_per_frame,
            "peak {peak} deg/frame, asked {deg_per_frame}"
        );
        assert!(
            mean > 0.7 * deg_per_frame && min > 0.4 * deg_per_frame,
            "mean {mean}, min {min} deg/frame for {deg_per_frame}"
        );
        // Hand-held: the walk and the sway, well under a metre a second.
        assert!(vmax > 0.05 && vmax < 0.8, "peak speed {vmax} m/s");
    }
}

#[test]
fn mean_viewing_depth_is_the_requested_one_at_both_sizes() {
    for depth in [1.5, 2.0, 3.0, 4.0] {
        for (name, camera) in [
            ("320x180", SynthCamera::phone_320x180()),
            ("640x480", SynthCamera::tum_640x480()),
        ] {
            let mut seq = SynthSequence::orbit_320x180(150, 3, depth, 45f64.to_radians());
            seq.camera = camera;
            let every = if camera.width > 320 { 30 } else { 10 };
            let mean = mean_viewing_depth(&seq, every);
            println!("{name} {depth} m: mean depth {mean:.3} m");
            assert!(
                (mean - depth).abs() < 0.04 * depth,
                "{name}: mean depth {mean} m, asked {depth} m"
            );
        }
    }
}

#[test]
fn the_camera_keeps_clear_of_the_hall() {
    for depth in [1.0, 2.5, 4.5] {
        let seq = SynthSequence::orbit_320x180(300, 11, depth, 60f64.to_radians());
        for i in 0..seq.frames {
            let p = seq.pose(i).translation.vector;
            let r = p.xy().norm();
            assert!((r - ORBIT_RADIUS_M).abs() < 0.1, "radius {r} at frame {i}");
            let clearance = seq.scene.clearance(&p.into());
            assert!(
                clearance > 0.5,
                "clearance {clearance} m at frame {i}, depth {depth}"
            );
        }
        assert!(hall_apothem(depth) > depth + ORBIT_RADIUS_M);
    }
}

#[test]
fn the_orbit_is_deterministic_in_its_seed() {
    let w = 45f64.to_radians();
    let a = SynthSequence::orbit_320x180(40, 9, 3.0, w);
    let b = SynthSequence::orbit_320x180(40, 9, 3.0, w);
    let c = SynthSequence::orbit_320x180(40, 10, 3.0, w);
    for i in [0, 13, 39] {
        assert_eq!(a.pose(i), b.pose(i));
        assert_eq!(a.frame(i), b.frame(i));
        let d = (a.pose(i).translation.vector - c.pose(i).translation.vector).norm();
        assert!(d > 1e-3, "seeds 9 and 10 give the same pose at {i}");
    }
}
