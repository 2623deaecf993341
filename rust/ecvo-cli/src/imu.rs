//! The IMU in the command line (issue 47, `docs/imu.md`): which `imu.txt` `ecvo run`
//! and `ecvo table` use and with which calibration, how its samples are fed beside
//! the frames, what `ecvo synth` writes, and `ecvo imu-from-groundtruth`, which makes
//! a simulated `imu.txt` for a real sequence from its ground truth.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use ecvo_core::{GyroSample, ImuCalibration};
use ecvo_io::Trajectory;
use ecvo_io::camera::CAMERA_FILE as CAMERA_FILE_NAME;
use ecvo_io::files::shown_path;
use ecvo_io::imu::{IMU_FILE, ImuSample, load_imu, save_imu};
use ecvo_synth::imu::{ImuModel, ImuReading, SplinePath};

/// Which IMU stream a run uses.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum ImuSource {
    /// The sequence's `imu.txt` if it has one.
    #[default]
    Auto,
    /// None, even if the sequence has one (`--no-imu`).
    Off,
    /// This file (`--imu`).
    File(PathBuf),
}

/// An IMU stream read for a run.
#[derive(Clone, Debug)]
pub struct ImuStream {
    /// The gyro samples, in time order.
    pub samples: Arc<[GyroSample]>,
    /// Its calibration.
    pub calibration: ImuCalibration,
    /// The file read.
    pub path: PathBuf,
    /// Where the calibration came from.
    pub calibration_from: String,
}

/// The stream `source` names for the sequence in `dir`, and its calibration: the
/// `imu` object of the `camera.json` beside the `imu.txt`, else of the sequence's,
/// else the default (an IMU aligned with the camera and on its clock, with a
/// warning).
pub fn load_stream(dir: &Path, source: &ImuSource) -> Result<Option<ImuStream>> {
    let path = match source {
        ImuSource::Off => return Ok(None),
        ImuSource::File(p) => p.clone(),
        ImuSource::Auto => {
            let p = dir.join(IMU_FILE);
            if !p.exists() {
                return Ok(None);
            }
            p
        }
    };
    let samples =
        load_imu(&path).with_context(|| format!("the IMU stream {}", shown_path(&path)))?;
    if samples.is_empty() {
        log::warn!(
            "{}: no IMU sample; tracking without the IMU",
            shown_path(&path)
        );
    }
    let found = ecvo_io::imu::find_calibration(&path, dir)?;
    let from = found.as_ref().map_or_else(
        || String::from("default (aligned with the camera, on its clock)"),
        |(_, p)| shown_path(p),
    );
    let calibration = found.map(|(c, _)| c).unwrap_or_else(|| {
        log::warn!(
            "{}: no `imu` object in camera.json; assuming an IMU aligned with the camera \
             and on its clock",
            shown_path(&path)
        );
        ImuCalibration::default()
    });
    Ok(Some(ImuStream {
        samples: samples.iter().map(ImuSample::gyro).collect(),
        calibration,
        path,
        calibration_from: from,
    }))
}

/// The calibration of a simulated IMU, as `camera.json` carries it.
pub fn calibration_of(m: &ImuModel) -> ImuCalibration {
    ImuCalibration {
        camera_from_imu: m.camera_from_imu,
        time_offset: m.time_offset,
        gyro_noise_density: Some(m.gyro_noise_density),
        gyro_bias_random_walk: Some(m.gyro_bias_random_walk),
    }
}

/// Writes a simulated IMU's readings as `imu.txt`, shifted by `start` seconds.
pub fn write_readings(
    path: &Path,
    readings: &[ImuReading],
    start: f64,
    m: &ImuModel,
    what: &str,
) -> Result<()> {
    let samples: Vec<ImuSample> = readings
        .iter()
        .map(|r| ImuSample {
            t: start + r.t,
            w: r.w,
            a: Some(r.a),
        })
        .collect();
    let comment = format!(
        "SIMULATED IMU ({what}), not a real sensor: {} Hz, gyro noise {:.2e} rad/s/sqrt(Hz), \
         turn-on bias [{:.4}, {:.4}, {:.4}] rad/s, bias walk {:.1e} rad/s/sqrt(s), \
         camera-IMU rotation {:.2} deg, time offset {:.4} s (t_frames = t_imu + offset); \
         calibration in camera.json",
        m.rate_hz,
        m.gyro_noise_density,
        m.gyro_turn_on_bias[0],
        m.gyro_turn_on_bias[1],
        m.gyro_turn_on_bias[2],
        m.gyro_bias_random_walk,
        m.camera_from_imu.angle().to_degrees(),
        m.time_offset
    );
    save_imu(path, &samples, &comment)?;
    Ok(())
}

/// Control-pose spacing of the spline through a ground truth, seconds.
pub const GROUNDTRUTH_KNOT_S: f64 = 0.02;

/// `ecvo imu-from-groundtruth`: a simulated `imu.txt` for the sequence in `seq` from
/// its `groundtruth.txt` (a smooth spline's derivatives, then a phone IMU's noise,
/// bias, rotation and offset drawn from `seed`), written with a `camera.json` (the
/// sequence's, with the `imu` object) into `out`, which must not be inside `seq`.
pub fn from_groundtruth(seq: &Path, out: &Path, seed: u64, knot: f64) -> Result<()> {
    if !(knot > 0.0 && knot <= 1.0) {
        bail!("--knot must be in (0, 1] s, got {knot}");
    }
    let gt_path = seq.join("groundtruth.txt");
    let gt = Trajectory::read_tum(&gt_path)
        .with_context(|| format!("reading {}", shown_path(&gt_path)))?;
    let Some(spline) = SplinePath::fit(&gt.stamps, &gt.poses, knot) else {
        bail!("{}: too few poses for a spline", shown_path(&gt_path));
    };
    // Checked before anything is created: the nearest existing ancestor of `out`,
    // resolved, must not lie inside the sequence folder.
    let seq_real = seq
        .canonicalize()
        .with_context(|| format!("{}", seq.display()))?;
    let abs = std::path::absolute(out)?;
    let existing = abs.ancestors().find(|p| p.exists()).unwrap_or(&abs);
    if existing.canonicalize()?.starts_with(&seq_real) {
        bail!(
            "--out {} is inside the sequence folder; write it elsewhere",
            out.display()
        );
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let model = ImuModel::phone(seed);
    let (lo, hi) = spline.span();
    // Relative times keep the differences exact; the stamps are shifted back.
    let readings = model.simulate(|t| spline.pose_at(t + lo), 0.0, hi - lo);
    write_readings(
        &out.join(IMU_FILE),
        &readings,
        lo,
        &model,
        &format!(
            "from {} by a spline, knots {knot} s, seed {seed}",
            shown_path(&gt_path)
        ),
    )?;
    let cam_src = seq.join(CAMERA_FILE_NAME);
    let cam_dst = out.join(CAMERA_FILE_NAME);
    std::fs::copy(&cam_src, &cam_dst)
        .with_context(|| format!("copying {}", shown_path(&cam_src)))?;
    ecvo_io::imu::save_imu_calibration(&cam_dst, &calibration_of(&model))?;
    outln!(
        "wrote {} simulated IMU samples at {} Hz ({:.1} s, rotation {:.2} deg, offset {:.1} ms) \
         and camera.json to {}; run with `ecvo run {} --imu {}`",
        readings.len(),
        model.rate_hz,
        hi - lo,
        model.camera_from_imu.angle().to_degrees(),
        model.time_offset * 1e3,
        out.display(),
        seq.display(),
        out.join(IMU_FILE).display()
    );
    Ok(())
}

/// The run's word on its IMU: a line for the summary and its JSON.
pub fn report(stream: &ImuStream, c: &ecvo_core::imu::ImuCounters) -> (String, serde_json::Value) {
    let line = format!(
        "IMU {}: {} samples taken ({} refused as out of order), {} frames with a gyro prior, \
         {} tracked without it (samples late {}, missing {}), bias updates {} ({} outliers), \
         depth turned to the intensity's time {} (not covered {})",
        shown_path(&stream.path),
        c.samples,
        c.refused,
        c.priors,
        c.late + c.missing,
        c.late,
        c.missing,
        c.bias_updates,
        c.bias_outliers,
        c.depth_turned,
        c.depth_unturned
    );
    let json = serde_json::json!({
        "file": stream.path.display().to_string(),
        "calibration_from": stream.calibration_from,
        "time_offset_s": stream.calibration.time_offset,
        "camera_from_imu_deg": stream.calibration.camera_from_imu.angle().to_degrees(),
        "samples": c.samples,
        "refused": c.refused,
        "dropped": c.dropped,
        "priors": c.priors,
        "late": c.late,
        "missing": c.missing,
        "bias_updates": c.bias_updates,
        "bias_outliers": c.bias_outliers,
        "depth_turned": c.depth_turned,
        "depth_unturned": c.depth_unturned,
    });
    (line, json)
}
