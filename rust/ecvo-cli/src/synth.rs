//! `ecvo synth`: render a synthetic stream (phone-like 320x180, or the 640x480 Kinect)
//! with exact ground truth and write it in the app's recording format.

use std::path::Path;

use anyhow::{Context, Result, bail};
use ecvo_core::Camera;
use ecvo_io::{SequenceWriter, Trajectory};
use ecvo_synth::{
    DepthNoise, FAST_MAX_ANGULAR_SPEED, FAST_MAX_LINEAR_SPEED, ORBIT_DEPTH_RANGE_M, SynthCamera,
    SynthSequence,
};

/// The sensor noise model of `ecvo synth --noise`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Noise {
    /// Exact depth (rounded to the depth unit), clean intensity.
    None,
    /// Phone depth sensor: σ = 4 mm·z², holes at edges and at random.
    Phone,
    /// Kinect v1: σ = 1.4 mm·z², disparity quantisation, shadows, holes.
    Kinect,
    /// A phone's time-of-flight sensor: σ = 1 mm + 0.3 % of z, millimetre depth, no
    /// quantisation, flying pixels at depth jumps, holes on dark and far surfaces.
    Tof,
}

impl Noise {
    fn model(self) -> DepthNoise {
        match self {
            Noise::None => DepthNoise::none(),
            Noise::Phone => DepthNoise::phone_like(),
            Noise::Kinect => DepthNoise::kinect_like(),
            Noise::Tof => DepthNoise::tof_like(),
        }
    }
}

/// The camera motion of `ecvo synth --motion`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Motion {
    /// The slow hand-held walk around the room (`CameraPath::handheld`).
    Slow,
    /// Fast hand-held motion in front of a wall (`CameraPath::fast_handheld`).
    Fast,
    /// A far-depth hand-held orbit panning round a hall's walls
    /// (`CameraPath::far_orbit` in `Scene::hall`).
    Orbit,
    /// A fast in-place pan round a hall's walls, the pan rate swinging between 0 and
    /// --max-rot-speed (`CameraPath::in_place_pan`).
    Pan,
}

/// The image size and camera of `ecvo synth --size`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Size {
    /// The phone-like 320x180 camera (fx = fy = 250, depth in millimetres).
    #[value(name = "320x180")]
    Phone320x180,
    /// The TUM Kinect's 640x480 camera (fx = fy = 525, depth in 1/5000 m).
    #[value(name = "640x480")]
    Kinect640x480,
}

/// The motion flags of `ecvo synth`.
#[derive(Clone, Copy, Debug)]
pub struct MotionArgs {
    /// Slow or fast.
    pub motion: Motion,
    /// Fast and orbit: distance to the walls looked at, metres (default 2 for fast,
    /// 2.5 for orbit).
    pub depth: Option<f64>,
    /// Fast and orbit: peak rotation rate, degrees per second (default 90 for fast,
    /// 45 for orbit).
    pub max_rot_speed_deg: Option<f64>,
    /// Fast only: peak speed, metres per second (default 1).
    pub max_speed: Option<f64>,
    /// Texture contrast of every surface, (0, 1]: 1 the standard room, towards 0
    /// blank walls.
    pub texture_contrast: f64,
    /// The camera.
    pub size: Size,
}

impl MotionArgs {
    /// The sequence (noise still the preset's), or an error naming the flag that is out
    /// of range or given with a motion that has no use for it.
    fn sequence(&self, frames: usize, seed: u64) -> Result<SynthSequence> {
        let c = self.texture_contrast;
        if !(c > 0.0 && c <= 1.0) {
            bail!("--texture-contrast must be in (0, 1], got {c}");
        }
        let mut seq = self.motion_sequence(frames, seed)?;
        if c < 1.0 {
            seq.scene.scale_contrast(c);
        }
        if self.size == Size::Kinect640x480 {
            seq.camera = SynthCamera::tum_640x480();
        }
        Ok(seq)
    }

    fn motion_sequence(&self, frames: usize, seed: u64) -> Result<SynthSequence> {
        match self.motion {
            Motion::Slow => {
                for (flag, given) in [
                    ("--depth", self.depth.is_some()),
                    ("--max-rot-speed", self.max_rot_speed_deg.is_some()),
                    ("--max-speed", self.max_speed.is_some()),
                ] {
                    if given {
                        bail!("{flag} needs --motion fast, orbit or pan");
                    }
                }
                Ok(SynthSequence::phone_320x180(frames, seed))
            }
            Motion::Fast => {
                let depth = self.depth.unwrap_or(2.0);
                if !(0.4..=4.5).contains(&depth) {
                    bail!("--depth must be between 0.4 and 4.5 m, got {depth}");
                }
                let w = self
                    .max_rot_speed_deg
                    .map_or(FAST_MAX_ANGULAR_SPEED, f64::to_radians);
                if !(w > 0.0 && w <= 720f64.to_radians()) {
                    bail!(
                        "--max-rot-speed must be in (0, 720] deg/s, got {}",
                        w.to_degrees()
                    );
                }
                let v = self.max_speed.unwrap_or(FAST_MAX_LINEAR_SPEED);
                if !(v > 0.0 && v <= 5.0) {
                    bail!("--max-speed must be in (0, 5] m/s, got {v}");
                }
                Ok(SynthSequence::fast_handheld_320x180(
                    frames, seed, depth, w, v,
                ))
            }
            Motion::Pan => {
                if self.max_speed.is_some() {
                    bail!("--max-speed needs --motion fast");
                }
                let depth = self.depth.unwrap_or(2.5);
                let (lo, hi) = ORBIT_DEPTH_RANGE_M;
                if !(lo..=hi).contains(&depth) {
                    bail!("--depth must be between {lo} and {hi} m with --motion pan, got {depth}");
                }
                let w = self.max_rot_speed_deg.unwrap_or(120.0);
                if !(w > 0.0 && w <= 360.0) {
                    bail!("--max-rot-speed must be in (0, 360] deg/s with --motion pan, got {w}");
                }
                Ok(SynthSequence::pan_320x180(
                    frames,
                    seed,
                    depth,
                    w.to_radians(),
                ))
            }
            Motion::Orbit => {
                if self.max_speed.is_some() {
                    bail!("--max-speed needs --motion fast");
                }
                let depth = self.depth.unwrap_or(2.5);
                let (lo, hi) = ORBIT_DEPTH_RANGE_M;
                if !(lo..=hi).contains(&depth) {
                    bail!(
                        "--depth must be between {lo} and {hi} m with --motion orbit, got {depth}"
                    );
                }
                let w = self.max_rot_speed_deg.unwrap_or(45.0);
                if !(w > 0.0 && w <= 180.0) {
                    bail!("--max-rot-speed must be in (0, 180] deg/s with --motion orbit, got {w}");
                }
                Ok(SynthSequence::orbit_320x180(
                    frames,
                    seed,
                    depth,
                    w.to_radians(),
                ))
            }
        }
    }
}

/// Renders `frames` frames of [`SynthSequence::phone_320x180`] with `seed` (or of
/// [`SynthSequence::fast_handheld_320x180`] with `--motion fast`, of
/// [`SynthSequence::orbit_320x180`] with `--motion orbit`) and writes them to `out` (TUM
/// layout, `camera.json`, `groundtruth.txt`). Frame `i` is stamped
/// `start_time + i / 30` seconds (as written, to the microsecond); the ground truth
/// holds exactly the rendered poses at those stamps. With `depth_delay` (seconds),
/// each depth image is rendered that much later and stamped so.
#[allow(clippy::too_many_arguments)]
pub fn synth_command(
    out: &Path,
    frames: usize,
    seed: u64,
    noise: Noise,
    start_time: f64,
    motion: &MotionArgs,
    with_imu: bool,
    depth_delay: f64,
) -> Result<()> {
    if frames < 2 {
        bail!("--frames must be at least 2, got {frames}");
    }
    if !(depth_delay.abs() < ecvo_io::sequence::MAX_RGB_DEPTH_DT) {
        bail!(
            "--depth-delay-ms must be within ±{} ms (the readers pair images at most that far \
             apart), got {}",
            ecvo_io::sequence::MAX_RGB_DEPTH_DT * 1e3,
            depth_delay * 1e3
        );
    }
    if !(start_time.is_finite() && start_time >= 0.0) {
        bail!("--start-time must be finite and not negative, got {start_time}");
    }
    let mut seq = motion.sequence(frames, seed)?;
    seq.noise = noise.model();
    if noise == Noise::Tof {
        // A phone's DEPTH16: millimetres whatever the image size.
        seq.camera.depth_scale = 1000.0;
    }
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
    let mut writer = SequenceWriter::create(out, &camera)?;
    let mut gt = Trajectory::with_capacity(frames);
    for i in 0..frames {
        let f = seq.frame_with_depth_delay(i, depth_delay);
        // The writer stores stamps to the microsecond; the ground truth uses the
        // stamp as written so that frames and poses associate exactly.
        let stamp: f64 = format!("{:.6}", start_time + f.timestamp)
            .parse()
            .context("formatting a timestamp")?;
        writer.write_frame_stamped(stamp, stamp + depth_delay, &f.intensity, &f.depth)?;
        gt.push(stamp, f.pose);
    }
    writer.write_groundtruth(&gt)?;
    let n = writer.finish()?;
    let imu = if with_imu {
        // The IMU over the frames' span and 0.1 s either side, on the written clock.
        let model = ecvo_synth::imu::ImuModel::phone(seed);
        let last = seq.timestamp(frames - 1);
        let readings = model.simulate(|t| seq.path.pose_at(t), -0.1, last + 0.1);
        crate::imu::write_readings(
            &out.join(ecvo_io::imu::IMU_FILE),
            &readings,
            start_time,
            &model,
            &format!("ecvo synth, seed {seed}"),
        )?;
        ecvo_io::imu::save_imu_calibration(
            out.join(ecvo_io::camera::CAMERA_FILE),
            &crate::imu::calibration_of(&model),
        )?;
        format!(", simulated IMU at {} Hz", model.rate_hz)
    } else {
        String::new()
    };
    outln!(
        "wrote {n} frames ({}x{}, depth in 1/{} m, noise {noise:?}, motion {:?}, seed {seed}{imu}) to {}",
        camera.width,
        camera.height,
        camera.depth_scale,
        motion.motion,
        out.display()
    );
    Ok(())
}
