//! The preparation as it was before it was fused into a few passes, kept to check
//! that the fused passes give the same frame bit for bit.
#![allow(clippy::all)]

use super::{D, I, ImageLevel, PreparedFrame, TEXTURE_GRADIENT, Template, rows, rows_per_task};
use crate::camera::{Camera, FrameView};
use crate::config::{Config, FilterConfig, MotionLevel};
use crate::error::Result;

use rayon::prelude::*;

/// Prepares frames for one camera and configuration, reusing its scratch buffers
/// and the output's buffers so that a warm preparer does not allocate.
#[derive(Clone, Debug)]
pub(super) struct OldPreparer {
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

impl OldPreparer {
    /// A preparer for `config` (validated by the caller).
    pub(super) fn new(config: &Config) -> Self {
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
        OldPreparer {
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
    pub(super) fn prepare_into(
        &mut self,
        view: FrameView<'_>,
        out: &mut PreparedFrame,
    ) -> Result<()> {
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
            t.pyramid_level = step.pyramid_level;
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
