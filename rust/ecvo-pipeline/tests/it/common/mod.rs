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
