//! IMU streams: `imu.txt` beside a sequence's lists, and the IMU's calibration, the
//! `imu` object of `camera.json` (issue 47, `docs/imu.md`).
//!
//! `imu.txt` holds one sample a line, `timestamp wx wy wz [ax ay az]`: seconds on the
//! IMU's clock, rad/s and m/s² in the IMU's frame, `#` comments. Every data line has
//! the same number of fields (4, or 7 with the accelerometer), every value is finite
//! and within a physical range, and timestamps strictly increase. The file is a
//! regular file of at most [`MAX_IMU_BYTES`].

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use ecvo_core::{GyroSample, ImuCalibration, Num};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::files::{MAX_CAMERA_BYTES, read_text_limited, shown};
use crate::list::{Monotonic, parse_f64, records};

/// Name of the IMU file inside a sequence folder.
pub const IMU_FILE: &str = "imu.txt";

/// Largest `imu.txt` read (64 MiB: about 800,000 samples, half an hour at 400 Hz).
pub const MAX_IMU_BYTES: u64 = 64 << 20;

/// Largest angular rate a line may hold, rad/s (a phone gyroscope saturates near
/// 35 rad/s, 2000 °/s).
pub const MAX_RATE_RAD_S: f64 = 100.0;

/// Largest acceleration a line may hold, m/s² (a phone accelerometer saturates near
/// 160 m/s², 16 g).
pub const MAX_ACCEL_M_S2: f64 = 1000.0;

/// One line of `imu.txt`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuSample {
    /// Seconds on the IMU's clock.
    pub t: f64,
    /// Angular velocity, rad/s in the IMU's frame.
    pub w: [f64; 3],
    /// Specific force, m/s² in the IMU's frame, when the file has it.
    pub a: Option<[f64; 3]>,
}

impl ImuSample {
    /// The gyroscope part, as the engine takes it.
    pub fn gyro(&self) -> GyroSample {
        GyroSample {
            t: self.t,
            w: self.w,
        }
    }
}

/// Parses `imu.txt` text; `path` is only used in error messages.
pub fn parse_imu(text: &str, path: &Path) -> Result<Vec<ImuSample>> {
    const NAMES: [&str; 7] = ["timestamp", "wx", "wy", "wz", "ax", "ay", "az"];
    let mut out = Vec::new();
    let mut mono = Monotonic::default();
    let mut width = None;
    for r in records(text) {
        let n = r.fields.len();
        if n != 4 && n != 7 {
            return Err(Error::parse(
                path,
                r.line,
                format!("expected `timestamp wx wy wz [ax ay az]`, found {n} field(s)"),
            ));
        }
        if *width.get_or_insert(n) != n {
            return Err(Error::parse(
                path,
                r.line,
                format!(
                    "{n} fields where the lines before have {}: every line has the \
                     accelerometer or none does",
                    width.unwrap_or(n)
                ),
            ));
        }
        let mut v = [0.0; 7];
        for k in 0..n {
            v[k] = parse_f64(path, r.line, NAMES[k], r.fields[k])?;
        }
        mono.check(path, r.line, v[0])?;
        for (k, &x) in v.iter().enumerate().take(n).skip(1) {
            let (limit, unit) = if k < 4 {
                (MAX_RATE_RAD_S, "rad/s")
            } else {
                (MAX_ACCEL_M_S2, "m/s²")
            };
            if x.abs() > limit {
                return Err(Error::parse(
                    path,
                    r.line,
                    format!(
                        "{} {} is out of range (at most {limit} {unit})",
                        NAMES[k],
                        Num(x)
                    ),
                ));
            }
        }
        out.push(ImuSample {
            t: v[0],
            w: [v[1], v[2], v[3]],
            a: (n == 7).then_some([v[4], v[5], v[6]]),
        });
    }
    Ok(out)
}

/// Reads and checks an `imu.txt` file.
pub fn load_imu(path: impl AsRef<Path>) -> Result<Vec<ImuSample>> {
    let path = path.as_ref();
    let text = read_text_limited(path, MAX_IMU_BYTES)?;
    parse_imu(&text, path)
}

/// Writes samples as `imu.txt`, with a comment line saying what wrote them.
pub fn save_imu(path: impl AsRef<Path>, samples: &[ImuSample], comment: &str) -> Result<()> {
    let path = path.as_ref();
    let io = |e| Error::io(path, e);
    let mut w = BufWriter::new(File::create(path).map_err(io)?);
    for line in comment.lines() {
        writeln!(w, "# {line}").map_err(io)?;
    }
    writeln!(
        w,
        "# timestamp wx wy wz [ax ay az] (s, rad/s, m/s², IMU frame)"
    )
    .map_err(io)?;
    for s in samples {
        write!(w, "{:.6} {:.9} {:.9} {:.9}", s.t, s.w[0], s.w[1], s.w[2]).map_err(io)?;
        if let Some(a) = s.a {
            write!(w, " {:.7} {:.7} {:.7}", a[0], a[1], a[2]).map_err(io)?;
        }
        writeln!(w).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Samples stamped up to this long after a frame (on the frames' clock) are pushed
/// before it by [`ImuFeed`]: what a live pusher has by the time the frame arrives,
/// and enough for the integration to interpolate the frame's end.
pub const FEED_AHEAD_S: f64 = 0.005;

/// Replays an IMU stream beside a sequence's frames, as `ecvo run` does: before each
/// frame, every sample not yet pushed and stamped up to [`FEED_AHEAD_S`] after it.
#[derive(Clone, Debug)]
pub struct ImuFeed {
    samples: Vec<GyroSample>,
    offset: f64,
    next: usize,
}

impl ImuFeed {
    /// A feed of `samples` whose clock is `time_offset` behind the frames'
    /// ([`ImuCalibration::time_offset`]).
    pub fn new(samples: Vec<GyroSample>, time_offset: f64) -> Self {
        ImuFeed {
            samples,
            offset: time_offset,
            next: 0,
        }
    }

    /// The samples to push before a frame stamped `t` (frames' clock).
    pub fn before(&mut self, t: f64) -> &[GyroSample] {
        let start = self.next;
        let limit = t + FEED_AHEAD_S - self.offset;
        while self.next < self.samples.len() && self.samples[self.next].t <= limit {
            self.next += 1;
        }
        &self.samples[start..self.next]
    }

    /// The samples to push before `frame`: [`Self::before`] the later of its intensity
    /// and depth times, so that the gyro covers the turn of its depth to the
    /// intensity's time.
    pub fn before_frame(&mut self, frame: &crate::Frame) -> &[GyroSample] {
        self.before(frame.timestamp.max(frame.depth_timestamp))
    }
}

/// The calibration of the IMU stream `imu_txt` of the sequence in `seq_dir`: the
/// `imu` object of the `camera.json` beside `imu_txt`, else of the sequence's, with
/// the file it came from; `None` if neither has one.
pub fn find_calibration(
    imu_txt: &Path,
    seq_dir: &Path,
) -> Result<Option<(ImuCalibration, std::path::PathBuf)>> {
    let beside = imu_txt.parent().map(|p| p.join(crate::camera::CAMERA_FILE));
    for cam in beside
        .into_iter()
        .chain([seq_dir.join(crate::camera::CAMERA_FILE)])
    {
        if cam.exists()
            && let Some(c) = load_imu_calibration(&cam)?
        {
            return Ok(Some((c, cam)));
        }
    }
    Ok(None)
}

/// The `imu` object of `camera.json`.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ImuFile {
    camera_from_imu: [[f64; 3]; 3],
    time_offset: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_noise_density: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyro_bias_random_walk: Option<f64>,
}

/// How far from orthonormal (per entry of `RᵀR − I`) a rotation matrix may be.
const ROTATION_TOLERANCE: f64 = 1e-6;

impl ImuFile {
    fn calibration(&self) -> std::result::Result<ImuCalibration, String> {
        let r = &self.camera_from_imu;
        let m = Matrix3::from_fn(|i, j| r[i][j]);
        if !m.iter().all(|x| x.is_finite()) {
            return Err("camera_from_imu has a non-finite entry".into());
        }
        let off = (m.transpose() * m - Matrix3::identity()).abs().max();
        if off > ROTATION_TOLERANCE || m.determinant() < 0.0 {
            return Err(format!(
                "camera_from_imu is not a rotation matrix (RᵀR differs from I by {off:.2e}, \
                 determinant {:.6})",
                m.determinant()
            ));
        }
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m));
        let c = ImuCalibration {
            camera_from_imu: q,
            time_offset: self.time_offset,
            gyro_noise_density: self.gyro_noise_density,
            gyro_bias_random_walk: self.gyro_bias_random_walk,
        };
        c.validate().map_err(|e| e.to_string())?;
        Ok(c)
    }

    fn of(c: &ImuCalibration) -> ImuFile {
        let m = c.camera_from_imu.to_rotation_matrix();
        ImuFile {
            camera_from_imu: std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)])),
            time_offset: c.time_offset,
            gyro_noise_density: c.gyro_noise_density,
            gyro_bias_random_walk: c.gyro_bias_random_walk,
        }
    }
}

/// The IMU calibration in `camera.json` text (its `imu` object), `None` without
/// one; `path` is only used in error messages.
pub fn parse_imu_calibration(text: &str, path: &Path) -> Result<Option<ImuCalibration>> {
    let bad = |msg: String| Error::Camera {
        path: path.to_path_buf(),
        msg,
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| bad(shown(&e.to_string())))?;
    let Some(imu) = value.get("imu") else {
        return Ok(None);
    };
    let file: ImuFile = serde_json::from_value(imu.clone())
        .map_err(|e| bad(format!("imu: {}", shown(&e.to_string()))))?;
    file.calibration()
        .map(Some)
        .map_err(|m| bad(format!("imu: {m}")))
}

/// Reads the IMU calibration of a `camera.json` file, `None` without one.
pub fn load_imu_calibration(path: impl AsRef<Path>) -> Result<Option<ImuCalibration>> {
    let path = path.as_ref();
    let text = read_text_limited(path, MAX_CAMERA_BYTES)?;
    parse_imu_calibration(&text, path)
}

/// `camera.json` text with `imu` added as its `imu` object (replacing any).
pub fn with_imu_calibration(text: &str, path: &Path, imu: &ImuCalibration) -> Result<String> {
    let bad = |msg: String| Error::Camera {
        path: path.to_path_buf(),
        msg,
    };
    imu.validate().map_err(|e| bad(e.to_string()))?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| bad(shown(&e.to_string())))?;
    let obj = value
        .as_object_mut()
        .ok_or_else(|| bad("not a JSON object".into()))?;
    obj.insert(
        "imu".into(),
        serde_json::to_value(ImuFile::of(imu)).map_err(|e| bad(e.to_string()))?,
    );
    let mut out = serde_json::to_string_pretty(&value).map_err(|e| bad(e.to_string()))?;
    out.push('\n');
    Ok(out)
}

/// Adds `imu` to the `camera.json` file at `path` (rewriting it).
pub fn save_imu_calibration(path: impl AsRef<Path>, imu: &ImuCalibration) -> Result<()> {
    let path = path.as_ref();
    let text = read_text_limited(path, MAX_CAMERA_BYTES)?;
    let out = with_imu_calibration(&text, path, imu)?;
    std::fs::write(path, out).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("seq/imu.txt")
    }

    #[test]
    fn reads_gyro_and_accelerometer() {
        let t = "# ecvo synth\n1.000 0.1 -0.2 0.3 0 0 9.81\n\n1.005 0.1 -0.2 0.3 0 0.1 9.8\n";
        let s = parse_imu(t, p()).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[1].w, [0.1, -0.2, 0.3]);
        assert_eq!(s[1].a, Some([0.0, 0.1, 9.8]));
        assert_eq!(s[0].gyro().t, 1.0);
        let g = parse_imu("\u{feff}5 1 2 3\n6 1 2 3\n", p()).unwrap();
        assert_eq!((g.len(), g[0].a), (2, None));
        assert!(parse_imu("", p()).unwrap().is_empty());
    }

    #[test]
    fn refuses_bad_lines_naming_them() {
        for (text, line, what) in [
            ("1 2 3\n", 1, "found 3 field(s)"),
            (
                "1 0 0 0\n2 0 0 0 0 0 9.8\n",
                2,
                "every line has the accelerometer",
            ),
            ("1 0 0 0\n1 0 0 0\n", 2, "strictly increasing"),
            ("1 0 0 0\n0.5 0 0 0\n", 2, "strictly increasing"),
            ("1 nan 0 0\n", 1, "not finite"),
            ("1 0 inf 0\n", 1, "not finite"),
            ("1 0 0 x\n", 1, "not a number"),
            ("1 0 0 1e3\n", 1, "out of range"),
            ("1 0 0 0 0 0 1e9\n", 1, "out of range"),
            ("1 0 0 0 0 0 0 0\n", 1, "found 8 field(s)"),
        ] {
            let e = parse_imu(text, p()).unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("seq/imu.txt:{line}:")),
                "{text:?}: {e}"
            );
            assert!(e.contains(what), "{text:?}: {e}");
        }
    }

    #[test]
    fn calibration_round_trips_and_bad_ones_are_refused() {
        let cam = r#"{"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 32, "cy": 24, "depth_scale": 5000}"#;
        let path = Path::new("camera.json");
        assert_eq!(parse_imu_calibration(cam, path).unwrap(), None);
        let c = ImuCalibration {
            camera_from_imu: UnitQuaternion::from_euler_angles(0.03, -0.02, 0.05),
            time_offset: 0.012,
            gyro_noise_density: Some(1.2e-4),
            gyro_bias_random_walk: None,
        };
        let text = with_imu_calibration(cam, path, &c).unwrap();
        // The camera still reads, and so does the calibration.
        crate::camera::parse_camera_json(&text, path).unwrap();
        let back = parse_imu_calibration(&text, path).unwrap().unwrap();
        assert!(back.camera_from_imu.angle_to(&c.camera_from_imu) < 1e-12);
        assert_eq!(
            (
                back.time_offset,
                back.gyro_noise_density,
                back.gyro_bias_random_walk
            ),
            (0.012, Some(1.2e-4), None)
        );
        let with = |imu: &str| format!(r#"{{"width": 64, "imu": {imu}}}"#);
        for (imu, what) in [
            (
                r#"{"camera_from_imu": [[1,0,0],[0,1,0],[0,0,1]]}"#,
                "time_offset",
            ),
            (
                r#"{"camera_from_imu": [[2,0,0],[0,1,0],[0,0,1]], "time_offset": 0}"#,
                "not a rotation",
            ),
            (
                r#"{"camera_from_imu": [[-1,0,0],[0,1,0],[0,0,1]], "time_offset": 0}"#,
                "not a rotation",
            ),
            (
                r#"{"camera_from_imu": [[1,0,0],[0,1,0],[0,0,1]], "time_offset": 5}"#,
                "within ±1 s",
            ),
            (
                r#"{"camera_from_imu": [[1,0,0],[0,1,0],[0,0,1]], "time_offset": 0, "gyro_noise_density": -1}"#,
                "non-negative",
            ),
            (
                r#"{"camera_from_imu": [[1,0,0],[0,1,0],[0,0,1]], "time_offset": 0, "offset": 0}"#,
                "unknown field",
            ),
            (
                r#"{"camera_from_imu": [[1,0],[0,1]], "time_offset": 0}"#,
                "imu",
            ),
            ("[]", "imu"),
        ] {
            let e = parse_imu_calibration(&with(imu), path)
                .unwrap_err()
                .to_string();
            assert!(e.contains(what), "{imu}: {e}");
        }
    }
}
