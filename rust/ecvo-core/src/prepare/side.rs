//! Work by role (issue 46): under keyframe tracking a frame is first prepared only
//! as far as the warp samples it, its *lookup levels* (`Preparer::prepare_lookup`);
//! what only a reference reads, its *reference side* (the bilateral filter, the
//! normal and contour removal, the templates, the filtered planes and normals of
//! the point cloud), is finished once, from the raw planes the frame keeps, when the
//! tracker first registers a frame against it ([`Preparer::finish`]): a keyframe, or
//! the previous frame of a fall-back or a fusion. A frame that never becomes a
//! reference never pays for it.
//!
//! The reference side sits behind a lock in the frame, so a shared frame is
//! finished in place; finishing is a pure function of the raw planes, so poses do
//! not depend on which thread finishes a frame, or when.

use std::ops::Deref;
use std::sync::{PoisonError, RwLock, RwLockReadGuard};

use super::simd::multiversion;
use super::{PreparedFrame, Preparer, Template, bilateral, pyramid};
use crate::camera::{Camera, FrameView};
use crate::config::{BilateralConfig, Config, LookupDepth};

/// The raw planes a frame prepared for lookup keeps, to finish its reference side
/// later.
#[derive(Clone, Debug, Default)]
pub(crate) struct RawPlanes {
    pub intensity: Vec<u8>,
    pub depth: Vec<u16>,
    /// The depth through the bilateral filter in metres (NaN where missing) when the
    /// lookup levels were made from the very filter the reference side uses (full
    /// resolution): finishing takes it instead of filtering again, bit for bit the
    /// same. Empty otherwise.
    pub smoothed: Vec<f32>,
}

/// What only a reference reads, finished once ([`Preparer::finish`]).
#[derive(Clone, Debug, Default)]
pub struct ReferenceSide {
    /// Whether it was finished for the frame's current contents.
    finished: bool,
    /// Template points, one entry per step of the motion schedule.
    pub templates: Vec<Template>,
    /// Unit normals of the full-resolution pixels (empty unless kept).
    pub normals: Vec<[f32; 3]>,
    /// Pixels with depth after filtering and removal.
    pub valid_depth: usize,
    /// Pixels the normal filter removed.
    pub removed_by_normal: usize,
    /// Pixels the contour filter removed.
    pub removed_by_contour: usize,
    /// The filtered full-resolution planes, for the frame's points.
    pub(crate) base: pyramid::Planes,
}

impl ReferenceSide {
    /// Whether the side was finished.
    pub fn is_finished(&self) -> bool {
        self.finished
    }
}

/// The reference side of a frame prepared for lookup, behind a lock: finished in
/// place by whichever holder of the shared frame needs it first.
#[derive(Debug, Default)]
pub(crate) struct ReferenceCell(RwLock<ReferenceSide>);

impl Clone for ReferenceCell {
    fn clone(&self) -> Self {
        ReferenceCell(RwLock::new(self.read().clone()))
    }
}

impl ReferenceCell {
    /// The side, for reading (a poisoned lock still holds a whole side: finishing
    /// sets `finished` last).
    pub(crate) fn read(&self) -> RwLockReadGuard<'_, ReferenceSide> {
        self.0.read().unwrap_or_else(PoisonError::into_inner)
    }

    /// The side, for a holder with exclusive access.
    pub(crate) fn get_mut(&mut self) -> &mut ReferenceSide {
        self.0.get_mut().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A frame's templates: its own, or its finished reference side's (empty while
/// unfinished).
pub enum Templates<'a> {
    /// A frame prepared whole.
    Whole(&'a [Template]),
    /// A frame prepared for lookup: its reference side.
    Side(RwLockReadGuard<'a, ReferenceSide>),
}

impl Deref for Templates<'_> {
    type Target = [Template];

    fn deref(&self) -> &[Template] {
        match self {
            Templates::Whole(t) => t,
            Templates::Side(s) if s.finished => &s.templates,
            Templates::Side(_) => &[],
        }
    }
}

impl PreparedFrame {
    /// The template points of every schedule step: what `MOTION` reads of a frame
    /// registered against. Empty for a frame prepared for lookup whose reference side
    /// is not finished ([`Preparer::finish`]).
    pub fn templates(&self) -> Templates<'_> {
        if self.light {
            Templates::Side(self.reference.read())
        } else {
            Templates::Whole(&self.templates)
        }
    }

    /// Whether the frame was prepared only for lookup ([`Config::lookup_depth`]).
    pub fn is_lookup_only(&self) -> bool {
        self.light
    }

    /// Whether `MOTION` can register against the frame: prepared whole, or its
    /// reference side finished.
    pub fn is_reference_ready(&self) -> bool {
        !self.light || self.reference.read().finished
    }

    /// The reference side of a frame prepared for lookup (`None` for a frame prepared
    /// whole, whose fields hold the same).
    pub fn reference_side(&self) -> Option<RwLockReadGuard<'_, ReferenceSide>> {
        self.light.then(|| self.reference.read())
    }

    /// Reserves the buffers of a lookup frame's raw planes and reference side.
    pub(crate) fn reserve_side(&mut self, config: &Config, templates: Vec<Template>) {
        let n = config.camera.pixels();
        let smoothed = if lookup_depth(config) == Some(LookupDepth::Bilateral)
            && half_bilateral(config, &super::tracked_levels(config)).is_none()
        {
            n
        } else {
            0
        };
        self.raw = RawPlanes {
            intensity: Vec::with_capacity(n),
            depth: Vec::with_capacity(n),
            smoothed: Vec::with_capacity(smoothed),
        };
        let side = self.reference.get_mut();
        side.templates = templates;
        side.normals = Vec::with_capacity(n);
        side.base = pyramid::Planes {
            intensity: Vec::with_capacity(n),
            depth: Vec::with_capacity(n),
        };
    }
}

/// Whether `config` prepares frames for lookup only, and with which depth.
pub(crate) fn lookup_depth(config: &Config) -> Option<LookupDepth> {
    (config.keyframes && config.lookup_depth != LookupDepth::Filtered)
        .then_some(config.lookup_depth)
}

/// The bilateral window of a lookup frame filtered on level 1: with
/// [`LookupDepth::Bilateral`] when no step tracks level 0 (640x480 under the default
/// schedule), the filter runs after the 2x2 downsampling, on a quarter of the pixels,
/// with the window halved so that it covers the same patch of the scene (radius 2
/// and σ 1.5 px become 1 and 0.75 px). On the suite against the full-resolution
/// filter (`docs/accuracy.md`): drift 0.998 on the real cells, 1.016 on the noise
/// cells, the others unchanged (they track level 0); tracking 0.63x the
/// instructions per frame at 640x480 (`docs/speed.md`). `None` otherwise.
pub(crate) fn half_bilateral(config: &Config, tracked: &[bool]) -> Option<BilateralConfig> {
    let b = config.filter.bilateral?;
    (lookup_depth(config) == Some(LookupDepth::Bilateral) && tracked.len() > 1 && !tracked[0])
        .then_some(BilateralConfig {
            radius: b.radius.div_ceil(2),
            sigma_space_px: b.sigma_space_px * 0.5,
            ..b
        })
}

/// The preparer's scratch for [`half_bilateral`]: level 1's padded depth and the
/// window's spatial weights (0 without it).
pub(crate) fn half_bilateral_bytes(config: &Config) -> usize {
    let tracked = super::tracked_levels(config);
    half_bilateral(config, &tracked).map_or(0, |b| {
        let c = config.camera.half();
        let r = b.radius;
        4 * (c.width + 2 * r) * (c.height + 2 * r) + 4 * (2 * r + 1) * (2 * r + 1)
    })
}

/// Level 0's compact planes without removal: intensity in [0, 1], and depth (NaN
/// where missing) kept only where it agrees within [`EDGE_AGREEMENT`] with its four
/// neighbours (the cheap stand-in of the contour filter: the warp interpolates no
/// depth across an edge; at the border the missing neighbour is the pixel itself).
/// Returns the pixels with depth.
#[inline(never)]
fn plain_planes(intensity: &[u8], depth: &[f32], w: usize, planes: &mut pyramid::Planes) -> usize {
    planes.intensity.resize(intensity.len(), 0.0);
    planes.depth.resize(depth.len(), f32::NAN);
    for (o, &i) in planes.intensity.iter_mut().zip(intensity) {
        *o = i as f32 * (1.0 / 255.0);
    }
    let n = depth.len();
    let h = n / w.max(1);
    let mut valid = 0;
    for y in 0..h {
        let r = y * w;
        let up = &depth[r.saturating_sub(w)..][..w];
        let down = &depth[(r + w).min(n - w)..][..w];
        let row = &depth[r..r + w];
        let out = &mut planes.depth[r..r + w];
        valid += edge_row(up, row, down, out) as usize;
    }
    valid
}

multiversion! {
    /// One row of [`plain_planes`]' depth: `row`'s depth kept where it agrees with
    /// its left and right neighbours and with `up` and `down` (the rows above and
    /// below); returns how many were kept.
    fn edge_row(up: &[f32], row: &[f32], down: &[f32], out: &mut [f32]) -> u32 = edge_row_kernel;
}

#[inline(always)]
fn edge_row_kernel(up: &[f32], row: &[f32], down: &[f32], out: &mut [f32]) -> u32 {
    let w = row.len();
    let (up, down, out) = (&up[..w], &down[..w], &mut out[..w]);
    // Branch-free: a NaN neighbour fails every comparison, so it keeps the pixel.
    let keep = |z: f32, l: f32, r: f32, u: f32, d: f32| {
        let tol = EDGE_AGREEMENT * z;
        let edge = ((l - z).abs() > tol)
            | ((r - z).abs() > tol)
            | ((u - z).abs() > tol)
            | ((d - z).abs() > tol);
        !z.is_nan() & !edge
    };
    let mut count = 0u32;
    if w < 3 {
        for x in 0..w {
            let (l, r) = (row[x.saturating_sub(1)], row[(x + 1).min(w - 1)]);
            let k = keep(row[x], l, r, up[x], down[x]);
            out[x] = if k { row[x] } else { f32::NAN };
            count += k as u32;
        }
        return count;
    }
    for x in [0, w - 1] {
        let (l, r) = (row[x.saturating_sub(1)], row[(x + 1).min(w - 1)]);
        let k = keep(row[x], l, r, up[x], down[x]);
        out[x] = if k { row[x] } else { f32::NAN };
        count += k as u32;
    }
    let m = w - 2;
    let (zl, zc, zr) = (&row[..m], &row[1..m + 1], &row[2..]);
    let (zu, zd, o) = (&up[1..m + 1], &down[1..m + 1], &mut out[1..m + 1]);
    for i in 0..m {
        let k = keep(zc[i], zl[i], zr[i], zu[i], zd[i]);
        o[i] = if k { zc[i] } else { f32::NAN };
        count += k as u32;
    }
    count
}

/// How far (relative) a lookup depth may differ from a neighbour's before the pixel
/// counts as a depth edge and loses its depth: the pyramid's 2x2 agreement rule.
const EDGE_AGREEMENT: f32 = 0.03;

impl Preparer {
    /// The lookup levels of `view` alone, from its depth as `depth` says; the raw
    /// planes kept and the reference side marked unfinished.
    pub(super) fn prepare_lookup(
        &mut self,
        view: FrameView<'_>,
        depth: LookupDepth,
        out: &mut PreparedFrame,
    ) {
        out.light = true;
        out.raw.intensity.clear();
        out.raw.intensity.extend_from_slice(view.intensity);
        out.raw.depth.clear();
        out.raw.depth.extend_from_slice(view.depth);
        {
            let side = out.reference.get_mut();
            side.finished = false;
            for t in &mut side.templates {
                t.points.clear();
            }
        }
        debug_assert_eq!(self.lookup, Some(depth));
        self.planes
            .resize_with(self.pyramid_depth + 1, pyramid::Planes::default);
        let made = if let Some((b, spatial)) = &self.half
            && depth == LookupDepth::Bilateral
        {
            out.raw.smoothed.clear();
            // Level 0 is not tracked: raw depth with the edge rule, the 2x2
            // agreement rule down to level 1, and the bilateral filter there, on a
            // quarter of the pixels.
            let (w, h) = (self.camera.width, self.camera.height);
            self.smoothed.resize(w * h, f32::NAN);
            bilateral::load_plain(view.depth, self.depth_range(), &mut self.smoothed);
            out.valid_depth = plain_planes(view.intensity, &self.smoothed, w, &mut self.planes[0]);
            let c1 = self.camera.half();
            let (head, tail) = self.planes.split_at_mut(1);
            pyramid::downsample(&head[0], w, &mut tail[0], c1);
            let level1 = &mut tail[0];
            bilateral::load_padded_metres(
                &level1.depth,
                c1.width,
                c1.height,
                b.radius,
                &mut self.padded_half,
            );
            bilateral::filter(
                &self.padded_half,
                spatial,
                c1.width,
                b.radius,
                b.sigma_depth_rel,
                &mut level1.depth,
            );
            1
        } else {
            self.smooth_depth(view.depth, true);
            out.valid_depth = plain_planes(
                view.intensity,
                &self.smoothed,
                self.camera.width,
                &mut self.planes[0],
            );
            // The frame keeps the filtered depth for its reference side; the preparer
            // takes the frame's old buffer for the next frame (no copy).
            if depth == LookupDepth::Bilateral && self.filter.bilateral.is_some() {
                std::mem::swap(&mut self.smoothed, &mut out.raw.smoothed);
            } else {
                out.raw.smoothed.clear();
            }
            0
        };
        out.removed_by_normal = 0;
        out.removed_by_contour = 0;
        out.normals.clear();
        self.lookup_levels(out, made);
    }

    /// Finishes the reference side of `frame` if it was prepared for lookup and is
    /// not finished yet: the whole preparation of its raw planes, less the lookup
    /// levels it has. A frame prepared whole, or finished, is left as it is.
    pub fn finish(&mut self, frame: &PreparedFrame) {
        if !frame.light || frame.reference.read().finished {
            return;
        }
        let mut side = frame
            .reference
            .0
            .write()
            .unwrap_or_else(PoisonError::into_inner);
        if side.finished {
            return;
        }
        let camera: Camera = *frame.levels[0].camera();
        if camera != self.camera {
            // Same size: checked when the frame was prepared.
            self.set_intrinsics(camera)
                .expect("a prepared frame's intrinsics are valid");
        }
        let view = FrameView {
            timestamp: frame.timestamp,
            intensity: &frame.raw.intensity,
            depth: &frame.raw.depth,
        };
        let side = &mut *side;
        let smoothed = (!frame.raw.smoothed.is_empty()).then_some(frame.raw.smoothed.as_slice());
        let counts = self.filtered_planes(view, smoothed, &mut side.normals);
        side.valid_depth = counts.valid;
        side.removed_by_normal = counts.by_normal;
        side.removed_by_contour = counts.by_contour;
        // The planes of the levels the templates are taken from, and the samples a
        // step with a point budget selects from (on the filtered depth).
        let deepest = self
            .schedule
            .iter()
            .map(|s| s.pyramid_level)
            .max()
            .unwrap_or(0);
        let mut level_cam = self.camera;
        for l in 1..=deepest {
            let (head, tail) = self.planes.split_at_mut(l);
            pyramid::downsample(
                &head[l - 1],
                level_cam.width,
                &mut tail[0],
                level_cam.half(),
            );
            level_cam = level_cam.half();
        }
        let mut levels = std::mem::take(&mut self.side_levels);
        levels.resize_with(self.pyramid_depth + 1, Default::default);
        for (l, level) in levels.iter_mut().enumerate() {
            level.camera = frame.levels[l].camera;
            let budgeted = self
                .schedule
                .iter()
                .any(|s| s.pyramid_level == l && s.max_points.is_some());
            if budgeted {
                pyramid::samples(&self.planes[l], level.camera().width, &mut level.samples);
            }
        }
        self.build_templates(&levels, &mut side.templates);
        self.side_levels = levels;
        std::mem::swap(&mut self.planes[0], &mut side.base);
        side.finished = true;
    }
}

/// The bytes a lookup frame adds to a frame prepared whole: its raw planes (3 a
/// pixel, 7 with the filtered depth kept) and the filtered level-0 planes of its
/// reference side (8 a pixel).
pub(crate) fn side_bytes(config: &Config) -> usize {
    if lookup_depth(config).is_some() {
        let kept = lookup_depth(config) == Some(LookupDepth::Bilateral)
            && half_bilateral(config, &super::tracked_levels(config)).is_none();
        (11 + 4 * kept as usize) * config.camera.pixels()
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::super::{D, I, Preparer, Template};
    use crate::camera::{Camera, FrameView};
    use crate::config::{Config, LookupDepth, Mode, Preset};
    use crate::prepare::PreparedFrame;

    /// A textured, depth-varying frame of `w` x `h` with some holes.
    fn frame(w: usize, h: usize, seed: usize) -> (Camera, Vec<u8>, Vec<u16>) {
        let c = Camera {
            width: w,
            height: h,
            fx: 0.8 * w as f64,
            fy: 0.8 * w as f64,
            cx: w as f64 / 2.0 - 0.5,
            cy: h as f64 / 2.0 - 0.5,
            depth_scale: 1000.0,
        };
        let mut intensity = vec![0u8; w * h];
        let mut depth = vec![0u16; w * h];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                intensity[i] = (((x + seed) / 4 + y / 6) % 5 * 45 + (x * 13 + y * 7) % 9) as u8;
                let t = (x as f32 + seed as f32) / 7.0 + y as f32 / 11.0;
                let step = if x > w / 2 { 600.0 } else { 0.0 };
                depth[i] = if (x * 31 + y * 17) % 23 == 0 {
                    0
                } else {
                    (1500.0 + step + 80.0 * t.sin()) as u16
                };
            }
        }
        (c, intensity, depth)
    }

    fn config(c: Camera, depth: LookupDepth, budget: Option<usize>) -> Config {
        let mut config = Config::new(c, Preset::Pc, Mode::L2);
        config.keyframes = true;
        config.lookup_depth = depth;
        config.motion.set_point_budget(1, budget);
        config
    }

    fn bits(t: &[Template]) -> Vec<(usize, Vec<[u32; 4]>)> {
        t.iter()
            .map(|t| {
                let p = t.points.iter().map(|p| p.map(f32::to_bits)).collect();
                (t.pyramid_level, p)
            })
            .collect()
    }

    fn cloud(f: &PreparedFrame) -> Vec<([u32; 3], [u32; 3], u8)> {
        let mut v = Vec::new();
        f.for_each_point(2, |p, n, i| {
            v.push((p.map(f32::to_bits), n.map(f32::to_bits), i))
        });
        v
    }

    /// A frame prepared for lookup and then finished has, on its reference side, the
    /// templates, normals, removal counts and cloud of the same frame prepared whole,
    /// bit for bit; before it is finished it has no templates. Its lookup levels are
    /// those of its lookup depth: raw depth averaged down the pyramid, or the
    /// bilateral filter's. Pooled frames reused for other frames give the same.
    #[test]
    fn a_finished_lookup_frame_is_the_whole_frame_on_its_reference_side() {
        for (w, h) in [(160, 120), (320, 240)] {
            for depth in [LookupDepth::Raw, LookupDepth::Bilateral] {
                for budget in [None, Some(300)] {
                    let what = format!("{w}x{h} {depth:?} budget {budget:?}");
                    let (c, _, _) = frame(w, h, 0);
                    let cfg = config(c, depth, budget);
                    let whole_cfg = Config {
                        lookup_depth: LookupDepth::Filtered,
                        ..cfg.clone()
                    };
                    let mut light = Preparer::new(&cfg);
                    let mut whole = Preparer::new(&whole_cfg);
                    light.set_normals(false);
                    let mut finisher = Preparer::whole(&cfg);
                    let mut lf = PreparedFrame::for_config(&cfg);
                    let mut wf = PreparedFrame::for_config(&whole_cfg);
                    for seed in [0, 5, 9] {
                        let (_, intensity, d) = frame(w, h, seed);
                        let view = FrameView {
                            timestamp: seed as f64,
                            intensity: &intensity,
                            depth: &d,
                        };
                        light.prepare_into(view, &mut lf).unwrap();
                        whole.prepare_into(view, &mut wf).unwrap();
                        assert!(lf.is_lookup_only() && !wf.is_lookup_only(), "{what}");
                        assert!(!lf.is_reference_ready(), "{what}");
                        assert!(lf.templates().is_empty(), "{what}");
                        assert!(lf.normals.is_empty(), "{what}");
                        // The lookup levels: level 0 of 160x120 holds the raw depth,
                        // less the pixels at a depth edge (a neighbour more than 3 %
                        // away), and the intensity.
                        if w == 160 && depth == LookupDepth::Raw {
                            let l0 = &lf.levels[0].samples;
                            let m = |x: usize, y: usize| d[y * w + x] as f32 * (1.0 / 1000.0);
                            let (mut kept, mut edges) = (0, 0);
                            for y in 0..h {
                                for x in 0..w {
                                    let (i, z) = (y * w + x, m(x, y));
                                    let near = [
                                        m(x.saturating_sub(1), y),
                                        m((x + 1).min(w - 1), y),
                                        m(x, y.saturating_sub(1)),
                                        m(x, (y + 1).min(h - 1)),
                                    ];
                                    let edge =
                                        near.iter().any(|&n| n > 0.0 && (n - z).abs() > 0.03 * z);
                                    let got = l0[i][D];
                                    if d[i] == 0 || edge {
                                        assert!(got.is_nan(), "{what}: pixel {i}");
                                        edges += (d[i] != 0) as usize;
                                    } else {
                                        assert_eq!(got.to_bits(), z.to_bits(), "{what}: {i}");
                                        kept += 1;
                                    }
                                    let gray = intensity[i] as f32 * (1.0 / 255.0);
                                    assert_eq!(l0[i][I].to_bits(), gray.to_bits(), "{what}");
                                }
                            }
                            assert!(edges > 100 && kept > 10 * edges, "{what}: {kept} {edges}");
                            assert_eq!(lf.valid_depth, kept, "{what}");
                        }
                        finisher.finish(&lf);
                        assert!(lf.is_reference_ready(), "{what}");
                        let side = lf.reference_side().unwrap();
                        assert_eq!(bits(&lf.templates()), bits(&wf.templates), "{what}");
                        assert!(!wf.templates.last().unwrap().points.is_empty(), "{what}");
                        assert_eq!(side.removed_by_normal, wf.removed_by_normal, "{what}");
                        assert_eq!(side.removed_by_contour, wf.removed_by_contour, "{what}");
                        assert!(
                            side.removed_by_normal + side.removed_by_contour > 0,
                            "{what}"
                        );
                        assert_eq!(side.valid_depth, wf.valid_depth, "{what}");
                        drop(side);
                        assert!(cloud(&lf) == cloud(&wf), "{what}: cloud");
                        // Finishing twice changes nothing.
                        finisher.finish(&lf);
                        assert_eq!(bits(&lf.templates()), bits(&wf.templates), "{what}");
                    }
                }
            }
        }
    }

    /// Without keyframe tracking, or with `LookupDepth::Filtered`, frames are
    /// prepared whole, as before.
    #[test]
    fn only_keyframe_tracking_prepares_for_lookup() {
        let (c, intensity, d) = frame(160, 120, 0);
        let view = FrameView {
            timestamp: 0.0,
            intensity: &intensity,
            depth: &d,
        };
        for (keyframes, depth, lookup) in [
            (false, LookupDepth::Raw, false),
            (true, LookupDepth::Filtered, false),
            (true, LookupDepth::Raw, true),
            (true, LookupDepth::Bilateral, true),
        ] {
            let mut cfg = config(c, depth, None);
            cfg.keyframes = keyframes;
            let mut f = PreparedFrame::for_config(&cfg);
            Preparer::new(&cfg).prepare_into(view, &mut f).unwrap();
            assert_eq!(f.is_lookup_only(), lookup, "{keyframes} {depth:?}");
            assert_eq!(f.is_reference_ready(), !lookup);
            assert_eq!(f.templates().is_empty(), lookup);
        }
    }
}
