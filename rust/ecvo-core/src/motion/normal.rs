//! The Gauss-Newton system of one linearisation, and its accumulation over a chunk
//! of residuals in [`LANES`]-wide blocks.

use nalgebra::{Matrix6, Vector6};

use super::lanes::{self, LANES, V};
use super::robust::weigh;
use super::warp::Chunk;
use crate::prepare::simd::multiversion;
use crate::scale::Whitener;

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

/// Points per run of single-precision sums (each lane adds `RUN / LANES` points)
/// before they are flushed into double precision.
const RUN: usize = 128;

/// Entries of the upper triangle of `JᵀWJ`.
const H: usize = 21;

/// The normal equations of a chunk (`count` residuals) at the scale `wh`; `f` is
/// (fx, fy) of the level. `error` is left 0.
pub(super) fn chunk(c: &Chunk, wh: &Whitener, f: [f32; 2]) -> NormalEquations {
    let n = c.padded();
    let mut ne = accumulate(
        &c.ri[..n],
        &c.rz[..n],
        &c.sz[..n],
        &c.gx[..n],
        &c.gy[..n],
        &c.dx[..n],
        &c.dy[..n],
        &c.x[..n],
        &c.y[..n],
        &c.z[..n],
        wh,
        &f,
    );
    ne.count = c.n;
    ne
}

multiversion! {
    /// `JᵀWJ` and `JᵀWr` of whitened residuals, summed by lane in f32 over runs of
    /// [`RUN`] points, by lane in f64 across runs, then lane after lane.
    fn accumulate(
        ri: &[f32],
        rz: &[f32],
        sz: &[f32],
        gx: &[f32],
        gy: &[f32],
        dx: &[f32],
        dy: &[f32],
        x: &[f32],
        y: &[f32],
        z: &[f32],
        wh: &Whitener,
        f: &[f32; 2],
    ) -> NormalEquations = accumulate_kernel;
}

#[inline(always)]
fn accumulate_kernel(
    ri: &[f32],
    rz: &[f32],
    sz: &[f32],
    gx: &[f32],
    gy: &[f32],
    dx: &[f32],
    dy: &[f32],
    x: &[f32],
    y: &[f32],
    z: &[f32],
    wh: &Whitener,
    f: &[f32; 2],
) -> NormalEquations {
    let n = ri.len();
    let mut total = NormalEquations::default();
    let mut h64 = [lanes::W::default(); H];
    let mut g64 = [lanes::W::default(); 6];
    let zero = lanes::splat(0.0);
    let (fx, fy) = (lanes::splat(f[0]), lanes::splat(f[1]));
    for start in (0..n).step_by(RUN) {
        let mut h = [zero; H];
        let mut g = [zero; 6];
        for b in (start..n.min(start + RUN)).step_by(LANES) {
            let r = lanes::load(ri, b);
            let q = weigh(wh, r, lanes::load(rz, b));
            let p = [lanes::load(x, b), lanes::load(y, b), lanes::load(z, b)];
            let (ji, jz) = jacobians(
                p,
                [lanes::load(gx, b), lanes::load(gy, b)],
                [lanes::load(dx, b), lanes::load(dy, b)],
                lanes::load(sz, b),
                fx,
                fy,
            );
            // L r and L J with Σ⁻¹ = Lᵀ L: two whitened rows; without depth the
            // second is 0 and the first is l1d J_I.
            let l1 = lanes::select(q.two, lanes::splat(wh.l11), lanes::splat(wh.l1d));
            let l12 = lanes::select(q.two, lanes::splat(wh.l12), zero);
            let jz: [V; 6] = std::array::from_fn(|k| lanes::select(q.two, jz[k], zero));
            let a: [V; 6] =
                std::array::from_fn(|k| lanes::add(lanes::mul(l1, ji[k]), lanes::mul(l12, jz[k])));
            let c: [V; 6] = std::array::from_fn(|k| lanes::mul(lanes::splat(wh.l22), jz[k]));
            add_row(&mut h, &mut g, &a, q.a, q.w);
            add_row(&mut h, &mut g, &c, q.b, q.w);
        }
        for k in 0..H {
            lanes::flush(&mut h64[k], &h[k]);
        }
        for i in 0..6 {
            lanes::flush(&mut g64[i], &g[i]);
        }
    }
    total.h = h64.map(|t| lanes::sum(&t));
    total.g = g64.map(|t| lanes::sum(&t));
    total
}

/// `h += w jᵀj` (upper triangle) and `g += w jᵀ r` for one whitened row per lane.
#[inline(always)]
fn add_row(h: &mut [V; H], g: &mut [V; 6], j: &[V; 6], r: V, w: V) {
    let wj: [V; 6] = std::array::from_fn(|k| lanes::mul(w, j[k]));
    let mut k = 0;
    for a in 0..6 {
        for b in a..6 {
            lanes::acc(&mut h[k], lanes::mul(wj[a], j[b]));
            k += 1;
        }
        lanes::acc(&mut g[a], lanes::mul(wj[a], r));
    }
}

/// The Jacobians of the photometric and scaled depth residuals of a block of warped
/// points `p` with respect to a left perturbation `exp(δ) T`:
/// `J_I = ∇I · ∂π/∂p · [I | −[p]×]` and `J_Z = s (∇D · ∂π/∂p − e_z) · [I | −[p]×]`,
/// with `s` the depth residual's gain (held fixed, as IRLS holds a weight fixed).
/// `J_Z` is garbage (NaN) where the depth is missing.
#[inline(always)]
pub(super) fn jacobians(p: [V; 3], gi: [V; 2], gz: [V; 2], s: V, fx: V, fy: V) -> ([V; 6], [V; 6]) {
    use lanes::{add, mul, splat, sub};
    let [x, y, z] = p;
    let iz = lanes::div(splat(1.0), z);
    let iz2 = |v: V| mul(mul(v, iz), iz);
    let neg = lanes::neg;
    let a = [
        mul(mul(gi[0], fx), iz),
        mul(mul(gi[1], fy), iz),
        iz2(neg(add(mul(mul(gi[0], fx), x), mul(mul(gi[1], fy), y)))),
    ];
    let b = [
        mul(mul(mul(s, gz[0]), fx), iz),
        mul(mul(mul(s, gz[1]), fy), iz),
        mul(
            s,
            sub(
                iz2(neg(add(mul(mul(gz[0], fx), x), mul(mul(gz[1], fy), y)))),
                splat(1.0),
            ),
        ),
    ];
    (twist_row(a, p), twist_row(b, p))
}

/// `a · [I | −[p]×] = [a, p × a]`.
#[inline(always)]
fn twist_row(a: [V; 3], p: [V; 3]) -> [V; 6] {
    use lanes::{mul, sub};
    [
        a[0],
        a[1],
        a[2],
        sub(mul(p[1], a[2]), mul(p[2], a[1])),
        sub(mul(p[2], a[0]), mul(p[0], a[2])),
        sub(mul(p[0], a[1]), mul(p[1], a[0])),
    ]
}
