//! `Preparer::prepare_into` and MOTION on arbitrary frames: any size from 8x8 to 96x72,
//! any intrinsics the camera validation accepts, any schedule (the paper's sampling, or
//! the pyramids cut to the levels the size allows), weighting and depth-noise model,
//! hostile (NaN-free: the inputs are integers) depth and intensity, and an arbitrary
//! initial motion; then the tracker on a few such frames. Poses must stay finite;
//! MOTION fails cleanly or succeeds.
//!
//! The schedule is chosen to fit: the default pyramid goes 3 levels down and needs
//! 64x64 frames, so with the default alone almost every input stopped at the
//! configuration check (found on the 600 s run of this stop: coverage never grew).
#![no_main]

use ecvo_core::nalgebra::{Translation3, UnitQuaternion, Vector3};
use ecvo_core::{
    Camera, Config, DepthNoiseModel, FrameView, Mode, MotionEstimator, Odometry, Pose,
    PreparedFrame, Preparer, Preset, Schedule, Weighting,
};
use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;

struct Frames {
    config: Config,
    frames: Vec<(Vec<u8>, Vec<u16>)>,
    t_init: Pose,
}

fn finite(u: &mut Unstructured<'_>, lo: f64, hi: f64) -> Result<f64> {
    let x: u32 = u.arbitrary()?;
    Ok(lo + (hi - lo) * (f64::from(x) / f64::from(u32::MAX)))
}

fn frames(u: &mut Unstructured<'_>) -> Result<Frames> {
    let width = u.int_in_range(8..=96)?;
    let height = u.int_in_range(8..=72)?;
    let camera = Camera {
        width,
        height,
        fx: finite(u, -200.0, 200.0)?,
        fy: finite(u, -200.0, 200.0)?,
        cx: finite(u, -100.0, 100.0)?,
        cy: finite(u, -100.0, 100.0)?,
        depth_scale: finite(u, 1e-3, 1e5)?,
    };
    let preset = if u.arbitrary()? {
        Preset::Pc
    } else {
        Preset::Phone
    };
    let mode = match u.int_in_range(0..=2)? {
        0 => Mode::Naive,
        1 => Mode::L1,
        _ => Mode::L2,
    };
    let mut config = Config::new(camera, preset, mode);
    config.motion.min_valid_pixels = u.int_in_range(1..=200)?;
    let schedule = match u.int_in_range(0..=2)? {
        0 => Schedule::PaperSampling,
        1 => Schedule::Pyramid,
        _ => Schedule::PyramidStride2,
    };
    // The deepest pyramid level whose image is still 8x8 or larger.
    let (mut w, mut h, mut deepest) = (width, height, 0);
    while deepest < 3 && w / 2 >= 8 && h / 2 >= 8 {
        (w, h, deepest) = (w / 2, h / 2, deepest + 1);
    }
    let mut levels = schedule.levels();
    levels.retain(|l| l.pyramid_level <= deepest);
    config.motion.levels = levels;
    let weighting = |k| {
        if k {
            Weighting::Bivariate
        } else {
            Weighting::Scalar
        }
    };
    config.motion.weighting = weighting(u.arbitrary()?);
    config.motion.fine_weighting = if u.arbitrary()? {
        Some(weighting(u.arbitrary()?))
    } else {
        None
    };
    config.motion.depth_noise = if u.arbitrary()? {
        DepthNoiseModel::Quadratic
    } else {
        DepthNoiseModel::Constant
    };
    let n = width * height;
    let count = u.int_in_range(1..=4)?;
    let mut frames = Vec::new();
    for _ in 0..count {
        // A constant, a ramp, or raw bytes: the bytes run out quickly at 64x48.
        let mut intensity = vec![0u8; n];
        let mut depth = vec![0u16; n];
        let base: u16 = u.arbitrary()?;
        let step: u16 = u.arbitrary()?;
        for i in 0..n {
            intensity[i] = u.arbitrary().unwrap_or((i * 7) as u8);
            depth[i] = u
                .arbitrary()
                .unwrap_or_else(|_| base.wrapping_add(step.wrapping_mul(i as u16)));
        }
        frames.push((intensity, depth));
    }
    let t_init = Pose::from_parts(
        Translation3::new(
            finite(u, -5.0, 5.0)?,
            finite(u, -5.0, 5.0)?,
            finite(u, -5.0, 5.0)?,
        ),
        UnitQuaternion::from_scaled_axis(Vector3::new(
            finite(u, -4.0, 4.0)?,
            finite(u, -4.0, 4.0)?,
            finite(u, -4.0, 4.0)?,
        )),
    );
    Ok(Frames {
        config,
        frames,
        t_init,
    })
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let Ok(f) = frames(&mut u) else {
        return;
    };
    if f.config.validate().is_err() {
        return;
    }
    let mut prep = Preparer::new(&f.config);
    let mut prepared = Vec::new();
    for (k, (i, d)) in f.frames.iter().enumerate() {
        let mut out = PreparedFrame::for_config(&f.config);
        let view = FrameView {
            timestamp: k as f64,
            intensity: i,
            depth: d,
        };
        prep.prepare_into(view, &mut out).expect("sizes match");
        prepared.push(out);
    }
    let mut est = MotionEstimator::new();
    let a = &prepared[0];
    let b = prepared.last().expect("one frame at least");
    for init in [Pose::identity(), f.t_init] {
        let r = est.motion(a, b, &init, &f.config.motion);
        if r.is_ok() {
            assert!(ecvo_core::se3::is_finite(&r.pose), "{r:?}");
        }
    }
    let mut odo = Odometry::new(f.config.clone()).expect("validated");
    for (k, (i, d)) in f.frames.iter().enumerate() {
        let out = odo
            .push(FrameView {
                timestamp: k as f64,
                intensity: i,
                depth: d,
            })
            .expect("sizes match");
        assert!(ecvo_core::se3::is_finite(&out.pose), "{out:?}");
    }
});
