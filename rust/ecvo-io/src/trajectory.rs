//! Timestamped camera trajectories in the TUM format that the TUM tools and evo read:
//! one `timestamp tx ty tz qx qy qz qw` line per pose, `#` comments allowed.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use ecvo_core::{Num, Pose};
use nalgebra::{Quaternion, Translation3, UnitQuaternion};

use crate::error::{Error, Result};
use crate::list::{Monotonic, parse_f64, read_text, records};

/// Largest position coordinate a trajectory file may hold, metres: beyond it the
/// squares of the evaluation's sums are no longer exact enough to mean anything (and
/// near 1e154 they overflow to infinity).
pub const MAX_COORDINATE_M: f64 = 1e9;

/// A sequence of timestamped camera-to-world poses; `stamps[i]` belongs to `poses[i]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Timestamps in seconds.
    pub stamps: Vec<f64>,
    /// Camera-to-world poses.
    pub poses: Vec<Pose>,
}

impl Trajectory {
    /// An empty trajectory.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty trajectory with room for `n` poses.
    pub fn with_capacity(n: usize) -> Self {
        Trajectory {
            stamps: Vec::with_capacity(n),
            poses: Vec::with_capacity(n),
        }
    }

    /// Appends a pose taken at `stamp` seconds.
    pub fn push(&mut self, stamp: f64, pose: Pose) {
        self.stamps.push(stamp);
        self.poses.push(pose);
    }

    /// Number of poses.
    pub fn len(&self) -> usize {
        self.stamps.len().min(self.poses.len())
    }

    /// Whether there is no pose.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Iterates over `(stamp, pose)` pairs.
    pub fn iter(&self) -> impl Iterator<Item = (f64, &Pose)> + '_ {
        self.stamps.iter().copied().zip(self.poses.iter())
    }

    /// Parses TUM trajectory text; `path` is only used in error messages.
    ///
    /// Each data line holds exactly 8 finite numbers, positions within
    /// [`MAX_COORDINATE_M`]; the quaternion is normalised and must
    /// not be (near) zero; timestamps must be strictly increasing.
    pub fn parse_tum(text: &str, path: &Path) -> Result<Self> {
        let mut traj = Trajectory::new();
        let mut mono = Monotonic::default();
        const NAMES: [&str; 8] = ["timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"];
        for r in records(text) {
            if r.fields.len() != 8 {
                return Err(Error::parse(
                    path,
                    r.line,
                    format!(
                        "expected `timestamp tx ty tz qx qy qz qw`, found {} field(s)",
                        r.fields.len()
                    ),
                ));
            }
            let mut v = [0.0; 8];
            for k in 0..8 {
                v[k] = parse_f64(path, r.line, NAMES[k], r.fields[k])?;
            }
            mono.check(path, r.line, v[0])?;
            for k in 1..4 {
                if v[k].abs() > MAX_COORDINATE_M {
                    return Err(Error::parse(
                        path,
                        r.line,
                        format!(
                            "{} {} is out of range (at most {MAX_COORDINATE_M:e} m from the origin)",
                            NAMES[k],
                            Num(v[k])
                        ),
                    ));
                }
            }
            let q = Quaternion::new(v[7], v[4], v[5], v[6]);
            let norm = q.norm();
            if !(norm > 1e-6) {
                return Err(Error::parse(path, r.line, "the quaternion is zero"));
            }
            // Keep quaternions that are unit to rounding as written, so that writing
            // and reading back is exact.
            let q = if (norm - 1.0).abs() > 1e-15 {
                q / norm
            } else {
                q
            };
            let rot = UnitQuaternion::new_unchecked(q);
            traj.push(
                v[0],
                Pose::from_parts(Translation3::new(v[1], v[2], v[3]), rot),
            );
        }
        Ok(traj)
    }

    /// Reads a TUM trajectory file (`timestamp tx ty tz qx qy qz qw`); errors name the
    /// file and line.
    pub fn read_tum(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = read_text(path)?;
        Self::parse_tum(&text, path)
    }

    /// Writes the trajectory as TUM text to `out`, every number with full (round-trip)
    /// precision.
    pub fn write_tum_to(&self, mut out: impl Write) -> std::io::Result<()> {
        writeln!(out, "# timestamp tx ty tz qx qy qz qw")?;
        for (t, p) in self.iter() {
            let tr = &p.translation.vector;
            let q = p.rotation.quaternion();
            writeln!(
                out,
                "{} {} {} {} {} {} {} {}",
                t, tr.x, tr.y, tr.z, q.i, q.j, q.k, q.w
            )?;
        }
        out.flush()
    }

    /// Writes a TUM trajectory file that evo and the TUM tools read; every number is
    /// written with full (round-trip) precision. Non-finite values are an error.
    pub fn write_tum(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        if self.stamps.len() != self.poses.len() {
            return Err(Error::InvalidInput(format!(
                "{}: trajectory has {} stamps but {} poses",
                path.display(),
                self.stamps.len(),
                self.poses.len()
            )));
        }
        for (i, (t, p)) in self.iter().enumerate() {
            let q = p.rotation.quaternion();
            let finite = t.is_finite()
                && p.translation.vector.iter().all(|v| v.is_finite())
                && q.coords.iter().all(|v| v.is_finite());
            if !finite {
                return Err(Error::InvalidInput(format!(
                    "{}: pose {i} (timestamp {}) has a non-finite value",
                    path.display(),
                    Num(t)
                )));
            }
        }
        let file = File::create(path).map_err(|e| Error::io(path, e))?;
        self.write_tum_to(BufWriter::new(file))
            .map_err(|e| Error::io(path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn text_round_trip_is_exact() {
        let mut t = Trajectory::new();
        for i in 0..20 {
            let f = i as f64;
            let pose = Pose::new(
                Vector3::new(0.1 * f, -1.0 / 3.0 * f, 1e-9 * f),
                Vector3::new(0.01 * f, 0.3, -0.02 * f),
            );
            t.push(1305031102.175304 + f / 30.0, pose);
        }
        let mut buf = Vec::new();
        t.write_tum_to(&mut buf).unwrap();
        let back =
            Trajectory::parse_tum(std::str::from_utf8(&buf).unwrap(), Path::new("m")).unwrap();
        assert_eq!(back.stamps, t.stamps);
        for (a, b) in back.poses.iter().zip(&t.poses) {
            assert_eq!(a.translation, b.translation);
            assert!(a.rotation.angle_to(&b.rotation) < 1e-15);
        }
    }

    #[test]
    fn bad_lines_name_file_and_line() {
        let p = Path::new("gt.txt");
        let e = Trajectory::parse_tum("# c\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n", p).unwrap_err();
        assert!(e.to_string().starts_with("gt.txt:3:"), "{e}");
        let e = Trajectory::parse_tum("1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n", p).unwrap_err();
        assert!(
            e.to_string().starts_with("gt.txt:2:") && e.to_string().contains("ty"),
            "{e}"
        );
        let e = Trajectory::parse_tum("1 0 0 0 0 0 0 1\n\n1 0 0 0 0 0 0 1\n", p).unwrap_err();
        assert!(matches!(e, Error::NonMonotonic { line: 3, .. }), "{e}");
        let e = Trajectory::parse_tum("1 0 0 0 0 0 0 0\n", p).unwrap_err();
        assert!(e.to_string().starts_with("gt.txt:1:"), "{e}");
        // Non-finite and absurd values are refused with their line.
        for (line, needle) in [
            ("2 nan 0 0 0 0 0 1", "tx"),
            ("2 0 0 0 0 inf 0 1", "qy"),
            ("2 0 1e300 0 0 0 0 1", "out of range"),
            ("inf 0 0 0 0 0 0 1", "timestamp"),
        ] {
            let text = format!("1 0 0 0 0 0 0 1\n{line}\n");
            let e = Trajectory::parse_tum(&text, p).unwrap_err().to_string();
            assert!(e.starts_with("gt.txt:2:") && e.contains(needle), "{e}");
        }
    }
}
