//! Shared helpers of the integration tests: a noisy synthetic stream and the
//! configuration for it.

#![allow(dead_code)]

use ecvo_core::{Camera, Config, Mode, Preset};
use ecvo_synth::SynthSequence;

/// One decoded frame.
pub struct Frame {
    pub timestamp: f64,
    pub intensity: Vec<u8>,
    pub depth: Vec<u16>,
}

impl Frame {
    pub fn view(&self) -> ecvo_core::FrameView<'_> {
        ecvo_core::FrameView {
            timestamp: self.timestamp,
            intensity: &self.intensity,
            depth: &self.depth,
        }
    }
}

/// The synthetic phone stream (320x180, phone-like depth noise, hand-held path) and
/// an L2 configuration for it.
pub fn synthetic(frames: usize, seed: u64) -> (Config, Vec<Frame>) {
    frames_of(SynthSequence::phone_320x180(frames, seed))
}

/// The same room and path seen by a 640x480 Kinect-like camera: large enough that
/// ecvo-core splits its loops between threads.
pub fn synthetic_640x480(frames: usize, seed: u64) -> (Config, Vec<Frame>) {
    let mut seq = SynthSequence::phone_320x180(frames, seed);
    seq.camera = ecvo_synth::SynthCamera::tum_640x480();
    seq.noise = ecvo_synth::DepthNoise::kinect_like();
    frames_of(seq)
}

fn frames_of(seq: SynthSequence) -> (Config, Vec<Frame>) {
    let c = seq.camera;
    let camera = Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    };
    let frames = seq
        .iter()
        .map(|f| Frame {
            timestamp: f.timestamp,
            intensity: f.intensity,
            depth: f.depth,
        })
        .collect();
    (Config::new(camera, Preset::Pc, Mode::L2), frames)
}

/// The bit patterns of a pose's homogeneous matrix.
pub fn bits(pose: &ecvo_core::Pose) -> Vec<u64> {
    pose.to_homogeneous().iter().map(|v| v.to_bits()).collect()
}

/// A 10 Hz in-place pan peaking at 200 °/s (320x180) with a simulated phone gyro
/// riding on it: the configuration (its calibration in `Config::imu`), the frames and
/// the gyro's samples.
pub fn pan_with_imu(frames: usize, seed: u64) -> (Config, Vec<Frame>, Vec<ecvo_core::GyroSample>) {
    let mut seq = SynthSequence::pan_320x180(frames, seed, 2.5, 200f64.to_radians());
    seq.fps = 10.0;
    let m = ecvo_synth::imu::ImuModel::phone(seed);
    let end = seq.timestamp(frames.saturating_sub(1)) + 0.1;
    let imu = m
        .simulate(|t| seq.path.pose_at(t), -0.1, end)
        .iter()
        .map(|r| ecvo_core::GyroSample { t: r.t, w: r.w })
        .collect();
    let (mut config, frames) = frames_of(seq);
    config.imu = ecvo_core::ImuCalibration {
        camera_from_imu: m.camera_from_imu,
        time_offset: m.time_offset,
        gyro_noise_density: Some(m.gyro_noise_density),
        gyro_bias_random_walk: Some(m.gyro_bias_random_walk),
    };
    (config, frames, imu)
}

/// The samples of `imu` to push before a frame stamped `t` (those up to 5 ms after
/// it on the frames' clock, from `*next` on), advancing `*next`.
pub fn imu_before<'a>(
    imu: &'a [ecvo_core::GyroSample],
    next: &mut usize,
    t: f64,
    offset: f64,
) -> &'a [ecvo_core::GyroSample] {
    let start = *next;
    while *next < imu.len() && imu[*next].t + offset <= t + 0.005 {
        *next += 1;
    }
    &imu[start..*next]
}
