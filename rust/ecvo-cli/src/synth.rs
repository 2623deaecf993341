//! `ecvo synth`: render a synthetic phone-like stream with exact ground truth and
//! write it in the app's recording format.

use std::path::Path;

use anyhow::{Context, Result, bail};
use ecvo_core::Camera;
use ecvo_io::{SequenceWriter, Trajectory};
use ecvo_synth::{DepthNoise, SynthSequence};

/// The sensor noise model of `ecvo synth --noise`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Noise {
    /// Exact depth (rounded to the depth unit), clean intensity.
    None,
    /// Phone depth sensor: σ = 4 mm·z², holes at edges and at random.
    Phone,
    /// Kinect v1: σ = 1.4 mm·z², disparity quantisation, shadows, holes.
    Kinect,
}

impl Noise {
    fn model(self) -> DepthNoise {
        match self {
            Noise::None => DepthNoise::none(),
            Noise::Phone => DepthNoise::phone_like(),
            Noise::Kinect => DepthNoise::kinect_like(),
        }
    }
}

/// Renders `frames` frames of [`SynthSequence::phone_320x180`] with `seed` and writes
/// them to `out` (TUM layout, `camera.json`, `groundtruth.txt`). Frame `i` is stamped
/// `start_time + i / 30` seconds (as written, to the microsecond); the ground truth
/// holds exactly the rendered poses at those stamps.
pub fn synth_command(
    out: &Path,
    frames: usize,
    seed: u64,
    noise: Noise,
    start_time: f64,
) -> Result<()> {
    if frames < 2 {
        bail!("--frames must be at least 2, got {frames}");
    }
    if !(start_time.is_finite() && start_time >= 0.0) {
        bail!("--start-time must be finite and not negative, got {start_time}");
    }
    let mut seq = SynthSequence::phone_320x180(frames, seed);
    seq.noise = noise.model();
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
        let f = seq.frame(i);
        // The writer stores stamps to the microsecond; the ground truth uses the
        // stamp as written so that frames and poses associate exactly.
        let stamp: f64 = format!("{:.6}", start_time + f.timestamp)
            .parse()
            .context("formatting a timestamp")?;
        writer.write_frame(stamp, &f.intensity, &f.depth)?;
        gt.push(stamp, f.pose);
    }
    writer.write_groundtruth(&gt)?;
    let n = writer.finish()?;
    println!(
        "wrote {n} frames ({}x{}, depth in 1/{} m, noise {noise:?}, seed {seed}) to {}",
        camera.width,
        camera.height,
        camera.depth_scale,
        out.display()
    );
    Ok(())
}
