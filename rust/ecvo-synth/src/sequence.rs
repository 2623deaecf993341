//! Synthetic RGB-D sequences: scene + camera + path + noise, frame by frame.

use nalgebra::Isometry3;

use crate::camera::SynthCamera;
use crate::noise::{DepthNoise, apply_noise};
use crate::path::CameraPath;
use crate::render::{Rendered, render};
use crate::rng::mix64;
use crate::scene::Scene;

/// A synthetic sequence. Frame `i` is taken at time `i / fps` seconds; its noise is
/// drawn from a seed derived from `(seed, i)`, so frames can be generated in any order.
#[derive(Clone, Debug)]
pub struct SynthSequence {
    /// Camera intrinsics and depth scale.
    pub camera: SynthCamera,
    /// Scene to render.
    pub scene: Scene,
    /// Camera trajectory (camera-to-world).
    pub path: CameraPath,
    /// Sensor noise model.
    pub noise: DepthNoise,
    /// Frame rate, frames per second.
    pub fps: f64,
    /// Number of frames.
    pub frames: usize,
    /// Seed for the per-frame sensor noise.
    pub seed: u64,
}

/// One sensor frame with its exact ground-truth pose.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthFrame {
    /// Frame index.
    pub index: usize,
    /// Time stamp, seconds (`index / fps`).
    pub timestamp: f64,
    /// Ground-truth camera-to-world pose.
    pub pose: Isometry3<f64>,
    /// 8-bit intensity, row-major.
    pub intensity: Vec<u8>,
    /// Raw depth in `camera.depth_scale` units per metre, 0 = missing, row-major.
    pub depth: Vec<u16>,
}

impl SynthSequence {
    /// Phone-like preset: 320x180 camera with fx = fy = 250 (≈ 65° horizontal field of
    /// view), principal point at the centre, depth in millimetres, phone-like noise, 30
    /// fps, the standard room and a hand-held path (both from `seed`).
    pub fn phone_320x180(frames: usize, seed: u64) -> Self {
        Self {
            camera: SynthCamera::phone_320x180(),
            scene: Scene::room(seed),
            path: CameraPath::handheld(seed),
            noise: DepthNoise::phone_like(),
            fps: 30.0,
            frames,
            seed,
        }
    }

    /// Time stamp of frame `i`, seconds.
    pub fn timestamp(&self, i: usize) -> f64 {
        i as f64 / self.fps
    }

    /// Ground-truth camera-to-world pose of frame `i`.
    pub fn pose(&self, i: usize) -> Isometry3<f64> {
        self.path.pose_at(self.timestamp(i))
    }

    /// Noise-free rendering of frame `i` (exact depth, intensity, viewing angle).
    pub fn render_clean(&self, i: usize) -> Rendered {
        render(&self.scene, &self.camera, &self.pose(i))
    }

    /// Seed used for the sensor noise of frame `i`.
    pub fn frame_seed(&self, i: usize) -> u64 {
        mix64(self.seed ^ mix64(i as u64 ^ 0xF0A3_0000_0000_0000))
    }

    /// Frame `i` with sensor noise applied (valid for any `i`, not only `< frames`).
    pub fn frame(&self, i: usize) -> SynthFrame {
        let rendered = self.render_clean(i);
        let (intensity, depth) =
            apply_noise(&rendered, &self.camera, &self.noise, self.frame_seed(i));
        SynthFrame {
            index: i,
            timestamp: self.timestamp(i),
            pose: self.pose(i),
            intensity,
            depth,
        }
    }

    /// Frame `i` with its depth taken `delay` seconds after its intensity (before it if
    /// negative), as by an RGB-D camera whose two streams are not triggered together:
    /// the depth is rendered from the path's pose at `timestamp(i) + delay`, with frame
    /// `i`'s noise; the intensity, the pose and the timestamp are frame `i`'s.
    pub fn frame_with_depth_delay(&self, i: usize, delay: f64) -> SynthFrame {
        let mut f = self.frame(i);
        if delay != 0.0 {
            let pose = self.path.pose_at(self.timestamp(i) + delay);
            let rendered = render(&self.scene, &self.camera, &pose);
            (_, f.depth) = apply_noise(&rendered, &self.camera, &self.noise, self.frame_seed(i));
        }
        f
    }

    /// Iterator over all `frames` frames.
    pub fn iter(&self) -> impl Iterator<Item = SynthFrame> + '_ {
        (0..self.frames).map(|i| self.frame(i))
    }
}

/// Peak rotation rate of [`SynthSequence::fast_320x180`], rad/s (90°/s).
pub const FAST_MAX_ANGULAR_SPEED: f64 = std::f64::consts::FRAC_PI_2;

/// Peak linear speed of [`SynthSequence::fast_320x180`], m/s.
pub const FAST_MAX_LINEAR_SPEED: f64 = 1.0;

/// Surface id of the wall `x = 3` of [`Scene::room`], which the fast path looks at.
pub const FAST_WALL_SURFACE: u32 = 3;

impl SynthSequence {
    /// [`Self::phone_320x180`] with fast hand-held motion instead of the slow walk:
    /// [`CameraPath::fast_handheld`] at `depth` metres from the wall `x = 3`, with
    /// peaks of 90°/s and 1 m/s at 30 fps.
    pub fn fast_320x180(frames: usize, seed: u64, depth: f64) -> Self {
        Self::fast_handheld_320x180(
            frames,
            seed,
            depth,
            FAST_MAX_ANGULAR_SPEED,
            FAST_MAX_LINEAR_SPEED,
        )
    }

    /// [`Self::fast_320x180`] with the given peak rotation rate (rad/s) and speed (m/s).
    ///
    /// The texture of the wall looked at is stretched by `depth / 2` (clamped to
    /// 0.3–2), so that it shows about the detail in pixels at every depth that the
    /// standard room shows from 2 m: near views are not blank, far ones do not alias.
    pub fn fast_handheld_320x180(
        frames: usize,
        seed: u64,
        depth: f64,
        max_angular_speed: f64,
        max_linear_speed: f64,
    ) -> Self {
        let mut scene = Scene::room(seed);
        scene.scale_texture(FAST_WALL_SURFACE, (depth / 2.0).clamp(0.3, 2.0));
        Self {
            scene,
            path: CameraPath::fast_handheld(seed, depth, max_angular_speed, max_linear_speed),
            ..Self::phone_320x180(frames, seed)
        }
    }
}
