//! Synthetic frames for the engine's tests, rendered by ecvo-synth.
#![allow(dead_code)]

use ecvo_core::{
    Camera, Config, FrameOutput, FrameView, Mode, Odometry, Pose, PreparedFrame, Preparer, Preset,
};
use ecvo_synth::{DepthNoise, SynthCamera, SynthFrame, SynthSequence};

/// A 320x180 phone-like sequence with a fine depth unit (0.2 mm) and the given noise.
pub fn sequence(noise: DepthNoise, seed: u64) -> SynthSequence {
    let mut s = SynthSequence::phone_320x180(200, seed);
    s.camera.depth_scale = 5000.0;
    s.noise = noise;
    s
}

pub fn camera_of(c: &SynthCamera) -> Camera {
    Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    }
}

pub fn config(seq: &SynthSequence, mode: Mode) -> Config {
    Config::new(camera_of(&seq.camera), Preset::Pc, mode)
}

/// Frame `i` prepared whole with `cfg` (both sides, as a reference is), and its
/// ground-truth pose.
pub fn prepared(seq: &SynthSequence, i: usize, cfg: &Config) -> (PreparedFrame, Pose) {
    let f = seq.frame(i);
    prepare_raw(cfg, f.timestamp, &f.intensity, &f.depth, f.pose)
}

pub fn prepare_raw(
    cfg: &Config,
    t: f64,
    intensity: &[u8],
    depth: &[u16],
    pose: Pose,
) -> (PreparedFrame, Pose) {
    // Whole: these frames are registered against (with keyframe tracking a
    // `Preparer::new` frame would be prepared for lookup only).
    let mut p = Preparer::whole(cfg);
    let mut out = PreparedFrame::default();
    p.prepare_into(
        FrameView {
            timestamp: t,
            intensity,
            depth,
        },
        &mut out,
    )
    .unwrap();
    (out, pose)
}

/// Translation error (m) and rotation error (deg) between two motions.
pub fn pose_error(a: &Pose, b: &Pose) -> (f64, f64) {
    let d = a.inverse() * b;
    (
        d.translation.vector.norm(),
        ecvo_core::se3::angle(&d).to_degrees(),
    )
}

/// The first `n` frames of `seq`, rendered once for a test that tracks them several
/// times (rendering costs more than tracking: most of these tests' time).
pub fn frames(seq: &SynthSequence, n: usize) -> Vec<SynthFrame> {
    (0..n).map(|i| seq.frame(i)).collect()
}

/// Pushes `f` into `odo`, unwrapping the result.
pub fn push(odo: &mut Odometry, f: &SynthFrame) -> FrameOutput {
    odo.push(FrameView {
        timestamp: f.timestamp,
        intensity: &f.intensity,
        depth: &f.depth,
    })
    .unwrap()
}

/// Tracks `frames` (from [`frames`]) with `config`, one `Odometry::push` each: what
/// [`run`] does, without rendering them again.
pub fn run_frames(config: Config, frames: &[SynthFrame]) -> (Odometry, Vec<FrameOutput>) {
    let mut odo = Odometry::new(config).unwrap();
    let outs = frames.iter().map(|f| push(&mut odo, f)).collect();
    (odo, outs)
}

/// Tracks the first `frames` frames of `seq` with `config`, one `Odometry::push` each.
pub fn run(seq: &SynthSequence, config: Config, frames: usize) -> (Odometry, Vec<FrameOutput>) {
    let mut odo = Odometry::new(config).unwrap();
    let outs = (0..frames).map(|i| push(&mut odo, &seq.frame(i))).collect();
    (odo, outs)
}

/// RMSE (m) of the translations relative to the first frame against the ground truth
/// (both trajectories start at the first camera, so no alignment is needed).
pub fn drift_rmse(seq: &SynthSequence, outs: &[FrameOutput]) -> f64 {
    let p0 = seq.pose(0);
    let se: f64 = outs
        .iter()
        .map(|o| {
            ((p0.inverse() * seq.pose(o.index as usize))
                .translation
                .vector
                - o.pose.translation.vector)
                .norm_squared()
        })
        .sum();
    (se / outs.len() as f64).sqrt()
}
