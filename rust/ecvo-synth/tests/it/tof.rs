//! The time-of-flight noise preset (`DepthNoise::tof_like`) and the noise-free one
//! (`DepthNoise::none`), measured on renders: the ToF depth error has the stated spread
//! σ(z) = 1 mm + 0.3 % z at every depth, flying pixels sit only beside depth jumps and
//! holes follow the weak-signal rule; `none` is exact to the depth unit.

use ecvo_synth::{
    DepthNoise, EdgeDropout, Rendered, SynthCamera, SynthSequence, apply_noise, edge_mask,
    to_raw_depth,
};

/// Renders of the far orbit (1.5 m and 3.5 m walls) and of the slow walk (0.8–3 m).
fn renders() -> Vec<(SynthCamera, Rendered)> {
    let mut out = Vec::new();
    for seq in [
        SynthSequence::orbit_320x180(60, 2, 1.5, 45f64.to_radians()),
        SynthSequence::orbit_320x180(60, 2, 3.5, 45f64.to_radians()),
        SynthSequence::phone_320x180(60, 2),
    ] {
        for i in [0, 30, 59] {
            out.push((seq.camera, seq.render_clean(i)));
        }
    }
    out
}

/// Pixels of a render beside a clean depth jump of more than 5 % (3x3 window).
fn jumps(r: &Rendered) -> Vec<bool> {
    let edge = EdgeDropout {
        relative_jump: 0.05,
        radius_px: 1,
    };
    edge_mask(&r.depth_m, r.width, r.height, &edge)
}

#[test]
fn tof_depth_error_has_the_stated_spread_at_every_depth() {
    let noise = DepthNoise::tof_like();
    assert_eq!(noise.sigma_at(1.0), 0.004);
    // Per 0.5 m depth bin: sum of squared errors, of the expected variances, count.
    let mut bins = [(0.0f64, 0.0f64, 0usize); 10];
    for (k, (cam, r)) in renders().iter().enumerate() {
        assert_eq!(cam.depth_scale, 1000.0);
        let (_, raw) = apply_noise(r, cam, &noise, 100 + k as u64);
        let near_jump = jumps(r);
        for i in 0..raw.len() {
            let z = r.depth_m[i] as f64;
            if raw[i] == 0 || near_jump[i] {
                continue;
            }
            let err = raw[i] as f64 / cam.depth_scale - z;
            let bin = &mut bins[((z / 0.5) as usize).min(9)];
            // The error's variance: the Gaussian's plus rounding to 1 mm (1/12 mm²).
            let sigma = noise.sigma_at(z);
            bin.0 += err * err;
            bin.1 += sigma * sigma + 1e-6 / 12.0;
            bin.2 += 1;
        }
    }
    let mut checked = 0;
    for (b, &(sq, expected, n)) in bins.iter().enumerate() {
        if n < 5000 {
            continue;
        }
        let (got, want) = ((sq / n as f64).sqrt(), (expected / n as f64).sqrt());
        println!(
            "{:.1}–{:.1} m: n {n}, rms error {:.2} mm, stated {:.2} mm",
            b as f64 * 0.5,
            b as f64 * 0.5 + 0.5,
            got * 1e3,
            want * 1e3
        );
        assert!(
            (got / want - 1.0).abs() < 0.03,
            "bin {b}: rms {got} m, stated {want} m"
        );
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} depth bins with enough pixels");
}

#[test]
fn tof_flying_pixels_are_mixed_depths_beside_jumps_only() {
    let noise = DepthNoise::tof_like();
    let (mut far_off, mut candidates, mut elsewhere) = (0usize, 0usize, 0usize);
    for (k, (cam, r)) in renders().iter().enumerate() {
        let (_, raw) = apply_noise(r, cam, &noise, 7 + k as u64);
        let near_jump = jumps(r);
        for i in 0..raw.len() {
            if raw[i] == 0 {
                continue;
            }
            let z = r.depth_m[i] as f64;
            let off = (raw[i] as f64 / cam.depth_scale - z).abs() > 6.0 * noise.sigma_at(z) + 1e-3;
            if near_jump[i] {
                candidates += 1;
                far_off += off as usize;
            } else {
                elsewhere += off as usize;
            }
        }
    }
    let share = far_off as f64 / candidates as f64;
    println!("{candidates} pixels beside jumps, {share:.3} of them far off, {elsewhere} elsewhere");
    assert!(candidates > 2000, "{candidates} pixels beside jumps");
    // A quarter are mixed; most mixed depths land far from both sides.
    assert!(
        (0.1..0.27).contains(&share),
        "share of flying pixels {share}"
    );
    assert_eq!(elsewhere, 0, "errors beyond 6 σ away from depth jumps");
}

#[test]
fn tof_holes_follow_the_weak_signal_rule() {
    let noise = DepthNoise {
        random_dropout: 0.0,
        grazing_max_angle_deg: 90.0,
        ..DepthNoise::tof_like()
    };
    let min = noise.low_signal.unwrap().min_signal;
    let seq = SynthSequence::orbit_320x180(60, 4, 4.5, 45f64.to_radians());
    let (mut weak, mut ramp_missing, mut ramp) = (0usize, 0usize, 0usize);
    for i in [0, 20, 40] {
        let r = seq.render_clean(i);
        let (_, raw) = apply_noise(&r, &seq.camera, &noise, i as u64);
        for k in 0..raw.len() {
            let z = r.depth_m[k] as f64;
            if z <= 0.0 || z > noise.max_depth_m {
                continue;
            }
            let signal = r.intensity_f32[k] as f64 / 255.0 / (z * z);
            if signal < min {
                weak += 1;
                assert_eq!(raw[k], 0, "weak return kept at pixel {k}");
            } else if signal < 2.0 * min {
                ramp += 1;
                ramp_missing += (raw[k] == 0) as usize;
            } else {
                assert_ne!(raw[k], 0, "strong return lost at pixel {k}");
            }
        }
    }
    println!("{weak} weak, {ramp} in the ramp ({ramp_missing} missing)");
    assert!(ramp > 1000, "{ramp} pixels in the ramp");
    let share = ramp_missing as f64 / ramp as f64;
    assert!((0.15..0.85).contains(&share), "ramp missing share {share}");
}

#[test]
fn none_is_exact_to_the_depth_unit_and_leaves_intensity_clean() {
    let noise = DepthNoise::none();
    for (k, (cam, r)) in renders().iter().enumerate() {
        let mut cam = *cam;
        for scale in [1000.0, 5000.0] {
            cam.depth_scale = scale;
            let (intensity, raw) = apply_noise(r, &cam, &noise, k as u64);
            assert_eq!(intensity, r.intensity, "render {k}: intensity changed");
            assert_eq!(
                raw,
                to_raw_depth(r, &cam),
                "render {k}: depth not the rounded one"
            );
            let mut worst = 0.0f64;
            for (&d, &z) in raw.iter().zip(&r.depth_m) {
                assert_eq!(d == 0, z <= 0.0, "render {k}: a hole in noise-free depth");
                worst = worst.max((d as f64 / scale - z as f64).abs());
            }
            assert!(
                worst <= 0.5 / scale + 1e-9,
                "render {k}: error {worst} m at scale {scale}"
            );
            // The rounding is all there is: exact depth comes back to the unit.
            assert!(
                worst > 0.3 / scale,
                "render {k}: implausibly small rounding {worst}"
            );
        }
    }
}
