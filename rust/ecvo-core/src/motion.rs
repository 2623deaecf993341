//! `MOTION(Fi, Fj, Tinit)`: dense direct alignment of intensity and depth.
//!
//! Following Tykkälä et al. with the weighting of Kerl et al., as the paper does:
//! every valid template point `q` of the reference frame `Fj` is moved into the
//! current frame `Fi` by `T = T_{j→i}` and projected to `u' = π(T q)`; there
//!
//! - the photometric residual is `r_I = I_i(u') − I_j(q)` (intensities in [0, 1]),
//! - the geometric residual is `r_Z = D_i(u') − [T q]_z` (metres), scaled by λ,
//!
//! and both share one weight from a bivariate t-distribution (ν = 5) on
//! `e² = r_I² + λ² r_Z²`, whose scale is re-estimated every iteration. Gauss-Newton
//! on a left perturbation `T ← exp(δ) T` runs coarse to fine; a step that raises the
//! error is rejected and ends its level. The result reports `T_{i,j} = T⁻¹`, the
//! motion that maps camera `i` coordinates into camera `j` coordinates.

use nalgebra::{Matrix6, SymmetricEigen, Vector6};
use rayon::prelude::*;

use crate::Pose;
use crate::config::MotionConfig;
use crate::prepare::{PreparedFrame, Sample};
use crate::se3;

/// The most coarse-to-fine steps a schedule may have.
pub const MAX_STEPS: usize = 8;

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
    /// `JᵀWJ` at the finest step: the information matrix of the twist `[v; ω]`.
    pub information: Matrix6<f64>,
    /// Converged, ran out of iterations, or failed.
    pub status: Status,
}

impl MotionResult {
    /// True unless the estimate failed.
    pub fn is_ok(&self) -> bool {
        !matches!(self.status, Status::Failed(_))
    }
}

/// The Gauss-Newton system `JᵀWJ δ = −JᵀWr` of one linearisation, with its error.
/// `merge` adds two partial systems, which is what a parallel reduction needs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NormalEquations {
    /// Upper triangle of `JᵀWJ`, row by row.
    pub h: [f64; 21],
    /// `JᵀWr`.
    pub g: [f64; 6],
    /// `Σ w e²`.
    pub error: f64,
    /// Number of residual pixels.
    pub count: usize,
}

impl NormalEquations {
    /// Adds another partial system.
    pub fn merge(&mut self, o: &NormalEquations) {
        for k in 0..21 {
            self.h[k] += o.h[k];
        }
        for k in 0..6 {
            self.g[k] += o.g[k];
        }
        self.error += o.error;
        self.count += o.count;
    }

    /// `JᵀWJ` as a full symmetric matrix.
    pub fn hessian(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        let mut k = 0;
        for r in 0..6 {
            for c in r..6 {
                m[(r, c)] = self.h[k];
                m[(c, r)] = self.h[k];
                k += 1;
            }
        }
        m
    }

    /// The Gauss-Newton step `δ = −(JᵀWJ)⁻¹ JᵀWr`, or `None` when the system is
    /// not positive definite.
    pub fn solve(&self) -> Option<Vector6<f64>> {
        let chol = self.hessian().cholesky()?;
        let step = -chol.solve(&Vector6::from_column_slice(&self.g));
        step.iter().all(|x| x.is_finite()).then_some(step)
    }
}

/// A Jacobian row `[v; ω]` padded to eight lanes (the last two are 0), so that the
/// accumulation runs on whole SIMD vectors.
type JRow = [f32; 8];

/// Accumulates weighted Jacobian rows in single precision over short runs and
/// flushes them into double precision, keeping both speed and accuracy. Each row
/// of `JᵀWJ` is updated whole (eight lanes, the lower triangle too, which is never
/// read): every upper-triangle entry sees exactly the operations of a scalar loop.
struct Accumulator {
    h: [JRow; 6],
    g: JRow,
    run: usize,
    total: NormalEquations,
}

impl Accumulator {
    const RUN: usize = 128;

    fn new() -> Self {
        Accumulator {
            h: [[0.0; 8]; 6],
            g: [0.0; 8],
            run: 0,
            total: NormalEquations::default(),
        }
    }

    #[inline(always)]
    fn add(&mut self, j: &JRow, r: f32, w: f32) {
        let wj: JRow = std::array::from_fn(|b| w * j[b]);
        for (row, &wa) in self.h.iter_mut().zip(&wj) {
            for (h, &jb) in row.iter_mut().zip(j) {
                *h += wa * jb;
            }
        }
        for (g, &wa) in self.g.iter_mut().zip(&wj) {
            *g += wa * r;
        }
    }

    #[inline(always)]
    fn end_pixel(&mut self) {
        self.total.count += 1;
        self.run += 1;
        if self.run == Self::RUN {
            self.flush();
        }
    }

    fn flush(&mut self) {
        let mut k = 0;
        for a in 0..6 {
            for b in a..6 {
                self.total.h[k] += self.h[a][b] as f64;
                k += 1;
            }
            self.total.g[a] += self.g[a] as f64;
        }
        self.h = [[0.0; 8]; 6];
        self.g = [0.0; 8];
        self.run = 0;
    }

    fn finish(mut self) -> NormalEquations {
        self.flush();
        self.total
    }
}

/// One warped template point: its residuals and what its Jacobian needs.
#[derive(Clone, Copy, Debug, Default)]
struct Residual {
    /// Photometric residual.
    ri: f32,
    /// Depth residual, NaN when the current depth is missing there.
    rz: f32,
    /// `e² = r_I² + λ² r_Z²`.
    e2: f32,
    /// Intensity gradient at `u'` (per pixel).
    gx: f32,
    gy: f32,
    /// Depth gradient at `u'` (metres per pixel).
    dx: f32,
    dy: f32,
    /// The warped point `T q` in current-camera coordinates.
    p: [f32; 3],
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

/// Runs `MOTION` and keeps its scratch buffers between calls, so that a warm
/// estimator does not allocate.
///
/// The per-point work (warping, t-scale passes, weighted error, normal equations)
/// runs over fixed chunks of [`CHUNK`] template points, with rayon (in whatever pool
/// the caller is in) once a template is large enough. The per-chunk partial sums
/// are added in chunk order.
#[derive(Debug, Default)]
pub struct MotionEstimator {
    /// Residuals of each chunk of template points.
    chunks: Vec<Vec<Residual>>,
    /// Per-chunk normal equations, merged in order.
    partial: Vec<NormalEquations>,
    /// Per-chunk weighted errors, added in order.
    errors: Vec<f64>,
    /// Per-chunk sums of a t-scale pass, added in order.
    sums: Vec<f64>,
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
        let mut result = MotionResult {
            pose: *t_init,
            iterations: [0; MAX_STEPS],
            steps: cfg.levels.len().min(MAX_STEPS),
            error: f64::NAN,
            valid_pixels: 0,
            information: Matrix6::zeros(),
            status: Status::Failed(Failure::TooFewPixels),
        };
        if !se3::is_finite(t_init) {
            result.status = Status::Failed(Failure::NotFinite);
            return result;
        }
        let lambda2 = (cfg.depth_gain * cfg.depth_gain) as f32;
        let nu = cfg.t_dof as f32;
        // T_{j→i}: moves reference points into the current camera.
        let mut t = t_init.inverse();
        let mut finest: Option<NormalEquations> = None;
        let mut finest_hit_max = false;
        for (k, step) in cfg.levels.iter().enumerate().take(MAX_STEPS) {
            let (Some(level), Some(template)) =
                (fi.levels.get(step.pyramid_level), fj.templates.get(k))
            else {
                break;
            };
            let last = k + 1 == result.steps;
            let mut accepted: Option<NormalEquations> = None;
            let mut prev_t = t;
            let mut hit_max = true;
            let mut sigma2 = None;
            for it in 0..step.max_iterations {
                let n = self.residuals_at(&t, &template.points, level, lambda2);
                if n < MIN_STEP_RESIDUALS {
                    hit_max = false;
                    break;
                }
                let s2 = t_scale(&self.chunks[..self.used], &mut self.sums, nu, sigma2);
                sigma2 = Some(s2);
                // The error first: a step that made things worse needs no Jacobians.
                let error = self.weighted_error(s2, nu);
                let err = error / n as f64;
                if accepted.is_some_and(|a| err > a.error / a.count as f64) {
                    // The last step made things worse: undo it and end this level.
                    t = prev_t;
                    hit_max = false;
                    break;
                }
                let ne = self.normal_equations(level, s2, nu, lambda2, error);
                result.iterations[k] = it + 1;
                accepted = Some(ne);
                let Some(delta) = ne.solve() else {
                    hit_max = false;
                    break;
                };
                prev_t = t;
                t = se3::compose(&se3::exp(&delta), &t);
                let small = delta.fixed_rows::<3>(0).norm() < cfg.min_update
                    && delta.fixed_rows::<3>(3).norm() < cfg.min_update;
                if small {
                    hit_max = false;
                    break;
                }
            }
            if last {
                finest = accepted;
                finest_hit_max = hit_max;
            }
        }

        let Some(ne) = finest else {
            return result;
        };
        result.error = ne.error / ne.count as f64;
        result.valid_pixels = ne.count;
        result.information = ne.hessian();
        let pose = t.inverse();
        result.status = if ne.count < cfg.min_valid_pixels {
            Status::Failed(Failure::TooFewPixels)
        } else if !se3::is_finite(&pose) {
            Status::Failed(Failure::NotFinite)
        } else if is_degenerate(&result.information) {
            Status::Failed(Failure::Degenerate)
        } else if pose.translation.vector.norm() > cfg.max_translation_m
            || se3::angle(&pose).to_degrees() > cfg.max_rotation_deg
        {
            Status::Failed(Failure::TooLarge)
        } else if finest_hit_max {
            Status::MaxIterations
        } else {
            Status::Converged
        };
        if result.is_ok() {
            result.pose = pose;
        }
        result
    }

    /// Warps the template into `level` under `t` and stores the residuals; returns
    /// how many template points produced a photometric residual.
    fn residuals_at(
        &mut self,
        t: &Pose,
        points: &[[f32; 4]],
        level: &crate::prepare::ImageLevel,
        lambda2: f32,
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
            lambda2,
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
        self.chunks[..n].iter().map(Vec::len).sum()
    }

    /// `Σ w e²` over the stored residuals for the scale `sigma2` (pixel order within a
    /// chunk, chunk order across them).
    fn weighted_error(&mut self, sigma2: f32, nu: f32) -> f64 {
        let inv_s2 = 1.0 / sigma2;
        let sum = |res: &Vec<Residual>| {
            let mut e = 0.0f64;
            for r in res {
                e += (t_weight(r, nu, inv_s2) * r.e2) as f64;
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

    /// Weights the stored residuals and accumulates the normal equations; `error` is
    /// their [`Self::weighted_error`], computed first.
    fn normal_equations(
        &mut self,
        level: &crate::prepare::ImageLevel,
        sigma2: f32,
        nu: f32,
        lambda2: f32,
        error: f64,
    ) -> NormalEquations {
        let cam = level.camera();
        let (fx, fy) = (cam.fx as f32, cam.fy as f32);
        let inv_s2 = 1.0 / sigma2;
        let accumulate = |res: &Vec<Residual>| {
            let mut acc = Accumulator::new();
            for r in res {
                let w = t_weight(r, nu, inv_s2);
                let (ji, jz) = jacobians(r, fx, fy);
                acc.add(&ji, r.ri, w);
                if let Some(jz) = jz {
                    acc.add(&jz, r.rz, w * lambda2);
                }
                acc.end_pixel();
            }
            acc.finish()
        };
        map_chunks(&self.chunks[..self.used], &mut self.partial, accumulate);
        let mut total = NormalEquations::default();
        for p in &self.partial {
            total.merge(p);
        }
        total.error = error;
        total
    }
}

/// The t-distribution weight of a residual for the scale `1 / inv_s2` (Kerl et al.):
/// `(ν + d) / (ν + e² / σ²)`, with `d` its dimension (2 with depth, 1 without).
#[inline(always)]
fn t_weight(r: &Residual, nu: f32, inv_s2: f32) -> f32 {
    let dims = if r.rz.is_finite() { 2.0 } else { 1.0 };
    (nu + dims) / (nu + r.e2 * inv_s2)
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

/// The warp of one linearisation: `T_{j→i}`, the current level's intrinsics and
/// samples. Shared by the chunks of the parallel loop.
struct Warp<'a> {
    r: [[f32; 4]; 3],
    /// fx, fy, cx, cy.
    f: [f32; 4],
    w: usize,
    /// Largest u and v a bilinear lookup may start from (exclusive).
    max: [f32; 2],
    samples: &'a [Sample],
    lambda2: f32,
}

impl Warp<'_> {
    /// Warps `points` and stores the residuals of those that land inside the level.
    fn run(&self, points: &[[f32; 4]], out: &mut Vec<Residual>) {
        let r = &self.r;
        let [fx, fy, cx, cy] = self.f;
        let [umax, vmax] = self.max;
        let lambda2 = self.lambda2;
        out.clear();
        for q in points {
            let x = r[0][0] * q[0] + r[0][1] * q[1] + r[0][2] * q[2] + r[0][3];
            let y = r[1][0] * q[0] + r[1][1] * q[1] + r[1][2] * q[2] + r[1][3];
            let z = r[2][0] * q[0] + r[2][1] * q[1] + r[2][2] * q[2] + r[2][3];
            if z <= 1e-3 {
                continue;
            }
            let iz = 1.0 / z;
            let u = fx * x * iz + cx;
            let v = fy * y * iz + cy;
            // `!(a >= b)` also rejects NaN.
            if !(u >= 0.0 && v >= 0.0 && u < umax && v < vmax) {
                continue;
            }
            let s = bilinear(self.samples, self.w, u, v);
            let ri = s[0] - q[3];
            let rz = s[3] - z;
            let depth_ok = rz.is_finite() && s[4].is_finite() && s[5].is_finite();
            let rz = if depth_ok { rz } else { f32::NAN };
            let e2 = if depth_ok {
                ri * ri + lambda2 * rz * rz
            } else {
                ri * ri
            };
            out.push(Residual {
                ri,
                rz,
                e2,
                gx: s[1],
                gy: s[2],
                dx: s[4],
                dy: s[5],
                p: [x, y, z],
            });
        }
    }
}

/// The Jacobians of the photometric and (when present) depth residuals of one
/// warped point with respect to a left perturbation `exp(δ) T`:
/// `J_I = ∇I · ∂π/∂p · [I | −[p]×]` and `J_Z = (∇D · ∂π/∂p − e_z) · [I | −[p]×]`.
#[inline(always)]
fn jacobians(r: &Residual, fx: f32, fy: f32) -> (JRow, Option<JRow>) {
    let [x, y, z] = r.p;
    let iz = 1.0 / z;
    let a = [
        r.gx * fx * iz,
        r.gy * fy * iz,
        -(r.gx * fx * x + r.gy * fy * y) * iz * iz,
    ];
    let jz = r.rz.is_finite().then(|| {
        let b = [
            r.dx * fx * iz,
            r.dy * fy * iz,
            -(r.dx * fx * x + r.dy * fy * y) * iz * iz - 1.0,
        ];
        twist_row(b, r.p)
    });
    (twist_row(a, r.p), jz)
}

/// `a · [I | −[p]×] = [a, p × a]`, padded.
#[inline(always)]
fn twist_row(a: [f32; 3], p: [f32; 3]) -> JRow {
    [
        a[0],
        a[1],
        a[2],
        p[1] * a[2] - p[2] * a[1],
        p[2] * a[0] - p[0] * a[2],
        p[0] * a[1] - p[1] * a[0],
        0.0,
        0.0,
    ]
}

/// Bilinear lookup of all channels at `(u, v)`; the caller guarantees
/// `0 <= u < w - 1` and `0 <= v < h - 1`. Missing depth (NaN) propagates.
#[inline(always)]
fn bilinear(s: &[Sample], w: usize, u: f32, v: f32) -> Sample {
    let (x0, y0) = (u as usize, v as usize);
    let (ax, ay) = (u - x0 as f32, v - y0 as f32);
    let i = y0 * w + x0;
    let (p00, p01, p10, p11) = (&s[i], &s[i + 1], &s[i + w], &s[i + w + 1]);
    let (w00, w01, w10, w11) = (
        (1.0 - ax) * (1.0 - ay),
        ax * (1.0 - ay),
        (1.0 - ax) * ay,
        ax * ay,
    );
    std::array::from_fn(|c| w00 * p00[c] + w01 * p01[c] + w10 * p10[c] + w11 * p11[c])
}

/// The scale σ² of a bivariate t-distribution with `nu` degrees of freedom fitted
/// to the residuals (in chunks, see [`CHUNK`]) by fixed-point iteration (Kerl et
/// al.), started from `start` (the previous iteration's scale) when given; pixels
/// with only a photometric residual count as one dimension. A pass sums each chunk
/// (in f32 over short runs, then in f64), with rayon when there are enough chunks,
/// and adds the chunks in order; `sums` is scratch.
fn t_scale(chunks: &[Vec<Residual>], sums: &mut Vec<f64>, nu: f32, start: Option<f32>) -> f32 {
    let dims: usize = chunks
        .iter()
        .flatten()
        .map(|r| if r.rz.is_finite() { 2 } else { 1 })
        .sum();
    if dims == 0 {
        return 1.0;
    }
    let dims = dims as f64;
    let mut s2 = match start {
        Some(s) if s > 0.0 && s.is_finite() => s as f64,
        _ => (chunks.iter().flatten().map(|r| r.e2 as f64).sum::<f64>() / dims).max(1e-12),
    };
    for _ in 0..20 {
        let inv = (1.0 / s2) as f32;
        let pass = |c: &Vec<Residual>| {
            let mut acc = 0.0f64;
            for run in c.chunks(256) {
                let mut part = 0.0f32;
                for r in run {
                    let d = if r.rz.is_finite() { 2.0 } else { 1.0 };
                    part += r.e2 * (nu + d) / (nu + r.e2 * inv);
                }
                acc += part as f64;
            }
            acc
        };
        map_chunks(chunks, sums, pass);
        let mut acc = 0.0f64;
        for p in sums.iter() {
            acc += p;
        }
        let next = (acc / dims).max(1e-12);
        let done = (next - s2).abs() < 1e-3 * s2;
        s2 = next;
        if done {
            break;
        }
    }
    s2 as f32
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::prepare::ImageLevel;

    /// A level whose intensity and depth are affine in the pixel coordinates, so that
    /// central differences and bilinear interpolation are exact and finite
    /// differences of the residuals must match the analytic Jacobians.
    fn affine_level(fy: f64) -> ImageLevel {
        let cam = Camera {
            width: 64,
            height: 48,
            fx: 60.0,
            fy,
            cx: 31.5,
            cy: 23.5,
            depth_scale: 1000.0,
        };
        let (gx, gy, dx, dy) = (0.004f32, -0.003f32, 0.006f32, 0.004f32);
        let samples = (0..cam.pixels())
            .map(|i| {
                let (u, v) = ((i % cam.width) as f32, (i / cam.width) as f32);
                [
                    0.3 + gx * u + gy * v,
                    gx,
                    gy,
                    1.5 + dx * u + dy * v,
                    dx,
                    dy,
                    0.0,
                    0.0,
                ]
            })
            .collect();
        ImageLevel {
            camera: Some(cam),
            samples,
        }
    }

    #[test]
    fn analytic_jacobians_match_finite_differences() {
        for fy in [58.0, -58.0] {
            let level = affine_level(fy);
            let cam = *level.camera();
            let points: Vec<[f32; 4]> = (0..40)
                .map(|k| {
                    let (u, v, z) = (
                        10.0 + (k % 8) as f64 * 5.0,
                        8.0 + (k / 8) as f64 * 6.0,
                        1.2 + 0.02 * k as f64,
                    );
                    [
                        ((u - cam.cx) / cam.fx * z) as f32,
                        ((v - cam.cy) / cam.fy * z) as f32,
                        z as f32,
                        0.5,
                    ]
                })
                .collect();
            let t = se3::exp(&Vector6::new(0.02, -0.01, 0.03, 0.01, -0.02, 0.015));
            let mut est = MotionEstimator::new();
            let n = est.residuals_at(&t, &points, &level, 3.24);
            assert_eq!(n, points.len());
            let base: Vec<Residual> = est.residuals().copied().collect();
            let h = 1e-4;
            for k in 0..6 {
                let mut d = Vector6::zeros();
                d[k] = h;
                let plus = {
                    est.residuals_at(&(se3::exp(&d) * t), &points, &level, 3.24);
                    est.residuals().copied().collect::<Vec<_>>()
                };
                let minus = {
                    est.residuals_at(&(se3::exp(&-d) * t), &points, &level, 3.24);
                    est.residuals().copied().collect::<Vec<_>>()
                };
                for (i, r) in base.iter().enumerate() {
                    let (ji, jz) = jacobians(r, cam.fx as f32, cam.fy as f32);
                    let fd_i = (plus[i].ri - minus[i].ri) as f64 / (2.0 * h);
                    let fd_z = (plus[i].rz - minus[i].rz) as f64 / (2.0 * h);
                    let jz = jz.expect("depth is valid everywhere");
                    assert!(
                        (fd_i - ji[k] as f64).abs() < 2e-3 * (1.0 + fd_i.abs()),
                        "fy {fy} J_I[{k}] point {i}: fd {fd_i} analytic {}",
                        ji[k]
                    );
                    assert!(
                        (fd_z - jz[k] as f64).abs() < 2e-3 * (1.0 + fd_z.abs()),
                        "fy {fy} J_Z[{k}] point {i}: fd {fd_z} analytic {}",
                        jz[k]
                    );
                }
            }
        }
    }

    #[test]
    fn t_scale_fits_a_known_spread() {
        // Residuals drawn from ±s with no outliers: the t-scale sits near s².
        let s = 0.05f32;
        let res: Vec<Residual> = (0..1000)
            .map(|i| {
                let ri = if i % 2 == 0 { s } else { -s };
                Residual {
                    ri,
                    rz: f32::NAN,
                    e2: ri * ri,
                    ..Residual::default()
                }
            })
            .collect();
        let mut sums = Vec::new();
        let s2 = t_scale(std::slice::from_ref(&res), &mut sums, 5.0, None);
        assert!((s2 / (s * s) - 1.0).abs() < 0.05, "sigma² {s2}");
        assert_eq!(t_scale(&[], &mut sums, 5.0, None), 1.0);
        let warm = t_scale(std::slice::from_ref(&res), &mut sums, 5.0, Some(0.01));
        assert!((warm / s2 - 1.0).abs() < 0.01, "warm start {warm} vs {s2}");
    }

    #[test]
    fn normal_equations_merge_and_solve() {
        let mut a = NormalEquations::default();
        let mut k = 0;
        for r in 0..6 {
            for c in r..6 {
                a.h[k] = if r == c { 2.0 } else { 0.0 };
                k += 1;
            }
        }
        a.g = [2.0, -4.0, 0.0, 0.0, 6.0, 0.0];
        let b = a;
        a.merge(&b);
        let step = a.solve().unwrap();
        assert_eq!(step.as_slice(), &[-1.0, 2.0, 0.0, 0.0, -3.0, 0.0]);
        assert!(NormalEquations::default().solve().is_none());
    }
}
