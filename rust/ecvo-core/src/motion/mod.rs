//! `MOTION(Fi, Fj, Tinit)`: dense direct alignment of intensity and depth.
//!
//! Following Tykkälä et al. with the weighting of Kerl et al., as the paper does:
//! every valid template point `q` of the reference frame `Fj` is moved into the
//! current frame `Fi` by `T = T_{j→i}` and projected to `u' = π(T q)`; there
//!
//! - the photometric residual is `r_I = I_i(u') − I_j(q)` (intensities in [0, 1]),
//! - the geometric residual is `r_Z = D_i(u') − [T q]_z` (metres), scaled by λ,
//!
//! and both share one weight from a bivariate t-distribution (ν = 5) whose 2x2 scale
//! matrix over `(r_I, r_Z)` is re-fitted after every accepted update (see
//! [`crate::scale`]; [`Weighting::Scalar`] is the special case of one σ² over
//! `(r_I, λ r_Z)`). With [`DepthNoiseModel::Quadratic`] the depth residual is divided
//! by z², so the scale describes the depth noise at 1 m and far points count less.
//! Gauss-Newton on a left perturbation `T ← exp(δ) T` runs coarse to fine on the image
//! pyramid; an update that raises the robust cost at its scale, or leaves too few
//! residuals, is undone and ends its step. The result reports `T_{i,j} = T⁻¹`, the
//! motion that maps camera `i` coordinates into camera `j` coordinates.

mod normal;
#[cfg(test)]
mod tests;
mod warp;

use nalgebra::{Matrix6, SymmetricEigen};
use rayon::prelude::*;

use crate::Pose;
use crate::config::{DepthNoiseModel, MotionConfig, MotionLevel, Weighting};
use crate::prepare::{ImageLevel, PreparedFrame};
use crate::scale::{self, PassSums, Scale, Whitener};
use crate::se3;

pub use normal::NormalEquations;
use normal::{Accumulator, JRow, jacobians};
use warp::{Residual, Warp};

/// The most coarse-to-fine steps a schedule may have.
pub const MAX_STEPS: usize = 8;

/// The most initial guesses [`MotionEstimator::motion_from`] tries; further ones are
/// ignored.
pub const MAX_STARTS: usize = 4;

/// Why a motion estimate was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// Too few pixels of the reference frame landed on valid pixels of the current one.
    TooFewPixels,
    /// The normal equations are singular or nearly so (flat, featureless input).
    Degenerate,
    /// The estimate is not finite.
    NotFinite,
    /// The estimated motion is larger than a frame-to-frame motion can be.
    TooLarge,
    /// The residuals at the result spread too widely
    /// ([`MotionConfig::max_intensity_sigma`], [`MotionConfig::max_depth_sigma_m`]):
    /// the frames do not show the same scene at that alignment.
    Inconsistent,
}

/// How the estimation ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// The finest level converged (update below the threshold, or a rejected step).
    Converged,
    /// The finest level used all its iterations.
    MaxIterations,
    /// No usable estimate; the pose is the initial guess and must not be used.
    Failed(Failure),
}

/// The outcome of one `MOTION` call.
#[derive(Clone, Copy, Debug)]
pub struct MotionResult {
    /// `T_{i,j}`: maps points in camera `i` (current) coordinates to camera `j`
    /// (reference) coordinates. Equal to the initial guess when the call failed.
    pub pose: Pose,
    /// Gauss-Newton iterations at each coarse-to-fine step (first `steps` entries).
    pub iterations: [u32; MAX_STEPS],
    /// Number of coarse-to-fine steps run.
    pub steps: usize,
    /// Final weighted mean squared residual `Σ w e² / n`.
    pub error: f64,
    /// Valid residuals at the finest step.
    pub valid_pixels: usize,
    /// `JᵀWJ` at the finest step, whitened by the estimated scale: the information
    /// matrix of the twist `[v; ω]` of the left perturbation of `T_{j→i}`.
    pub information: Matrix6<f64>,
    /// The residuals' scale at the finest step.
    pub scale: Option<Scale>,
    /// Which initial guess won at the coarsest step (0: the first).
    pub start: u8,
    /// Converged, ran out of iterations, or failed.
    pub status: Status,
}

impl MotionResult {
    /// True unless the estimate failed.
    pub fn is_ok(&self) -> bool {
        !matches!(self.status, Status::Failed(_))
    }
}

/// Smallest number of residuals a coarse step needs to be worth solving.
const MIN_STEP_RESIDUALS: usize = 24;

/// Template points per chunk of the parallel loops. The chunking is fixed, so every
/// sum is grouped the same way whatever the number of threads: the poses do not
/// depend on it.
pub const CHUNK: usize = 4096;

/// Fewest chunks one rayon task takes. Handing work to another thread costs tens of
/// microseconds (waking it, and spinning while waiting for it), so a loop is only
/// split when each part has at least this many chunks: at 640x480 the finest step of
/// the paper's sampling (about 77k points) splits into up to nine tasks and the
/// middle one (19k) into two; at 320x240 only the finest step (19k) splits, in two.
pub const MIN_CHUNKS_PER_TASK: usize = 2;

/// Most fixed-point passes of one scale fit.
const MAX_SCALE_PASSES: usize = 20;

/// The settings of one `MOTION` call, in the form the per-pixel loops use.
#[derive(Clone, Copy, Debug)]
struct Params {
    nu: f32,
    /// λ.
    lambda: f32,
    weighting: Weighting,
    quadratic_noise: bool,
}

impl Params {
    fn of(cfg: &MotionConfig) -> Params {
        Params {
            nu: cfg.t_dof as f32,
            lambda: cfg.depth_gain as f32,
            weighting: cfg.weighting,
            quadratic_noise: cfg.depth_noise == DepthNoiseModel::Quadratic,
        }
    }
}

/// What one coarse-to-fine step left.
#[derive(Clone, Copy, Debug)]
struct StepOutcome {
    /// `T_{j→i}` at the end of the step.
    t: Pose,
    /// The normal equations of the last linearisation (None: the step never had
    /// enough residuals).
    ne: Option<NormalEquations>,
    /// Gauss-Newton iterations run (steps solved).
    iterations: u32,
    /// True when the step used all its iterations, each one accepted.
    hit_max: bool,
    /// The scale at the end of the step.
    scale: Option<Scale>,
    /// Mean robust cost at `t` for `scale`.
    cost: f64,
    /// Residuals at `t`.
    valid: usize,
}

/// Runs `MOTION` and keeps its scratch buffers between calls, so that a warm
/// estimator does not allocate.
///
/// The per-point work (warping, scale passes, robust cost, normal equations) runs
/// over fixed chunks of [`CHUNK`] template points, with rayon (in whatever pool the
/// caller is in) once a template is large enough. The per-chunk partial sums are
/// added in chunk order.
#[derive(Debug, Default)]
pub struct MotionEstimator {
    /// Residuals of each chunk of template points.
    chunks: Vec<Vec<Residual>>,
    /// Per-chunk normal equations, merged in order.
    partial: Vec<NormalEquations>,
    /// Per-chunk robust costs, added in order.
    errors: Vec<f64>,
    /// Per-chunk sums of a scale pass, added in order.
    sums: Vec<PassSums>,
    /// Chunks the last warp filled.
    used: usize,
}

impl MotionEstimator {
    /// A new estimator with empty scratch buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// An estimator whose scratch buffers hold templates of up to `max_points`
    /// points, so that it never allocates while tracking.
    pub fn with_capacity(max_points: usize) -> Self {
        let mut e = Self::default();
        e.reserve(max_points.div_ceil(CHUNK));
        e
    }

    fn reserve(&mut self, chunks: usize) {
        if self.chunks.len() < chunks {
            self.chunks
                .resize_with(chunks, || Vec::with_capacity(CHUNK));
            self.partial
                .reserve(chunks.saturating_sub(self.partial.len()));
            self.errors
                .reserve(chunks.saturating_sub(self.errors.len()));
            self.sums.reserve(chunks.saturating_sub(self.sums.len()));
        }
    }

    /// The residuals of the last warp, chunk after chunk.
    #[cfg(test)]
    fn residuals(&self) -> impl Iterator<Item = &Residual> {
        self.chunks[..self.used].iter().flatten()
    }

    /// `MOTION(Fi, Fj, Tinit)`: estimates `T_{i,j}`, the motion from the current
    /// frame `fi` to the reference frame `fj`, starting from `t_init`. Both frames
    /// must have been prepared with the same configuration.
    pub fn motion(
        &mut self,
        fi: &PreparedFrame,
        fj: &PreparedFrame,
        t_init: &Pose,
        cfg: &MotionConfig,
    ) -> MotionResult {
        self.motion_from(fi, fj, std::slice::from_ref(t_init), cfg)
    }

    /// `MOTION` from the best of several initial guesses: the coarsest step runs from
    /// each, and the one whose result explains the template best (the lowest mean
    /// robust cost at a common scale, a template point that leaves the image costing
    /// as much as the worst outlier) goes on to the finer steps. Ties go to the
    /// earlier guess. [`MotionResult::start`] says which one won. At most
    /// [`MAX_STARTS`] guesses are tried.
    pub fn motion_from(
        &mut self,
        fi: &PreparedFrame,
        fj: &PreparedFrame,
        inits: &[Pose],
        cfg: &MotionConfig,
    ) -> MotionResult {
        let first = inits.first().copied().unwrap_or_else(Pose::identity);
        let mut result = MotionResult {
            pose: first,
            iterations: [0; MAX_STEPS],
            steps: cfg.levels.len().min(MAX_STEPS),
            error: f64::NAN,
            valid_pixels: 0,
            information: Matrix6::zeros(),
            scale: None,
            start: 0,
            status: Status::Failed(Failure::TooFewPixels),
        };
        if inits.is_empty() || !inits.iter().all(se3::is_finite) {
            result.status = Status::Failed(Failure::NotFinite);
            return result;
        }
        let p = Params::of(cfg);
        let mut last_step: Option<StepOutcome> = None;
        let mut scale: Option<Scale> = None;
        let mut t = first.inverse();
        for (k, step) in cfg.levels.iter().enumerate().take(MAX_STEPS) {
            let (Some(level), Some(template)) =
                (fi.levels.get(step.pyramid_level), fj.templates.get(k))
            else {
                break;
            };
            let out = if k == 0 && inits.len() > 1 {
                let (best, out) = self.best_start(level, &template.points, inits, step, cfg, &p);
                result.start = best as u8;
                out
            } else {
                self.run_step(level, &template.points, t, step, cfg, &p, scale)
            };
            result.iterations[k] = out.iterations;
            t = out.t;
            if out.scale.is_some() {
                scale = out.scale;
            }
            last_step = Some(out);
        }

        let Some(last) = last_step else {
            return result;
        };
        let Some(ne) = last.ne else {
            return result;
        };
        result.error = last.cost;
        result.valid_pixels = last.valid;
        result.information = ne.hessian();
        result.scale = last.scale;
        let pose = t.inverse();
        result.status = if last.valid < cfg.min_valid_pixels {
            Status::Failed(Failure::TooFewPixels)
        } else if !se3::is_finite(&pose) {
            Status::Failed(Failure::NotFinite)
        } else if is_degenerate(&result.information) {
            Status::Failed(Failure::Degenerate)
        } else if pose.translation.vector.norm() > cfg.max_translation_m
            || se3::angle(&pose).to_degrees() > cfg.max_rotation_deg
        {
            Status::Failed(Failure::TooLarge)
        } else if last.scale.is_some_and(|s| {
            s.ii.sqrt() > cfg.max_intensity_sigma
                || s.zz.sqrt() > cfg.max_depth_sigma_m * cfg.depth_gain.max(1e-9)
        }) {
            Status::Failed(Failure::Inconsistent)
        } else if last.hit_max {
            Status::MaxIterations
        } else {
            Status::Converged
        };
        if result.is_ok() {
            result.pose = pose;
        }
        result
    }

    /// Runs the first step from every guess and keeps the best (see
    /// [`Self::motion_from`]); returns its index and outcome.
    fn best_start(
        &mut self,
        level: &ImageLevel,
        points: &[[f32; 4]],
        inits: &[Pose],
        step: &MotionLevel,
        cfg: &MotionConfig,
        p: &Params,
    ) -> (usize, StepOutcome) {
        // On the stack: a warm estimator does not allocate.
        let mut slots: [Option<StepOutcome>; MAX_STARTS] = [None; MAX_STARTS];
        for (slot, init) in slots.iter_mut().zip(inits) {
            *slot = Some(self.run_step(level, points, init.inverse(), step, cfg, p, None));
        }
        let outs = slots.iter().flatten();
        // A common scale: the first guess's (the identity's, for [A]).
        let Some(common) = outs.clone().find_map(|o| o.scale) else {
            return (0, slots[0].expect("at least one start"));
        };
        let wh = common.whitener(p.nu);
        let total = points.len().max(1) as f64;
        let mut best = (0, f64::INFINITY);
        for (k, o) in outs.enumerate() {
            if o.ne.is_none() {
                continue;
            }
            self.residuals_at(&o.t, points, level, p);
            let cost = self.cost(&wh);
            let missing = (points.len() - self.valid()) as f64 * wh.max_cost() as f64;
            let c = (cost + missing) / total;
            if c < best.1 {
                best = (k, c);
            }
        }
        (best.0, slots[best.0].expect("the best start ran"))
    }

    /// One coarse-to-fine step: Gauss-Newton from `t` with the scale re-fitted after
    /// every accepted update. A update is accepted only if it lowers the mean robust
    /// cost at the scale it was computed with (the IRLS majoriser, so the robust
    /// objective itself does not rise) and leaves enough residuals; otherwise it is
    /// undone and the step ends.
    fn run_step(
        &mut self,
        level: &ImageLevel,
        points: &[[f32; 4]],
        mut t: Pose,
        step: &MotionLevel,
        cfg: &MotionConfig,
        p: &Params,
        start: Option<Scale>,
    ) -> StepOutcome {
        let mut out = StepOutcome {
            t,
            ne: None,
            iterations: 0,
            hit_max: false,
            scale: start,
            cost: f64::NAN,
            valid: 0,
        };
        let mut n = self.residuals_at(&t, points, level, p);
        if n < MIN_STEP_RESIDUALS {
            return out;
        }
        let Some(mut scale) = self.fit_scale(p, start) else {
            return out;
        };
        let mut wh = scale.whitener(p.nu);
        let mut cost = self.cost(&wh) / n as f64;
        out.hit_max = true;
        for it in 0..step.max_iterations {
            let ne = self.normal_equations(level, &wh, cost * n as f64);
            out.ne = Some(ne);
            out.iterations = it + 1;
            let Some(delta) = ne.solve() else {
                out.hit_max = false;
                break;
            };
            let candidate = se3::compose(&se3::exp(&delta), &t);
            let m = self.residuals_at(&candidate, points, level, p);
            if m < MIN_STEP_RESIDUALS {
                out.hit_max = false;
                break;
            }
            let c = self.cost(&wh) / m as f64;
            // `!(c <= cost)` also rejects NaN.
            if !(c <= cost) {
                out.hit_max = false;
                break;
            }
            t = candidate;
            n = m;
            if let Some(s) = self.fit_scale(p, Some(scale)) {
                scale = s;
                wh = scale.whitener(p.nu);
            }
            cost = self.cost(&wh) / n as f64;
            let small = delta.fixed_rows::<3>(0).norm() < cfg.min_update
                && delta.fixed_rows::<3>(3).norm() < cfg.min_update;
            if small {
                out.hit_max = false;
                break;
            }
        }
        out.t = t;
        out.scale = Some(scale);
        out.cost = cost;
        out.valid = n;
        out
    }

    /// Residuals stored by the last warp.
    fn valid(&self) -> usize {
        self.chunks[..self.used].iter().map(Vec::len).sum()
    }

    /// Warps the template into `level` under `t` and stores the residuals; returns
    /// how many template points produced a photometric residual.
    fn residuals_at(
        &mut self,
        t: &Pose,
        points: &[[f32; 4]],
        level: &ImageLevel,
        p: &Params,
    ) -> usize {
        let cam = level.camera();
        assert_eq!(
            level.samples.len(),
            cam.width * cam.height,
            "level buffer matches its camera"
        );
        let m = t.to_homogeneous();
        let warp = Warp {
            r: std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)] as f32)),
            f: [cam.fx as f32, cam.fy as f32, cam.cx as f32, cam.cy as f32],
            w: cam.width,
            max: [(cam.width - 1) as f32, (cam.height - 1) as f32],
            samples: &level.samples,
            lambda: p.lambda,
            quadratic: p.quadratic_noise,
        };
        let n = points.len().div_ceil(CHUNK);
        self.reserve(n);
        self.used = n;
        let bufs = &mut self.chunks[..n];
        if !splits(n) {
            for (pts, buf) in points.chunks(CHUNK).zip(bufs.iter_mut()) {
                warp.run(pts, buf);
            }
        } else {
            points
                .par_chunks(CHUNK)
                .zip(bufs.par_iter_mut())
                .with_min_len(MIN_CHUNKS_PER_TASK)
                .for_each(|(pts, buf)| warp.run(pts, buf));
        }
        self.valid()
    }

    /// Fits the scale to the stored residuals by fixed-point iteration from `start`
    /// (or from their plain second moments); `None` when there is no residual.
    fn fit_scale(&mut self, p: &Params, start: Option<Scale>) -> Option<Scale> {
        let chunks = &self.chunks[..self.used];
        let (mut two, mut one) = (0, 0);
        for c in chunks {
            let (t, o) = scale::count(c);
            two += t;
            one += o;
        }
        let mut s = match start {
            Some(s) if s.ii > 0.0 && s.zz > 0.0 && s.ii.is_finite() && s.zz.is_finite() => s,
            _ => scale::initial_scale(chunks, p.weighting)?,
        };
        for _ in 0..MAX_SCALE_PASSES {
            let wh = s.whitener(p.nu);
            let weighting = p.weighting;
            map_chunks(chunks, &mut self.sums, |c| scale::pass(c, &wh, weighting));
            let mut total = [0.0f64; 4];
            for part in &self.sums {
                for k in 0..4 {
                    total[k] += part[k];
                }
            }
            let next = scale::next_scale(&total, two, one, p.weighting)?;
            let done = scale::settled(&s, &next);
            s = next;
            if done {
                break;
            }
        }
        Some(s)
    }

    /// `Σ w d²` over the stored residuals at a fixed scale (pixel order within a
    /// chunk, chunk order across them).
    fn cost(&mut self, wh: &Whitener) -> f64 {
        let sum = |res: &Vec<Residual>| {
            let mut e = 0.0f64;
            for run in res.chunks(256) {
                let mut part = 0.0f32;
                for r in run {
                    part += wh.cost(r.ri, r.rz);
                }
                e += part as f64;
            }
            e
        };
        map_chunks(&self.chunks[..self.used], &mut self.errors, sum);
        let mut total = 0.0;
        for e in &self.errors {
            total += e;
        }
        total
    }

    /// Weights and whitens the stored residuals and accumulates the normal equations;
    /// `error` is their [`Self::cost`], computed first.
    fn normal_equations(
        &mut self,
        level: &ImageLevel,
        wh: &Whitener,
        error: f64,
    ) -> NormalEquations {
        let cam = level.camera();
        let (fx, fy) = (cam.fx as f32, cam.fy as f32);
        let accumulate = |res: &Vec<Residual>| {
            let mut acc = Accumulator::new();
            for r in res {
                let (_, w) = wh.weigh(r.ri, r.rz);
                let (ji, jz) = jacobians(r, fx, fy);
                match jz {
                    Some(jz) => {
                        // L r and L J with Σ⁻¹ = Lᵀ L: two whitened rows.
                        let a: JRow = std::array::from_fn(|b| wh.l11 * ji[b] + wh.l12 * jz[b]);
                        acc.add(&a, wh.l11 * r.ri + wh.l12 * r.rz, w);
                        let c: JRow = std::array::from_fn(|b| wh.l22 * jz[b]);
                        acc.add(&c, wh.l22 * r.rz, w);
                    }
                    None => {
                        let a: JRow = std::array::from_fn(|b| wh.l1d * ji[b]);
                        acc.add(&a, wh.l1d * r.ri, w);
                    }
                }
                acc.end_pixel();
            }
            acc.finish()
        };
        map_chunks(&self.chunks[..self.used], &mut self.partial, accumulate);
        let mut total = NormalEquations::default();
        for part in &self.partial {
            total.merge(part);
        }
        total.error = error;
        total
    }
}

/// True when a loop over `chunks` chunks is worth handing to rayon: each of at least
/// two tasks gets [`MIN_CHUNKS_PER_TASK`] chunks.
fn splits(chunks: usize) -> bool {
    chunks >= 2 * MIN_CHUNKS_PER_TASK
}

/// `out[k] = f(&chunks[k])`, with rayon when there are enough chunks to split. The
/// results stay in chunk order, so what the caller sums does not depend on the
/// number of threads.
fn map_chunks<T: Send>(
    chunks: &[Vec<Residual>],
    out: &mut Vec<T>,
    f: impl Fn(&Vec<Residual>) -> T + Sync + Send,
) {
    if !splits(chunks.len()) {
        out.clear();
        out.extend(chunks.iter().map(f));
    } else {
        chunks
            .par_iter()
            .with_min_len(MIN_CHUNKS_PER_TASK)
            .map(f)
            .collect_into_vec(out);
    }
}

/// True when the Jacobi-scaled information matrix is nearly singular: some motion
/// is not observed by the input (a flat, textureless plane, for instance).
fn is_degenerate(h: &Matrix6<f64>) -> bool {
    let d: [f64; 6] = std::array::from_fn(|i| h[(i, i)]);
    if d.iter().any(|&x| !(x > 0.0) || !x.is_finite()) {
        return true;
    }
    let scaled = Matrix6::from_fn(|r, c| h[(r, c)] / (d[r] * d[c]).sqrt());
    let eig = SymmetricEigen::new(scaled).eigenvalues;
    let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &e| {
        (lo.min(e), hi.max(e))
    });
    !(lo > 1e-6 * hi)
}
