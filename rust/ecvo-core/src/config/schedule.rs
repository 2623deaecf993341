//! The coarse-to-fine schedule: its steps ([`MotionLevel`]), the named schedules,
//! and the parsers of `--schedule` and `--point-budget`.

use crate::camera::Camera;
use crate::error::{Error, Result};

/// The image side (the larger of width and height) from which the pyramid
/// schedules start one level coarser: they are written for images of about 320 pixels
/// across, and on every halving of the image down to below this size their steps
/// move one pyramid level up ([`Schedule::levels_for`]).
pub const SCHEDULE_SHIFT_SIDE: usize = 640;

/// The most pyramid levels [`Schedule::levels_for`] moves a schedule up: the pyramid
/// schedules reach level 3, and a configuration at most level 6.
pub const MAX_SCHEDULE_SHIFT: usize = 3;

/// The smallest side, in pixels, of the coarsest pyramid level a schedule may use.
pub const MIN_LEVEL_SIDE: usize = 8;

/// The deepest pyramid level a configuration may use, whatever the image size.
pub const MAX_PYRAMID_LEVEL: usize = 6;

/// The smallest point budget a step may have.
pub const MIN_POINT_BUDGET: usize = 64;

/// One step of the coarse-to-fine schedule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MotionLevel {
    /// Image pyramid level the residuals are computed on (0 = full resolution,
    /// each level halves width and height by 2x2 averaging).
    pub pyramid_level: usize,
    /// Use every `stride`-th pixel of that level in each direction (the paper
    /// samples every 8th, 4th and 2nd pixel of the full image).
    pub stride: usize,
    /// At most this many Gauss-Newton iterations at this step.
    pub max_iterations: u32,
    /// Keep at most this many template points at this step, chosen by their
    /// intensity and depth gradients and spread over the image
    /// ([`crate::prepare`]'s selection); `None` keeps every valid sampled pixel.
    pub max_points: Option<usize>,
}

/// The coarse-to-fine schedules the engine knows by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    /// The paper's: every 8th, 4th, then 2nd pixel of the full-resolution image. Every
    /// step looks the warped points up in the full-resolution image, so the basin of
    /// convergence is about one full-resolution pixel of gradient wide.
    PaperSampling,
    /// A 2x2-averaged image pyramid, coarsest first (1/8 resolution), down to every
    /// pixel of the full-resolution image.
    Pyramid,
    /// The pyramid from 1/8 resolution, every pixel down to half resolution, then
    /// every second pixel of the full-resolution image: the basin of the pyramid at
    /// the cost of the paper's sampling plus the coarse levels.
    PyramidStride2,
}

impl Schedule {
    /// How many pyramid levels the pyramid schedules move up on `camera`: the number
    /// of halvings that bring the larger image side below [`SCHEDULE_SHIFT_SIDE`]
    /// (0 at 320x240 and 320x180, 1 at 640x480, 2 at 1280x960), at most
    /// [`MAX_SCHEDULE_SHIFT`] so that the deepest level stays within the six a
    /// configuration may use.
    pub fn shift_for(camera: &Camera) -> usize {
        let mut side = camera.width.max(camera.height);
        let mut k = 0;
        while side >= SCHEDULE_SHIFT_SIDE && k < MAX_SCHEDULE_SHIFT {
            side /= 2;
            k += 1;
        }
        k
    }

    /// The deepest pyramid level an image of `camera`'s size has: the most halvings
    /// (at most [`MAX_PYRAMID_LEVEL`]) that leave both sides at least
    /// [`MIN_LEVEL_SIDE`] pixels (0 for images under 16 pixels on a side, 3 at 64x64,
    /// 2 at 64x48).
    pub fn max_level_for(camera: &Camera) -> usize {
        let (mut w, mut h) = (camera.width, camera.height);
        let mut k = 0;
        while k < MAX_PYRAMID_LEVEL && w / 2 >= MIN_LEVEL_SIDE && h / 2 >= MIN_LEVEL_SIDE {
            w /= 2;
            h /= 2;
            k += 1;
        }
        k
    }

    /// The steps of this schedule on `camera`. The paper's sampling is taken as
    /// written at every size (it was made for 640x480). The pyramid schedules are
    /// written for images of about 320 pixels across ([`Schedule::levels`]); on a
    /// larger image every step moves [`Schedule::shift_for`] levels up and divides its
    /// stride by as much (at least 1), so that the coarsest step sees about the same
    /// image and the finest runs on every pixel of the half-resolution image instead
    /// of every second pixel of the full one. On the 640x480 Kinect streams of the
    /// suite that is the same drift per second as the full-resolution step (real
    /// 1.01 translation / 0.97 rotation, synthetic 0.96 / 1.02) in about 0.7 of the
    /// time: the lookups run on an image four times smaller (`docs/profile-passes.md`).
    ///
    /// On an image too small for a step's level (fewer than [`MIN_LEVEL_SIDE`] pixels
    /// on a side there), the step runs on the deepest level the image has
    /// ([`Schedule::max_level_for`]): 64x48 runs levels 2, 2, 1, 0 instead of 3, 2,
    /// 1, 0, and 8192x8 runs every step on the full image. Sizes whose levels all
    /// fit are unchanged.
    pub fn levels_for(self, camera: &Camera) -> Vec<MotionLevel> {
        let k = match self {
            Schedule::PaperSampling => 0,
            Schedule::Pyramid | Schedule::PyramidStride2 => Self::shift_for(camera),
        };
        let deepest = Self::max_level_for(camera);
        self.levels()
            .into_iter()
            .map(|l| MotionLevel {
                pyramid_level: (l.pyramid_level + k).min(deepest),
                stride: (l.stride >> k).max(1),
                ..l
            })
            .collect()
    }

    /// The steps of this schedule as written, for images of about 320 pixels
    /// across (see [`Schedule::levels_for`]).
    pub fn levels(self) -> Vec<MotionLevel> {
        let l = |pyramid_level, stride, max_iterations| MotionLevel {
            pyramid_level,
            stride,
            max_iterations,
            max_points: None,
        };
        match self {
            Schedule::PaperSampling => vec![l(0, 8, 20), l(0, 4, 15), l(0, 2, 10)],
            Schedule::Pyramid => vec![l(3, 1, 20), l(2, 1, 15), l(1, 1, 10), l(0, 1, 8)],
            Schedule::PyramidStride2 => {
                vec![l(3, 1, 20), l(2, 1, 15), l(1, 1, 10), l(0, 2, 8)]
            }
        }
    }

    /// The name the command line uses.
    pub fn name(self) -> &'static str {
        match self {
            Schedule::PaperSampling => "paper",
            Schedule::Pyramid => "pyramid",
            Schedule::PyramidStride2 => "pyramid-stride2",
        }
    }
}

impl std::str::FromStr for Schedule {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "paper" => Ok(Schedule::PaperSampling),
            "pyramid" => Ok(Schedule::Pyramid),
            "pyramid-stride2" => Ok(Schedule::PyramidStride2),
            _ => Err(Error::InvalidConfig {
                field: "schedule",
                why: format!("`{s}` is not paper, pyramid or pyramid-stride2"),
            }),
        }
    }
}

/// Parses a coarse-to-fine schedule for `camera`: a name (`paper`, `pyramid`,
/// `pyramid-stride2`, whose steps [`Schedule::levels_for`] gives), or
/// steps written `LEVEL/STRIDE/ITERATIONS` or `LEVEL/STRIDE/ITERATIONS/POINTS` (a
/// point budget, [`MotionLevel::max_points`]), comma-separated, coarsest first (e.g.
/// `3/1/20,2/1/15,1/1/10,0/2/8`). Ranges are checked by [`Config::validate`](crate::config::Config::validate).
pub fn parse_schedule(s: &str, camera: &Camera) -> Result<Vec<MotionLevel>> {
    if let Ok(named) = s.parse::<Schedule>() {
        return Ok(named.levels_for(camera));
    }
    let bad = |why: String| Error::InvalidConfig {
        field: "schedule",
        why,
    };
    s.split(',')
        .map(|step| {
            let parts: Vec<&str> = step.trim().split('/').collect();
            let (level, stride, iterations, points) = match parts[..] {
                [l, s, i] => (l, s, i, None),
                [l, s, i, p] => (l, s, i, Some(p)),
                _ => {
                    return Err(bad(format!(
                        "`{step}` is not LEVEL/STRIDE/ITERATIONS[/POINTS] (and `{s}` is not paper, pyramid or pyramid-stride2)"
                    )));
                }
            };
            let num = |t: &str, what: &str| {
                t.trim()
                    .parse::<u32>()
                    .map_err(|_| bad(format!("`{step}`: {what} `{t}` is not a whole number")))
            };
            Ok(MotionLevel {
                pyramid_level: num(level, "level")? as usize,
                stride: num(stride, "stride")? as usize,
                max_iterations: num(iterations, "iterations")?,
                max_points: match points {
                    Some(p) => Some(num(p, "points")? as usize),
                    None => None,
                },
            })
        })
        .collect()
}

/// Parses per-level point budgets written `LEVEL=POINTS`, comma-separated, e.g.
/// `1=4096,0=4096`; `POINTS` may be `all` (no budget). `none` or an empty string
/// gives no entry. Apply them with [`MotionConfig::set_point_budget`](crate::config::MotionConfig::set_point_budget).
pub fn parse_point_budget(s: &str) -> Result<Vec<(usize, Option<usize>)>> {
    let bad = |why: String| Error::InvalidConfig {
        field: "point_budget",
        why,
    };
    super::parse_pairs(s, '=', "LEVEL=POINTS, e.g. 0=4096", &bad, |pair, l, n| {
        let level = l
            .trim()
            .parse::<usize>()
            .map_err(|_| bad(format!("`{pair}`: level `{l}` is not a whole number")))?;
        let n = n.trim();
        let points = if n.eq_ignore_ascii_case("all") {
            None
        } else {
            Some(n.parse::<usize>().map_err(|_| {
                bad(format!(
                    "`{pair}`: points `{n}` is not a whole number or all"
                ))
            })?)
        };
        Ok((level, points))
    })
}
