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

use crate::camera::{Camera, FrameView};
use crate::config::{Config, FilterConfig, MotionLevel};
use crate::error::Result;

use rayon::prelude::*;

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
    /// Valid points of that level, every `stride`-th pixel.
    pub points: Vec<[f32; 4]>,
}

/// A frame made ready for tracking: reusable as current, previous or reference.
#[derive(Clone, Debug, Default)]
pub struct PreparedFrame {
    /// Capture time in seconds.
    pub timestamp: f64,
    /// Image pyramid, full resolution first.
    pub levels: Vec<ImageLevel>,
    /// Template points, one entry per step of the motion schedule.
    pub templates: Vec<Template>,
    /// Unit normals of the full-resolution pixels (NaN where unknown), oriented
    /// towards the camera: the average of the axis and diagonal normals.
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
}

impl PreparedFrame {
    /// An empty frame with every buffer reserved at its full size for `config`, so
    /// that preparing into it never allocates (frame pools create their frames so).
    pub fn for_config(config: &Config) -> PreparedFrame {
        let cams = level_cameras(config);
        let levels = cams
            .iter()
            .map(|c| ImageLevel {
                camera: Some(*c),
                samples: Vec::with_capacity(c.pixels()),
            })
            .collect();
        let templates = config
            .motion
            .levels
            .iter()
            .map(|l| Template {
                pyramid_level: l.pyramid_level,
                points: Vec::with_capacity(template_capacity(&cams[l.pyramid_level], l.stride)),
            })
            .collect();
        PreparedFrame {
            levels,
            templates,
            normals: Vec::with_capacity(config.camera.pixels()),
            ..PreparedFrame::default()
        }
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
        for y in (0..h).step_by(stride) {
            for x in (0..w).step_by(stride) {
                let s = &level.samples[y * w + x];
                let z = s[D];
                if z.is_finite() {
                    let p = [(x as f32 - cx) / fx * z, (y as f32 - cy) / fy * z, z];
                    let n = self
                        .normals
                        .get(y * w + x)
                        .copied()
                        .unwrap_or([f32::NAN; 3]);
                    f(p, n, (s[I] * 255.0).round().clamp(0.0, 255.0) as u8);
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
    depth: Vec<f32>,
    smoothed: Vec<f32>,
    points: Vec<[f32; 3]>,
    keep: Vec<bool>,
    normal_drop: Vec<bool>,
    contour_drop: Vec<bool>,
    contour_seed: Vec<bool>,
    dilate_tmp: Vec<bool>,
    padded_depth: Vec<f32>,
    spatial: Vec<f32>,
}

impl Preparer {
    /// A preparer for `config` (validated by the caller).
    pub fn new(config: &Config) -> Self {
        let spatial = match config.filter.bilateral {
            Some(b) => {
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
            None => Vec::new(),
        };
        Preparer {
            camera: config.camera,
            filter: config.filter,
            schedule: config.motion.levels.clone(),
            pyramid_depth: config.pyramid_depth(),
            depth: Vec::new(),
            smoothed: Vec::new(),
            points: Vec::new(),
            keep: Vec::new(),
            normal_drop: Vec::new(),
            contour_drop: Vec::new(),
            contour_seed: Vec::new(),
            dilate_tmp: Vec::new(),
            padded_depth: Vec::new(),
            spatial,
        }
    }

    /// Prepares `view` into `out`, reusing `out`'s buffers. Fails only on a frame
    /// whose sizes do not match the camera.
    pub fn prepare_into(&mut self, view: FrameView<'_>, out: &mut PreparedFrame) -> Result<()> {
        view.validate(&self.camera)?;
        let cam = self.camera;
        let n = cam.pixels();
        out.timestamp = view.timestamp;

        // Raw units to metres; out-of-range depth is missing.
        let scale = 1.0 / cam.depth_scale as f32;
        let (lo, hi) = (
            self.filter.min_depth_m as f32,
            self.filter.max_depth_m as f32,
        );
        self.depth.clear();
        self.depth.extend(view.depth.iter().map(|&d| {
            let z = d as f32 * scale;
            if d != 0 && z >= lo && z <= hi {
                z
            } else {
                f32::NAN
            }
        }));

        self.smoothed.resize(n, f32::NAN);
        match self.filter.bilateral {
            Some(b) => self.bilateral(b.radius, b.sigma_depth_rel),
            None => self.smoothed.copy_from_slice(&self.depth),
        }
        self.back_project();
        let (removed_n, removed_c) = self.removal_filters(&mut out.normals);
        out.removed_by_normal = removed_n;
        out.removed_by_contour = removed_c;

        // Level 0 from the filtered depth and the intensity.
        out.levels
            .resize_with(self.pyramid_depth + 1, ImageLevel::default);
        {
            let l0 = &mut out.levels[0];
            l0.camera = Some(cam);
            l0.samples.clear();
            l0.samples.extend(
                view.intensity
                    .iter()
                    .zip(&self.smoothed)
                    .zip(&self.keep)
                    .map(|((&i, &z), &k)| {
                        let z = if k { z } else { f32::NAN };
                        [i as f32 * (1.0 / 255.0), 0.0, 0.0, z, 0.0, 0.0, 0.0, 0.0]
                    }),
            );
            out.valid_depth = l0.samples.iter().filter(|s| s[D].is_finite()).count();
        }
        for l in 1..=self.pyramid_depth {
            let (head, tail) = out.levels.split_at_mut(l);
            downsample(&head[l - 1], &mut tail[0]);
        }
        for level in &mut out.levels {
            gradients(level);
        }
        out.textured_pixels = out.levels[0]
            .samples
            .iter()
            .filter(|s| s[D].is_finite() && s[1].abs() + s[2].abs() >= TEXTURE_GRADIENT)
            .count();

        out.templates
            .resize_with(self.schedule.len(), Template::default);
        for (step, t) in self.schedule.iter().zip(&mut out.templates) {
            build_template(&out.levels[step.pyramid_level], step.stride, t);
        }
        Ok(())
    }

    /// Bilateral filter on `self.depth` into `self.smoothed`, over valid pixels
    /// only. The range weight is `(1 − x/4)⁴` for `x = Δz² / (2σ²)`, clamped at 0: it
    /// follows `exp(−x)` closely near 0, is exactly 0 beyond 2.8σ, and keeps the inner
    /// loop free of branches and table lookups. σ is a fraction of the centre depth.
    /// Missing neighbours enter as depth 0, whose range weight is 0.
    fn bilateral(&mut self, radius: usize, sigma_rel: f32) {
        let (w, h) = (self.camera.width, self.camera.height);
        let side = 2 * radius + 1;
        // Depth with missing pixels as 0, padded by `radius` zeros on every side: a
        // tap outside the image, like a missing pixel, gets range weight exactly 0
        // (config validation keeps σ small enough for that), so the padded filter
        // adds the same terms in the same order as one clipped at the border.
        let pw = w + 2 * radius;
        self.padded_depth.clear();
        self.padded_depth.resize(pw * (h + 2 * radius), 0.0);
        for (dst, src) in self.padded_depth[radius * pw..]
            .chunks_exact_mut(pw)
            .zip(self.depth.chunks_exact(w))
        {
            for (d, &z) in dst[radius..radius + w].iter_mut().zip(src) {
                *d = if z.is_finite() { z } else { 0.0 };
            }
        }
        let (padded, spatial) = (&self.padded_depth, &self.spatial);
        rows(&mut self.smoothed, w, |y, out| {
            // Blocks of pixels, each filtered tap after tap: the inner loop runs over
            // the block's pixels, which the compiler vectorises.
            const B: usize = 64;
            let centre = &padded[(y + radius) * pw + radius..][..w];
            for bx in (0..w).step_by(B) {
                let n = B.min(w - bx);
                let zc = &centre[bx..bx + n];
                let mut quarter_inv = [0.0f32; B];
                for (q, &z) in quarter_inv.iter_mut().zip(zc) {
                    let s = sigma_rel * z;
                    *q = 0.25 / (2.0 * s * s);
                }
                let (mut acc, mut wsum) = ([0.0f32; B], [0.0f32; B]);
                for dy in 0..side {
                    let row = &padded[(y + dy) * pw + bx..];
                    for dx in 0..side {
                        let ws = spatial[dy * side + dx];
                        let src = &row[dx..dx + n];
                        for i in 0..n {
                            let z = src[i];
                            let d = z - zc[i];
                            let t = (1.0 - d * d * quarter_inv[i]).max(0.0);
                            let t2 = t * t;
                            let wgt = ws * t2 * t2;
                            acc[i] += wgt * z;
                            wsum[i] += wgt;
                        }
                    }
                }
                for i in 0..n {
                    out[bx + i] = if zc[i] == 0.0 {
                        f32::NAN
                    } else {
                        acc[i] / wsum[i]
                    };
                }
            }
        });
    }

    /// Back-projects `self.smoothed` into `self.points` (NaN where missing).
    fn back_project(&mut self) {
        let c = self.camera;
        let (w, h) = (c.width, c.height);
        let (ifx, ify, cx, cy) = (
            1.0 / c.fx as f32,
            1.0 / c.fy as f32,
            c.cx as f32,
            c.cy as f32,
        );
        self.points.resize(w * h, [f32::NAN; 3]);
        for y in 0..h {
            let ry = (y as f32 - cy) * ify;
            for x in 0..w {
                let z = self.smoothed[y * w + x];
                self.points[y * w + x] = [(x as f32 - cx) * ifx * z, ry * z, z];
            }
        }
    }

    /// Normal-based and contour-based removal; fills `self.keep` and `normals`.
    /// Returns how many pixels each filter removed.
    fn removal_filters(&mut self, normals: &mut Vec<[f32; 3]>) -> (usize, usize) {
        let (w, h) = (self.camera.width, self.camera.height);
        let n = w * h;
        normals.clear();
        normals.resize(n, [f32::NAN; 3]);
        self.keep.clear();
        self.keep
            .extend(self.points.iter().map(|p| p[2].is_finite()));
        let cos_n = self
            .filter
            .normal_max_angle_deg
            .map(|a| (a.to_radians().cos()) as f32);
        let sin_g = self
            .filter
            .contour_angle_deg
            .map(|a| (a.to_radians().sin()) as f32);
        let p = &self.points;
        let normal_drop = &mut self.normal_drop;
        let contour_drop = &mut self.contour_drop;
        normal_drop.clear();
        normal_drop.resize(n, false);
        // First the pixels where the contour test fires (`contour_seed`), then their
        // 3x3 neighbourhoods (`contour_drop`), so that every row is written by one task.
        let contour_seed = &mut self.contour_seed;
        contour_seed.clear();
        contour_seed.resize(n, false);
        let interior = |y: usize| y >= 1 && y + 1 < h;
        normals
            .par_chunks_mut(w)
            .zip(normal_drop.par_chunks_mut(w))
            .zip(contour_seed.par_chunks_mut(w))
            .enumerate()
            .with_min_len(rows_per_task(w))
            .for_each(|(y, ((normals, normal_drop), seed))| {
                if !interior(y) {
                    return;
                }
                for x in 1..w - 1 {
                    let i = y * w + x;
                    let c = p[i];
                    if !c[2].is_finite() {
                        continue;
                    }
                    let (l, r, u, d) = (p[i - 1], p[i + 1], p[i - w], p[i + w]);
                    let (ul, ur, dl, dr) = (p[i - w - 1], p[i - w + 1], p[i + w - 1], p[i + w + 1]);
                    let all = [l, r, u, d, ul, ur, dl, dr]
                        .iter()
                        .all(|q| q[2].is_finite());
                    if all {
                        let np = cross(sub(r, l), sub(d, u));
                        let nd = cross(sub(dr, ul), sub(dl, ur));
                        if let (Some(np), Some(nd)) = (unit(np), unit(nd)) {
                            let cosang = dot(np, nd);
                            if cos_n.is_some_and(|cn| cosang < cn) {
                                normal_drop[x] = true;
                            } else if let Some(mut avg) = unit(add(np, nd)) {
                                if dot(avg, c) > 0.0 {
                                    avg = [-avg[0], -avg[1], -avg[2]];
                                }
                                normals[x] = avg;
                            }
                        } else if cos_n.is_some() {
                            normal_drop[x] = true;
                        }
                    } else if cos_n.is_some() {
                        // The neighbourhood is incomplete: the normals cannot vouch for it.
                        normal_drop[x] = true;
                    }
                    if let Some(sg) = sin_g
                        && l[2].is_finite()
                        && u[2].is_finite()
                    {
                        let nc = cross(sub(l, c), sub(u, c));
                        let nn = dot(nc, nc).sqrt();
                        let pn = dot(c, c).sqrt();
                        seed[x] = nn > 0.0 && (dot(nc, c) / (nn * pn)).abs() <= sg;
                    }
                }
            });
        dilate3x3(&self.contour_seed, &mut self.dilate_tmp, contour_drop, w);
        // Border pixels have no complete neighbourhood either.
        if cos_n.is_some() {
            for x in 0..w {
                normal_drop[x] = true;
                normal_drop[(h - 1) * w + x] = true;
            }
            for y in 0..h {
                normal_drop[y * w] = true;
                normal_drop[y * w + w - 1] = true;
            }
        }
        let (mut by_normal, mut by_contour) = (0, 0);
        for i in 0..n {
            if self.keep[i] {
                if normal_drop[i] {
                    by_normal += 1;
                    self.keep[i] = false;
                } else if contour_drop[i] {
                    by_contour += 1;
                    self.keep[i] = false;
                }
            }
            if !self.keep[i] {
                normals[i] = [f32::NAN; 3];
            }
        }
        (by_normal, by_contour)
    }
}

/// `dst` = the 3x3 dilation of the mask `src` of row width `w` (`tmp` is scratch):
/// a horizontal pass, then a vertical one, each row written by one task.
fn dilate3x3(src: &[bool], tmp: &mut Vec<bool>, dst: &mut Vec<bool>, w: usize) {
    let n = src.len();
    tmp.clear();
    tmp.resize(n, false);
    rows(tmp, w, |y, out| {
        let s = &src[y * w..(y + 1) * w];
        if w < 3 {
            let any = s.contains(&true);
            out.fill(any);
            return;
        }
        out[0] = s[0] | s[1];
        out[w - 1] = s[w - 2] | s[w - 1];
        for (o, ((a, b), c)) in out[1..w - 1]
            .iter_mut()
            .zip(s[..w - 2].iter().zip(&s[1..w - 1]).zip(&s[2..]))
        {
            *o = *a | *b | *c;
        }
    });
    let h = n / w.max(1);
    dst.clear();
    dst.resize(n, false);
    let tmp = &*tmp;
    rows(dst, w, |y, out| {
        let row = |yy: usize| &tmp[yy * w..(yy + 1) * w];
        let mid = row(y);
        let up = row(y.saturating_sub(1));
        let down = row((y + 1).min(h - 1));
        for (o, ((a, b), c)) in out.iter_mut().zip(up.iter().zip(mid).zip(down)) {
            *o = *a | *b | *c;
        }
    });
}

/// 2x2 downsampling: mean intensity; mean depth of the valid pixels when they agree
/// within 3 % (otherwise missing), so depth is never blurred across edges or holes.
fn downsample(src: &ImageLevel, dst: &mut ImageLevel) {
    let sc = src.camera();
    let dc = sc.half();
    let (sw, w, h) = (sc.width, dc.width, dc.height);
    dst.camera = Some(dc);
    dst.samples.clear();
    dst.samples.reserve(w * h);
    for y in 0..h {
        for x in 0..w {
            let i = 2 * y * sw + 2 * x;
            let q = [
                src.samples[i],
                src.samples[i + 1],
                src.samples[i + sw],
                src.samples[i + sw + 1],
            ];
            let intensity = (q[0][I] + q[1][I] + q[2][I] + q[3][I]) * 0.25;
            let (mut sum, mut cnt, mut lo, mut hi) = (0.0f32, 0u32, f32::INFINITY, 0.0f32);
            for s in &q {
                let z = s[D];
                if z.is_finite() {
                    sum += z;
                    cnt += 1;
                    lo = lo.min(z);
                    hi = hi.max(z);
                }
            }
            let z = if cnt > 0 && hi - lo <= 0.03 * lo {
                sum / cnt as f32
            } else {
                f32::NAN
            };
            dst.samples
                .push([intensity, 0.0, 0.0, z, 0.0, 0.0, 0.0, 0.0]);
        }
    }
}

/// Central-difference gradients of intensity and depth, in units per pixel. At the
/// border the intensity gradient is 0 and the depth gradient missing.
fn gradients(level: &mut ImageLevel) {
    let c = *level.camera();
    let (w, h) = (c.width, c.height);
    let s = &mut level.samples;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if x == 0 || y == 0 || x == w - 1 || y == h - 1 {
                s[i][1] = 0.0;
                s[i][2] = 0.0;
                s[i][4] = f32::NAN;
                s[i][5] = f32::NAN;
                continue;
            }
            s[i][1] = 0.5 * (s[i + 1][I] - s[i - 1][I]);
            s[i][2] = 0.5 * (s[i + w][I] - s[i - w][I]);
            s[i][4] = 0.5 * (s[i + 1][D] - s[i - 1][D]);
            s[i][5] = 0.5 * (s[i + w][D] - s[i - w][D]);
        }
    }
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

/// The most template points a level of camera `c` sampled every `stride` pixels has.
fn template_capacity(c: &Camera, stride: usize) -> usize {
    let s = stride.max(1);
    (c.width / s + 1) * (c.height / s + 1)
}

/// The most template points any step of `config`'s schedule can have.
pub fn max_template_points(config: &Config) -> usize {
    let cams = level_cameras(config);
    config
        .motion
        .levels
        .iter()
        .map(|l| template_capacity(&cams[l.pyramid_level], l.stride))
        .max()
        .unwrap_or(0)
}

/// Every `stride`-th valid pixel of `level` (away from the border) as a template point.
fn build_template(level: &ImageLevel, stride: usize, t: &mut Template) {
    let c = level.camera();
    let (w, h) = (c.width, c.height);
    let (ifx, ify, cx, cy) = (
        1.0 / c.fx as f32,
        1.0 / c.fy as f32,
        c.cx as f32,
        c.cy as f32,
    );
    t.points.clear();
    let start = (stride / 2).max(1);
    for y in (start..h - 1).step_by(stride) {
        let ry = (y as f32 - cy) * ify;
        for x in (start..w - 1).step_by(stride) {
            let s = &level.samples[y * w + x];
            let z = s[D];
            if z.is_finite() {
                t.points.push([(x as f32 - cx) * ifx * z, ry * z, z, s[I]]);
            }
        }
    }
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: [f32; 3]) -> Option<[f32; 3]> {
    let n = dot(a, a).sqrt();
    (n > 1e-12).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Mode, Preset};

    /// The bilateral filter as first written: pixel after pixel, its window clipped at
    /// the image border.
    fn clipped_reference(
        depth: &[f32],
        w: usize,
        h: usize,
        spatial: &[f32],
        r: usize,
        sr: f32,
    ) -> Vec<f32> {
        let side = 2 * r + 1;
        let z0: Vec<f32> = depth
            .iter()
            .map(|&z| if z.is_finite() { z } else { 0.0 })
            .collect();
        let mut out = vec![f32::NAN; w * h];
        for y in 0..h {
            for x in 0..w {
                let zc = z0[y * w + x];
                if zc == 0.0 {
                    continue;
                }
                let s = sr * zc;
                let quarter_inv = 0.25 / (2.0 * s * s);
                let (mut acc, mut wsum) = (0.0f32, 0.0f32);
                for yy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                    for xx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                        let z = z0[yy * w + xx];
                        let d = z - zc;
                        let t = (1.0 - d * d * quarter_inv).max(0.0);
                        let t2 = t * t;
                        let wgt = spatial[(yy + r - y) * side + (xx + r - x)] * t2 * t2;
                        acc += wgt * z;
                        wsum += wgt;
                    }
                }
                out[y * w + x] = acc / wsum;
            }
        }
        out
    }

    #[test]
    fn blocked_bilateral_equals_the_clipped_filter_bit_for_bit() {
        // Sizes around the 64-pixel blocks, holes, depth steps and slopes.
        for (w, h, r, sr) in [
            (37, 23, 1, 0.02),
            (150, 41, 2, 0.02),
            (64, 9, 3, 0.05),
            (129, 17, 2, 0.35),
        ] {
            let camera = crate::Camera {
                width: w,
                height: h,
                fx: 100.0,
                fy: 100.0,
                cx: w as f64 / 2.0,
                cy: h as f64 / 2.0,
                depth_scale: 1000.0,
            };
            let mut config = Config::new(camera, Preset::Pc, Mode::L2);
            config.filter.bilateral = Some(crate::config::BilateralConfig {
                radius: r,
                sigma_space_px: 1.5,
                sigma_depth_rel: sr,
            });
            let mut p = Preparer::new(&config);
            let mut seed = 12345u32;
            p.depth = (0..w * h)
                .map(|i| {
                    seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    let (x, y) = (i % w, i / w);
                    if seed >> 28 == 0 || x == 5 {
                        f32::NAN
                    } else {
                        let step = if x > w / 2 { 1.2 } else { 0.0 };
                        0.8 + 0.01 * y as f32 + step + (seed >> 8) as f32 * 1e-9
                    }
                })
                .collect();
            p.smoothed = vec![0.0; w * h];
            p.bilateral(r, sr);
            let want = clipped_reference(&p.depth, w, h, &p.spatial, r, sr);
            for (i, (a, b)) in p.smoothed.iter().zip(&want).enumerate() {
                assert_eq!(
                    a.to_bits(),
                    b.to_bits(),
                    "{w}x{h} r {r}: pixel {i}: {a} vs {b}"
                );
            }
        }
    }
}
