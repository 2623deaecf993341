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
//! `(r_I, λ r_Z)`). With
//! [`DepthNoiseModel::Quadratic`](crate::config::DepthNoiseModel::Quadratic) the depth
//! residual is divided by z², so the scale describes the depth noise at 1 m and far
//! points count less; the default, `Fitted`, has the tracker fit the shape of that
//! growth to the residuals ([`crate::noise`]).
//! Gauss-Newton on a left perturbation `T ← exp(δ) T` runs coarse to fine on the image
//! pyramid; an update that raises the robust cost at its scale, or leaves too few
//! residuals, is undone and ends its step. The result reports `T_{i,j} = T⁻¹`, the
//! motion that maps camera `i` coordinates into camera `j` coordinates.
//!
//! The per-point loops are structure-of-arrays (`warp`, `robust`, `normal`):
//! one `f32` slice per quantity, branch-free, summed over fixed lanes
//! (`lanes`), with AVX2 and AVX-512 copies chosen at run time on x86_64; every path
//! gives the same bits.

mod estimator;
pub use crate::config::MAX_SCALE_PASSES;
mod lanes;
mod normal;
#[cfg(test)]
mod reference;
mod robust;
#[cfg(test)]
mod tests;
mod warp;

use nalgebra::Matrix6;
use rayon::prelude::*;

use crate::Pose;
use crate::config::{MotionConfig, Weighting};
use crate::noise::{DepthSpread, SpreadHistogram};
use crate::prepare::{ImageLevel, PreparedFrame};
use crate::scale::{PassSums, Scale, Whitener};
use estimator::{Loops, Params};
pub use normal::NormalEquations;
use warp::{Chunk, TemplateChunk, Warp};

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
    /// Template points of the finest step run (`valid_pixels` of them were used).
    pub template_points: usize,
    /// `JᵀWJ` at the finest step, whitened by the estimated scale: the information
    /// matrix of the twist `[v; ω]` of the left perturbation of `T_{j→i}`.
    pub information: Matrix6<f64>,
    /// The residuals' scale at the finest step, in the form of
    /// [`MotionConfig::weighting`] (refitted on the finest step's residuals when
    /// `fine_weighting` weighed that step otherwise): what the spread checks read.
    pub scale: Option<Scale>,
    /// Which initial guess won at the coarsest step (0: the first).
    pub start: u8,
    /// Converged, ran out of iterations, or failed.
    pub status: Status,
    /// The raw depth residuals' robust spread per depth at the end of the finest step
    /// (every 4th residual; empty unless [`MotionConfig::depth_spread`] and the call
    /// succeeded): what [`crate::noise::NoiseFit`] fits the depth-noise model to.
    pub depth_spread: DepthSpread,
    /// With a rotation prior ([`MotionConfig::rotation_prior_information`]): the
    /// pose the images alone give, one Gauss-Newton step of their finest normal
    /// equations (`information`) without the prior from where they were last
    /// linearised, in `pose`'s convention. What the gyro's bias is learnt from, so
    /// that the gyro is not counted twice. `None` without a prior term.
    pub images_pose: Option<Pose>,
}

impl MotionResult {
    /// True unless the estimate failed.
    pub fn is_ok(&self) -> bool {
        !matches!(self.status, Status::Failed(_))
    }
}

/// Template points per chunk of the parallel loops. The chunking is fixed, so every
/// sum is grouped the same way whatever the number of threads: the poses do not
/// depend on it.
pub const CHUNK: usize = 4096;

/// Fewest chunks one rayon task takes. Handing work to another thread costs tens of
/// microseconds (waking it, and spinning while waiting for it), so a loop is only
/// split when each of two parts has at least this many chunks. At 1, every step of
/// 8k points or more splits: at 320x240 the finest step (up to 19k points) and the
/// half-resolution one (up to 19k); at 2 (before issue 46's keyframe tracking) only
/// loops of 16k points did, so at 320x240 keyframe tracking's registrations ran on
/// one thread and the pipeline of 2 threads gave only 1.20x / 1.30x the frames per
/// second of one (`examples/throughput.rs tum_fr1_xyz_half --threads 2 --repeat 3`,
/// two alternated rounds, idle 2-core AVX-512 VM); at 1: 1.51x / 1.42x, and the
/// sequential engine in a 2-thread pool 1.27x / 1.21x (was 1.11x / 1.10x). At
/// 640x480 1.71x against 1.68x. The chunking itself is unchanged, so are the poses.
pub const MIN_CHUNKS_PER_TASK: usize = 1;

/// Runs `MOTION` and keeps its scratch buffers between calls, so that a warm
/// estimator does not allocate.
///
/// The per-point work (warping, scale passes, robust cost, normal equations) runs
/// over fixed chunks of [`CHUNK`] template points, with rayon (in whatever pool the
/// caller is in) once a template is large enough. The per-chunk partial sums are
/// added in chunk order.
#[derive(Debug, Default)]
pub struct MotionEstimator {
    /// The template of the current step, chunk by chunk.
    template: Vec<TemplateChunk>,
    /// Residuals of each chunk of template points.
    chunks: Vec<Chunk>,
    /// Chunks of the current template.
    used: usize,
    /// Per-chunk normal equations, merged in order.
    partial: Vec<NormalEquations>,
    /// Per-chunk robust costs, added in order.
    errors: Vec<f64>,
    /// Per-chunk sums of a scale pass, added in order.
    sums: Vec<(PassSums, f64)>,
    /// Scratch of [`MotionResult::depth_spread`].
    spread: SpreadHistogram,
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
            self.template
                .resize_with(chunks, || TemplateChunk::with_capacity(CHUNK));
            self.chunks
                .resize_with(chunks, || Chunk::with_capacity(CHUNK));
            self.partial
                .reserve(chunks.saturating_sub(self.partial.len()));
            self.errors
                .reserve(chunks.saturating_sub(self.errors.len()));
            self.sums.reserve(chunks.saturating_sub(self.sums.len()));
        }
    }

    /// The chunks of the last warp.
    fn warped(&self) -> &[Chunk] {
        &self.chunks[..self.used]
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
        estimator::motion_from(self, fi, fj, inits, cfg)
    }
}

impl Loops for MotionEstimator {
    fn load(&mut self, points: &[[f32; 4]]) {
        let n = points.len().div_ceil(CHUNK);
        self.reserve(n);
        self.used = n;
        for (pts, t) in points.chunks(CHUNK).zip(&mut self.template) {
            t.load(pts);
        }
    }

    fn warp(&mut self, t: &Pose, level: &ImageLevel, p: &Params) -> usize {
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
            noise: p.noise,
            photometric: p.photometric,
        };
        let n = self.used;
        let (template, bufs) = (&self.template[..n], &mut self.chunks[..n]);
        if !splits(n) {
            for (q, buf) in template.iter().zip(bufs.iter_mut()) {
                warp.run(q, buf);
            }
        } else {
            template
                .par_iter()
                .zip(bufs.par_iter_mut())
                .with_min_len(MIN_CHUNKS_PER_TASK)
                .for_each(|(q, buf)| warp.run(q, buf));
        }
        self.valid()
    }

    fn valid(&self) -> usize {
        self.warped().iter().map(|c| c.n).sum()
    }

    fn counts(&self) -> (usize, usize) {
        let two = self.warped().iter().map(|c| c.two).sum();
        (two, self.valid() - two)
    }

    fn moments(&self, weighting: Weighting) -> PassSums {
        let mut sums = [0.0f64; 4];
        for c in self.warped() {
            let p = robust::moments(c, weighting);
            for k in 0..4 {
                sums[k] += p[k];
            }
        }
        sums
    }

    fn pass(&mut self, wh: &Whitener, weighting: Weighting) -> (PassSums, f64) {
        let chunks = &self.chunks[..self.used];
        map_chunks(chunks, &mut self.sums, |c| robust::pass(c, wh, weighting));
        let mut total = [0.0f64; 4];
        let mut cost = 0.0;
        for (part, e) in &self.sums {
            for k in 0..4 {
                total[k] += part[k];
            }
            cost += e;
        }
        (total, cost)
    }

    fn cost(&mut self, wh: &Whitener) -> f64 {
        let chunks = &self.chunks[..self.used];
        map_chunks(chunks, &mut self.errors, |c| robust::cost(c, wh));
        let mut total = 0.0;
        for e in &self.errors {
            total += e;
        }
        total
    }

    fn depth_spread(&mut self) -> DepthSpread {
        self.spread.clear();
        for c in &self.chunks[..self.used] {
            // Every 4th residual: enough for 20 bins, a quarter of the cost.
            for k in (0..c.n).step_by(4) {
                let (rz, sz) = (c.rz[k], c.sz[k]);
                if rz.is_finite() && sz > 0.0 {
                    self.spread.add(c.z[k], rz / sz);
                }
            }
        }
        self.spread.spread()
    }

    fn normal_equations(&mut self, level: &ImageLevel, wh: &Whitener) -> NormalEquations {
        let cam = level.camera();
        let f = [cam.fx as f32, cam.fy as f32];
        let chunks = &self.chunks[..self.used];
        map_chunks(chunks, &mut self.partial, |c| normal::chunk(c, wh, f));
        let mut total = NormalEquations::default();
        for part in &self.partial {
            total.merge(part);
        }
        total
    }
}

/// The bytes [`MotionEstimator::with_capacity`]`(max_points)` holds: per chunk of
/// [`CHUNK`] points, the template's four coordinates, the chunk's residual arrays and
/// its warp scratch, and the per-chunk sums (counted twice: rayon may collect them
/// into a fresh vector).
pub(crate) fn scratch_bytes(max_points: usize) -> usize {
    let chunks = max_points.div_ceil(CHUNK);
    let per_point = 4 * size_of::<f32>() // template x, y, z, i
        + 13 * size_of::<f32>() // ri rz sz gx gy dx dy x y z cell ax ay
        + size_of::<crate::prepare::Sample>(); // tmp
    let per_chunk_sums =
        size_of::<NormalEquations>() + size_of::<f64>() + size_of::<(PassSums, f64)>();
    chunks * (CHUNK.next_multiple_of(lanes::LANES) * per_point + 2 * per_chunk_sums)
        + SpreadHistogram::BYTES
}

/// True when a loop over `chunks` chunks is worth handing to rayon: each of at least
/// two tasks gets [`MIN_CHUNKS_PER_TASK`] chunks.
fn splits(chunks: usize) -> bool {
    chunks >= 2 * MIN_CHUNKS_PER_TASK
}

/// `out[k] = f(&chunks[k])`, with rayon when there are enough chunks to split. The
/// results stay in chunk order, so what the caller sums does not depend on the
/// number of threads.
fn map_chunks<C: Sync, T: Send>(chunks: &[C], out: &mut Vec<T>, f: impl Fn(&C) -> T + Sync + Send) {
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
