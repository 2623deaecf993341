//! Frame preparation: the filter stage of the paper (section 4.2, Figure 4).
//!
//! Raw depth is converted to metres, smoothed by a bilateral filter over valid
//! pixels only, then two removal filters drop unreliable pixels:
//!
//! - **normal-based removal** (εn): two normals from divided differences of the
//!   back-projected points, one along the principal axes and one along the
//!   diagonals; a pixel whose two normals differ by more than εn is dropped,
//!   otherwise their average is its normal;
//! - **contour-based removal** (εg): where the cross-product normal
//!   `(p(u-1,0) - p(u)) × (p(u,-1) - p(u))` makes an angle within `90° ± εg` with
//!   the viewing ray `p(u)`, the 3x3 neighbourhood is dropped.
//!
//! Both masks are computed on the same smoothed depth and applied together. The
//! result feeds an image pyramid (2x2 mean intensity, 2x2 mean of agreeing valid
//! depths), per-level gradients, and per-schedule-step template points. A frame is
//! prepared once and reused when it becomes the previous or a reference frame.
//!
//! The work is a few passes, each reading what the last one wrote and nothing else:
//!
//! 1. raw depth to metres, into a zero-padded buffer (`bilateral::load_padded`);
//! 2. the bilateral filter (`bilateral`), row-parallel;
//! 3. back-projection, both normals and the contour test in one pass
//!    (`removal::normals_and_seeds`), row-parallel: the points are recomputed from
//!    the smoothed depth where they are needed, never stored;
//! 4. the masks applied (the contour seeds dilated 3x3 on the fly) into compact
//!    intensity and depth planes of level 0 (`removal::apply_masks`);
//! 5. per level, the interleaved samples with their gradients, written once from
//!    the compact planes, and the next level's planes (`pyramid`);
//! 6. the templates.
//!
//! The per-pixel kernels are written branch-free over whole rows so that the
//! compiler vectorises them (SSE2 on x86_64, NEON on aarch64); on x86_64 the heavy
//! ones are compiled again for AVX2 and for AVX-512, and the widest copy the CPU has
//! runs (`simd`). Every pixel goes through the same IEEE operations in the same order
//! as in a scalar loop (no fused multiply-add), so the output is the same bit for
//! bit on every path.

use crate::camera::{Camera, FrameView};
use crate::config::{BilateralConfig, Config, FilterConfig, LookupDepth, MotionLevel};
use crate::error::Result;
use crate::imu::depth_time::DepthTime;

use rayon::prelude::*;

mod bilateral;
mod pyramid;
#[cfg(test)]
mod reference;
mod removal;
mod select;
mod side;
mod template;
mod turn;
pub use template::max_template_points;
use template::{build_selected_template, build_template, template_capacity};
pub use turn::turn_depth;
pub(crate) mod simd;
#[cfg(test)]
mod tests;

pub use side::{ReferenceSide, Templates};
pub(crate) use side::{half_bilateral_bytes, lookup_depth, side_bytes};

/// Fewest pixels one rayon task of a row-parallel loop takes. Handing work to
/// another thread costs tens of microseconds, so an image is only split when each
/// part has at least this many pixels: a 640x480 image into four tasks, a 320x240
/// one not at all. Every output pixel depends only on the inputs, never on the
/// order of the rows, so the result is the same whatever the number of threads.
const PIXELS_PER_TASK: usize = 65536;

/// Rows of width `w` per rayon task.
fn rows_per_task(w: usize) -> usize {
    PIXELS_PER_TASK.div_ceil(w.max(1))
}

/// Runs `f(y, row)` over the rows of width `w` of `out`, with rayon.
fn rows<T: Send>(out: &mut [T], w: usize, f: impl Fn(usize, &mut [T]) + Sync + Send) {
    out.par_chunks_mut(w)
        .enumerate()
        .with_min_len(rows_per_task(w))
        .for_each(|(y, row)| f(y, row));
}

/// Channels of one pixel of an [`ImageLevel`]: intensity in [0, 1], its x and y
/// gradients, depth in metres (NaN when missing), its x and y gradients (NaN when a
/// neighbour is missing), and two pad lanes so a pixel is 32 bytes.
pub type Sample = [f32; 8];

/// Index of the intensity channel in a [`Sample`].
pub const I: usize = 0;
/// Index of the depth channel in a [`Sample`].
pub const D: usize = 3;

/// The intensity gradient (`|Ix| + |Iy|`, intensity in [0, 1] per pixel: 2.5 gray
/// levels a pixel) above which a pixel counts as textured.
pub const TEXTURE_GRADIENT: f32 = 0.01;

/// One level of the image pyramid, interleaved so that a bilinear lookup of all
/// six channels touches four contiguous 32-byte pixels.
#[derive(Clone, Debug, Default)]
pub struct ImageLevel {
    /// Intrinsics of this level.
    pub camera: Option<Camera>,
    /// `width * height` samples, row-major.
    pub samples: Vec<Sample>,
}

impl ImageLevel {
    /// The intrinsics of this level (set by preparation).
    pub fn camera(&self) -> &Camera {
        self.camera.as_ref().expect("level prepared")
    }
}

/// The reference-side pixels of one coarse-to-fine step: back-projected points and
/// their intensities, `[x, y, z, intensity]` in this frame's camera coordinates.
#[derive(Clone, Debug, Default)]
pub struct Template {
    /// Pyramid level the points were taken from.
    pub pyramid_level: usize,
    /// Valid points of that level, every `stride`-th pixel (at most the step's
    /// `max_points` of them, chosen by `select`), row-major.
    pub points: Vec<[f32; 4]>,
}

/// A frame made ready for tracking: reusable as current, previous or reference.
#[derive(Clone, Debug, Default)]
pub struct PreparedFrame {
    /// Capture time in seconds.
    pub timestamp: f64,
    /// Whether the depth was turned to the intensity's time
    /// ([`Preparer::prepare_turned_into`]).
    pub depth_time: DepthTime,
    /// Image pyramid, full resolution first.
    pub levels: Vec<ImageLevel>,
    /// Template points, one entry per step of the motion schedule, of a frame
    /// prepared whole (empty for a frame prepared for lookup: read
    /// [`Self::templates`]).
    pub templates: Vec<Template>,
    /// Unit normals of the full-resolution pixels (NaN where unknown), oriented
    /// towards the camera: the average of the axis and diagonal normals. Empty when
    /// the preparer keeps none ([`Preparer::set_normals`]).
    pub normals: Vec<[f32; 3]>,
    /// Number of full-resolution pixels with depth after filtering.
    pub valid_depth: usize,
    /// Number of full-resolution pixels with depth whose intensity gradient
    /// (`|Ix| + |Iy|`, intensity in [0, 1] per pixel) is at least [`TEXTURE_GRADIENT`]:
    /// how much there is for the photometric residual to hold on to.
    pub textured_pixels: usize,
    /// Pixels the normal filter removed.
    pub removed_by_normal: usize,
    /// Pixels the contour filter removed.
    pub removed_by_contour: usize,
    /// The full-resolution intensity and filtered depth, kept only when the schedule
    /// does not track level 0 (its samples are then not built): what
    /// [`Self::for_each_point`] reads instead.
    base: pyramid::Planes,
    /// Prepared for lookup only ([`Config::lookup_depth`]): the templates, normals,
    /// removal counts and filtered planes are in [`Self::reference_side`], finished
    /// by [`Preparer::finish`]; `valid_depth` counts the lookup depth.
    light: bool,
    /// The raw planes of a frame prepared for lookup, to finish it from.
    raw: side::RawPlanes,
    /// The reference side of a frame prepared for lookup.
    reference: side::ReferenceCell,
}

impl PreparedFrame {
    /// An empty frame with every buffer reserved at its full size for `config`, so
    /// that preparing into it never allocates (frame pools create their frames so).
    pub fn for_config(config: &Config) -> PreparedFrame {
        let cams = level_cameras(config);
        let tracked = tracked_levels(config);
        let levels = cams
            .iter()
            .zip(&tracked)
            .map(|(c, &t)| ImageLevel {
                camera: Some(*c),
                samples: Vec::with_capacity(if t { c.pixels() } else { 0 }),
            })
            .collect();
        let base_pixels = if tracked[0] {
            0
        } else {
            config.camera.pixels()
        };
        let templates = config
            .motion
            .levels
            .iter()
            .map(|l| Template {
                pyramid_level: l.pyramid_level,
                points: Vec::with_capacity(template_capacity(&cams[l.pyramid_level], l.stride)),
            })
            .collect();
        let light = side::lookup_depth(config).is_some();
        let mut frame = PreparedFrame {
            levels,
            normals: Vec::with_capacity(if light { 0 } else { config.camera.pixels() }),
            base: pyramid::Planes {
                intensity: Vec::with_capacity(base_pixels),
                depth: Vec::with_capacity(base_pixels),
            },
            ..PreparedFrame::default()
        };
        if light {
            frame.reserve_side(config, templates);
        } else {
            frame.templates = templates;
        }
        frame
    }

    /// Visits every `stride`-th valid full-resolution pixel as
    /// `(point in camera coordinates, unit normal or NaN, intensity 0..=255)`.
    pub fn for_each_point(&self, stride: usize, mut f: impl FnMut([f32; 3], [f32; 3], u8)) {
        let Some(level) = self.levels.first() else {
            return;
        };
        let cam = level.camera();
        let (w, h) = (cam.width, cam.height);
        let (fx, fy, cx, cy) = (cam.fx as f32, cam.fy as f32, cam.cx as f32, cam.cy as f32);
        let stride = stride.max(1);
        // A frame prepared for lookup gives its reference side's filtered planes and
        // normals once finished, its lookup planes before.
        let side = self.reference_side().filter(|s| s.is_finished());
        let (base, normals) = match &side {
            Some(s) => (Some(&s.base), &s.normals),
            None => (
                (level.samples.is_empty()).then_some(&self.base),
                &self.normals,
            ),
        };
        // Level 0's samples when it is tracked, else the planes kept in their stead:
        // the same intensity and depth.
        let at = |i: usize| match base {
            None => (level.samples[i][D], level.samples[i][I]),
            Some(b) => (b.depth[i], b.intensity[i]),
        };
        if base.is_some_and(|b| b.depth.len() != w * h) {
            return;
        }
        for y in (0..h).step_by(stride) {
            for x in (0..w).step_by(stride) {
                let (z, intensity) = at(y * w + x);
                if z.is_finite() {
                    let p = [(x as f32 - cx) / fx * z, (y as f32 - cy) / fy * z, z];
                    let n = normals.get(y * w + x).copied().unwrap_or([f32::NAN; 3]);
                    f(p, n, (intensity * 255.0).round().clamp(0.0, 255.0) as u8);
                }
            }
        }
    }
}

/// Prepares frames for one camera and configuration, reusing its scratch buffers
/// and the output's buffers so that a warm preparer does not allocate.
#[derive(Clone, Debug)]
pub struct Preparer {
    camera: Camera,
    filter: FilterConfig,
    schedule: Vec<MotionLevel>,
    pyramid_depth: usize,
    /// Per pyramid level: whether a step of the schedule tracks it (only those get
    /// samples).
    tracked: Vec<bool>,
    /// Depth in metres, missing as 0, padded by the bilateral radius on every side.
    padded_depth: Vec<f32>,
    /// Smoothed depth in metres, NaN where missing.
    smoothed: Vec<f32>,
    /// Bilateral spatial weights, row-major over the window.
    spatial: Vec<f32>,
    /// A lookup frame whose finest tracked level is level 1 (640x480 under the
    /// default schedule): its bilateral filter runs on level 1, with this window
    /// ([`side::half_bilateral`]), its spatial weights and its padded depth.
    half: Option<(BilateralConfig, Vec<f32>)>,
    padded_half: Vec<f32>,
    /// `(x - cx) / fx` per column and `(y - cy) / fy` per row of level 0.
    ray_x: Vec<f32>,
    ray_y: Vec<f32>,
    /// Per pixel: dropped by the normal filter (1) or not (0).
    normal_drop: Vec<u8>,
    /// Per pixel: the contour test fired (1) or not (0).
    contour_seed: Vec<u8>,
    /// Two rows of masks for applying them.
    mask_rows: Vec<u8>,
    /// Compact intensity (in [0, 1]) and filtered depth (NaN where missing) of every
    /// pyramid level, full resolution first.
    planes: Vec<pyramid::Planes>,
    /// Scratch of the template point selection.
    selector: select::Selector,
    /// Whether frames get their normals ([`Preparer::set_normals`]).
    keep_normals: bool,
    /// Frames prepared for lookup only, with this depth ([`Config::lookup_depth`]).
    lookup: Option<LookupDepth>,
    /// Scratch levels of [`Preparer::finish`] (samples only for steps with a point
    /// budget).
    side_levels: Vec<ImageLevel>,
    /// Raw depth turned to the intensity's time ([`Preparer::prepare_turned_into`]).
    turned: Vec<u16>,
}

impl Preparer {
    /// A preparer for `config` (validated by the caller).
    pub fn new(config: &Config) -> Self {
        let spatial = config
            .filter
            .bilateral
            .map_or(Vec::new(), |b| spatial_weights(&b));
        let lookup = side::lookup_depth(config);
        let tracked = tracked_levels(config);
        let half = side::half_bilateral(config, &tracked).map(|b| (b, spatial_weights(&b)));
        let c = config.camera;
        let (ray_x, ray_y) = rays(&c);
        Preparer {
            camera: c,
            filter: config.filter,
            schedule: config.motion.levels.clone(),
            pyramid_depth: config.pyramid_depth(),
            tracked,
            padded_depth: Vec::new(),
            smoothed: Vec::new(),
            spatial,
            half,
            padded_half: Vec::new(),
            ray_x,
            ray_y,
            normal_drop: Vec::new(),
            contour_seed: Vec::new(),
            mask_rows: Vec::new(),
            planes: Vec::new(),
            selector: select::Selector::default(),
            keep_normals: true,
            lookup,
            side_levels: Vec::new(),
            turned: Vec::new(),
        }
    }

    /// A preparer that prepares every frame whole, whatever
    /// [`Config::lookup_depth`] says (a point cloud's frames; the tracker's
    /// [`Preparer::finish`]).
    pub fn whole(config: &Config) -> Self {
        Preparer {
            lookup: None,
            ..Preparer::new(config)
        }
    }

    /// The intrinsics frames are prepared with.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Prepares the next frames with new intrinsics of the same image size: a zoom,
    /// a refocus, or a calibration the camera reports per frame. Each prepared frame
    /// carries its own intrinsics at every level, and MOTION projects with the target
    /// frame's, so a frame prepared before the change still registers with one
    /// prepared after it. Fails (and changes nothing) on invalid intrinsics or
    /// another image size.
    pub fn set_intrinsics(&mut self, camera: Camera) -> Result<()> {
        camera.validate_change_from(&self.camera)?;
        (self.ray_x, self.ray_y) = rays(&camera);
        self.camera = camera;
        Ok(())
    }

    /// Whether the frames prepared from now on get their normals
    /// ([`PreparedFrame::normals`]; on by default). Only the point cloud reads them:
    /// without them the normal and contour filters drop the same pixels and every
    /// other output is the same, and preparing skips the averaged normal and its
    /// 12 bytes a pixel; `normals` is then empty and [`PreparedFrame::for_each_point`]
    /// gives NaN normals.
    pub fn set_normals(&mut self, on: bool) {
        self.keep_normals = on;
    }

    /// Prepares `view` into `out`, reusing `out`'s buffers. Fails only on a frame
    /// whose sizes do not match the camera. Under keyframe tracking with a
    /// [`LookupDepth`] other than `Filtered`, the frame is prepared only as far as
    /// the warp samples it (its lookup levels); its reference side is left to
    /// [`Preparer::finish`].
    pub fn prepare_into(&mut self, view: FrameView<'_>, out: &mut PreparedFrame) -> Result<()> {
        self.prepare_turned_into(view, DepthTime::Same, out)
    }

    /// [`Preparer::prepare_into`] for a view whose sizes were checked.
    pub(super) fn prepare_checked(
        &mut self,
        view: FrameView<'_>,
        out: &mut PreparedFrame,
    ) -> Result<()> {
        out.timestamp = view.timestamp;
        if let Some(depth) = self.lookup {
            self.prepare_lookup(view, depth, out);
            return Ok(());
        }
        out.light = false;
        let counts = self.filtered_planes(view, None, &mut out.normals);
        out.removed_by_normal = counts.by_normal;
        out.removed_by_contour = counts.by_contour;
        out.valid_depth = counts.valid;
        self.lookup_levels(out, 0);
        self.build_templates(&out.levels, &mut out.templates);
        Ok(())
    }

    /// Passes 1 to 4: raw depth to metres, the bilateral filter, normals, the removal
    /// masks, applied into level 0's compact planes (`self.planes[0]`); `normals` is
    /// filled when the preparer keeps them. `smoothed`: passes 1 and 2 done already
    /// (a lookup frame's filtered depth, [`side::RawPlanes::smoothed`]).
    fn filtered_planes(
        &mut self,
        view: FrameView<'_>,
        smoothed: Option<&[f32]>,
        normals: &mut Vec<[f32; 3]>,
    ) -> removal::Counts {
        let (w, h) = (self.camera.width, self.camera.height);
        match smoothed {
            Some(s) => {
                self.smoothed.clear();
                self.smoothed.extend_from_slice(s);
            }
            None => self.smooth_depth(view.depth, false),
        }
        let angles = removal::Angles {
            cos_n: self
                .filter
                .normal_max_angle_deg
                .map(|a| (a.to_radians().cos()) as f32),
            sin_g: self
                .filter
                .contour_angle_deg
                .map(|a| (a.to_radians().sin()) as f32),
        };
        removal::normals_and_seeds(
            &self.smoothed,
            &self.ray_x,
            &self.ray_y,
            angles,
            self.keep_normals,
            normals,
            &mut self.normal_drop,
            &mut self.contour_seed,
        );
        self.planes
            .resize_with(self.pyramid_depth + 1, pyramid::Planes::default);
        debug_assert_eq!(self.smoothed.len(), w * h);
        removal::apply_masks(
            view.intensity,
            &self.smoothed,
            &self.normal_drop,
            &self.contour_seed,
            w,
            angles.cos_n.is_some(),
            normals,
            &mut self.planes[0],
            &mut self.mask_rows,
        )
    }

    /// Raw depth to metres (out-of-range depth is missing) into `self.smoothed`,
    /// smoothed by the configured bilateral filter when there is one (for a lookup
    /// frame, `lookup`, only with [`LookupDepth::Bilateral`]).
    fn smooth_depth(&mut self, depth: &[u16], lookup: bool) {
        let b = match self.lookup {
            Some(LookupDepth::Raw) if lookup => None,
            _ => self.filter.bilateral,
        };
        let spatial = self.spatial.as_slice();
        let (w, h) = (self.camera.width, self.camera.height);
        let range = self.depth_range();
        self.smoothed.resize(w * h, f32::NAN);
        match b {
            Some(b) => {
                bilateral::load_padded(depth, w, h, b.radius, range, &mut self.padded_depth);
                bilateral::filter(
                    &self.padded_depth,
                    spatial,
                    w,
                    b.radius,
                    b.sigma_depth_rel,
                    &mut self.smoothed,
                );
            }
            None => bilateral::load_plain(depth, range, &mut self.smoothed),
        }
    }

    /// How raw depth becomes metres.
    fn depth_range(&self) -> bilateral::DepthRange {
        bilateral::DepthRange {
            scale: 1.0 / self.camera.depth_scale as f32,
            lo: self.filter.min_depth_m as f32,
            hi: self.filter.max_depth_m as f32,
        }
    }

    /// Pass 5: from level 0's planes, the pyramid's planes and the samples of every
    /// tracked level, the texture count; level 0's planes go to `out.base` when level
    /// 0 is not tracked. The planes of levels up to `made` are there already.
    fn lookup_levels(&mut self, out: &mut PreparedFrame, made: usize) {
        out.levels
            .resize_with(self.pyramid_depth + 1, ImageLevel::default);
        let mut level_cam = self.camera;
        for l in 0..=self.pyramid_depth {
            if l > made {
                let (head, tail) = self.planes.split_at_mut(l);
                pyramid::downsample(
                    &head[l - 1],
                    level_cam.width,
                    &mut tail[0],
                    level_cam.half(),
                );
            }
            if l > 0 {
                level_cam = level_cam.half();
            }
            let level = &mut out.levels[l];
            level.camera = Some(level_cam);
            // A level no step tracks needs no samples (at 640x480 the default
            // schedule's finest step is on level 1): only level 0's texture count.
            if self.tracked[l] {
                let textured =
                    pyramid::samples(&self.planes[l], level_cam.width, &mut level.samples);
                if l == 0 {
                    out.textured_pixels = textured;
                }
            } else {
                level.samples.clear();
                if l == 0 {
                    out.textured_pixels = pyramid::textured(&self.planes[0], level_cam.width);
                }
            }
        }
        if !self.tracked[0] {
            // The frame keeps level 0's planes for its points; the preparer takes the
            // frame's old buffers (reserved by `for_config`) for the next frame.
            std::mem::swap(&mut self.planes[0], &mut out.base);
        }
    }

    /// Pass 6: the template of every schedule step from the planes (a step with a
    /// point budget selects from `levels`' samples).
    fn build_templates(&mut self, levels: &[ImageLevel], templates: &mut Vec<Template>) {
        templates.resize_with(self.schedule.len(), Template::default);
        for (step, t) in self.schedule.iter().zip(templates.iter_mut()) {
            let l = step.pyramid_level;
            // A frame made by `Default` (not `for_config`) learns its levels here.
            t.pyramid_level = l;
            match step.max_points {
                None => build_template(&self.planes[l], levels[l].camera(), step.stride, t),
                Some(budget) => {
                    build_selected_template(&levels[l], step.stride, budget, &mut self.selector, t)
                }
            }
        }
    }
}

/// The bilateral filter's spatial weights, row-major over its window.
fn spatial_weights(b: &crate::config::BilateralConfig) -> Vec<f32> {
    let r = b.radius as isize;
    let s2 = 2.0 * b.sigma_space_px * b.sigma_space_px;
    let mut v = Vec::new();
    for dy in -r..=r {
        for dx in -r..=r {
            v.push((-((dx * dx + dy * dy) as f32) / s2).exp());
        }
    }
    v
}

/// `(1/fx, 1/fy, cx, cy)` in `f32`: a pixel `(x, y)` at depth `z` back-projects to
/// `((x - cx) z / fx, (y - cy) z / fy, z)`.
fn back_projection(c: &Camera) -> (f32, f32, f32, f32) {
    (
        1.0 / c.fx as f32,
        1.0 / c.fy as f32,
        c.cx as f32,
        c.cy as f32,
    )
}

/// `(x - cx) / fx` per column and `(y - cy) / fy` per row of `c`.
fn rays(c: &Camera) -> (Vec<f32>, Vec<f32>) {
    let (ifx, ify, cx, cy) = back_projection(c);
    (
        (0..c.width).map(|x| (x as f32 - cx) * ifx).collect(),
        (0..c.height).map(|y| (y as f32 - cy) * ify).collect(),
    )
}

/// The intrinsics of every pyramid level of `config`, full resolution first.
fn level_cameras(config: &Config) -> Vec<Camera> {
    let mut cams = vec![config.camera];
    for _ in 0..config.pyramid_depth() {
        let half = cams[cams.len() - 1].half();
        cams.push(half);
    }
    cams
}

/// Per pyramid level of `config`, full resolution first: whether a step of its
/// schedule runs on it.
pub(crate) fn tracked_levels(config: &Config) -> Vec<bool> {
    let mut tracked = vec![false; config.pyramid_depth() + 1];
    for l in &config.motion.levels {
        tracked[l.pyramid_level] = true;
    }
    tracked
}
