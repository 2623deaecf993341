//! The Gauss-Newton system of one linearisation, and its accumulation over a chunk
//! of residuals in [`LANES`]-wide blocks.

use nalgebra::{Matrix6, Vector6};

use super::lanes::{LANES, Lanes, lanes_multiversion};
use super::robust::{RUN, weigh};
use super::warp::Chunk;
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

    /// The system with a prior term `info · |r|²` on the rotation added, `r` the
    /// rotation residual at the linearisation point (`δ = [v; ω]`, the rotation
    /// perturbed on the left, so `∂r/∂ω ≈ I`): `info` on the diagonal of the
    /// rotation block, `info · r` to `JᵀWr`, `info · |r|²` to the error.
    pub fn with_rotation_prior(&self, r: &nalgebra::Vector3<f64>, info: f64) -> NormalEquations {
        let mut ne = *self;
        // The diagonal (3,3), (4,4), (5,5) of the row-major upper triangle.
        for (k, d) in [15, 18, 20].into_iter().enumerate() {
            ne.h[d] += info;
            ne.g[3 + k] += info * r[k];
        }
        ne.error += info * r.norm_squared();
        ne
    }

    /// The Gauss-Newton step `δ = −(JᵀWJ)⁻¹ JᵀWr`, or `None` when the system is
    /// not positive definite.
    pub fn solve(&self) -> Option<Vector6<f64>> {
        let chol = self.hessian().cholesky()?;
        let step = -chol.solve(&Vector6::from_column_slice(&self.g));
        step.iter().all(|x| x.is_finite()).then_some(step)
    }
}

/// Entries of the upper triangle of `JᵀWJ`.
const H: usize = 21;

/// The normal equations of a chunk (`count` residuals) at the scale `wh`, with their
/// `Σ w d²` (the bits of [`super::robust::cost`]); `f` is (fx, fy) of the level.
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

lanes_multiversion! {
    /// `JᵀWJ`, `JᵀWr` and `Σ w d²` of whitened residuals, summed by lane in f32 over
    /// runs of [`RUN`] points, by lane in f64 across runs, then lane after lane.
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
fn accumulate_kernel<L: Lanes>(
    l: L,
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
    let mut h64 = [l.zero_w(); H];
    let mut g64 = [l.zero_w(); 6];
    let mut e64 = l.zero_w();
    let zero = l.splat(0.0);
    let (fx, fy) = (l.splat(f[0]), l.splat(f[1]));
    for start in (0..n).step_by(RUN) {
        let mut h = [zero; H];
        let mut g = [zero; 6];
        let mut e = zero;
        for b in (start..n.min(start + RUN)).step_by(LANES) {
            let r = l.load(ri, b);
            let q = weigh(l, wh, r, l.load(rz, b));
            l.acc(&mut e, l.mul(q.w, q.d2));
            let p = [l.load(x, b), l.load(y, b), l.load(z, b)];
            let (ji, jz) = jacobians(
                l,
                p,
                [l.load(gx, b), l.load(gy, b)],
                [l.load(dx, b), l.load(dy, b)],
                l.load(sz, b),
                fx,
                fy,
            );
            // L r and L J with Σ⁻¹ = Lᵀ L: two whitened rows; without depth the
            // second is 0 and the first is l1d J_I.
            let l1 = l.select(q.two, l.splat(wh.l11), l.splat(wh.l1d));
            let l12 = l.select(q.two, l.splat(wh.l12), zero);
            let jz: [L::V; 6] = std::array::from_fn(|k| l.select(q.two, jz[k], zero));
            let a: [L::V; 6] = std::array::from_fn(|k| l.add(l.mul(l1, ji[k]), l.mul(l12, jz[k])));
            let c: [L::V; 6] = std::array::from_fn(|k| l.mul(l.splat(wh.l22), jz[k]));
            add_row(l, &mut h, &mut g, &a, q.a, q.w);
            add_row(l, &mut h, &mut g, &c, q.b, q.w);
        }
        for k in 0..H {
            l.flush(&mut h64[k], &h[k]);
        }
        for i in 0..6 {
            l.flush(&mut g64[i], &g[i]);
        }
        l.flush(&mut e64, &e);
    }
    total.h = h64.map(|t| l.sum(&t));
    total.g = g64.map(|t| l.sum(&t));
    total.error = l.sum(&e64);
    total
}

/// `h += w jᵀj` (upper triangle) and `g += w jᵀ r` for one whitened row per lane.
#[inline(always)]
fn add_row<L: Lanes>(l: L, h: &mut [L::V; H], g: &mut [L::V; 6], j: &[L::V; 6], r: L::V, w: L::V) {
    let wj: [L::V; 6] = std::array::from_fn(|k| l.mul(w, j[k]));
    let mut k = 0;
    for a in 0..6 {
        for b in a..6 {
            l.acc(&mut h[k], l.mul(wj[a], j[b]));
            k += 1;
        }
        l.acc(&mut g[a], l.mul(wj[a], r));
    }
}

/// The Jacobians of the photometric and scaled depth residuals of a block of warped
/// points `p` with respect to a left perturbation `exp(δ) T`:
/// `J_I = ∇I · ∂π/∂p · [I | −[p]×]` and `J_Z = s (∇D · ∂π/∂p − e_z) · [I | −[p]×]`,
/// with `s` the depth residual's gain (held fixed, as IRLS holds a weight fixed).
/// `J_Z` is garbage (NaN) where the depth is missing.
#[inline(always)]
pub(super) fn jacobians<L: Lanes>(
    l: L,
    p: [L::V; 3],
    gi: [L::V; 2],
    gz: [L::V; 2],
    s: L::V,
    fx: L::V,
    fy: L::V,
) -> ([L::V; 6], [L::V; 6]) {
    let [x, y, z] = p;
    let iz = l.div(l.splat(1.0), z);
    let iz2 = |v: L::V| l.mul(l.mul(v, iz), iz);
    let a = [
        l.mul(l.mul(gi[0], fx), iz),
        l.mul(l.mul(gi[1], fy), iz),
        iz2(l.neg(l.add(l.mul(l.mul(gi[0], fx), x), l.mul(l.mul(gi[1], fy), y)))),
    ];
    let b = [
        l.mul(l.mul(l.mul(s, gz[0]), fx), iz),
        l.mul(l.mul(l.mul(s, gz[1]), fy), iz),
        l.mul(
            s,
            l.sub(
                iz2(l.neg(l.add(l.mul(l.mul(gz[0], fx), x), l.mul(l.mul(gz[1], fy), y)))),
                l.splat(1.0),
            ),
        ),
    ];
    (twist_row(l, a, p), twist_row(l, b, p))
}

/// `a · [I | −[p]×] = [a, p × a]`.
#[inline(always)]
fn twist_row<L: Lanes>(l: L, a: [L::V; 3], p: [L::V; 3]) -> [L::V; 6] {
    [
        a[0],
        a[1],
        a[2],
        l.sub(l.mul(p[1], a[2]), l.mul(p[2], a[1])),
        l.sub(l.mul(p[2], a[0]), l.mul(p[0], a[2])),
        l.sub(l.mul(p[0], a[1]), l.mul(p[1], a[0])),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// The prior lands on the rotation block's diagonal and the rotation rows of
    /// `JᵀWr`, nowhere else, and its step pulls the rotation onto the prior.
    #[test]
    fn the_rotation_prior_adds_to_the_rotation_block_only() {
        let mut ne = NormalEquations::default();
        let mut k = 0;
        for r in 0..6 {
            for c in r..6 {
                ne.h[k] = if r == c { 2.0 } else { 0.1 * (r + c) as f64 };
                k += 1;
            }
        }
        ne.g = [1.0, -1.0, 0.5, 0.2, -0.3, 0.4];
        ne.error = 3.0;
        let r = Vector3::new(0.01, -0.02, 0.03);
        let with = ne.with_rotation_prior(&r, 100.0);
        let dh = with.hessian() - ne.hessian();
        for i in 0..6 {
            for j in 0..6 {
                let want = if i == j && i >= 3 { 100.0 } else { 0.0 };
                assert_eq!(dh[(i, j)], want, "({i}, {j})");
            }
        }
        for i in 0..6 {
            let want = if i >= 3 { 100.0 * r[i - 3] } else { 0.0 };
            assert!((with.g[i] - ne.g[i] - want).abs() < 1e-12, "g[{i}]");
        }
        assert!((with.error - 3.0 - 100.0 * r.norm_squared()).abs() < 1e-12);
        // With images that say nothing about the rotation, the step undoes r.
        let mut blind = NormalEquations::default();
        for d in [0, 6, 11] {
            blind.h[d] = 1.0;
        }
        let step = blind.with_rotation_prior(&r, 1e4).solve().unwrap();
        for i in 0..3 {
            assert!((step[3 + i] + r[i]).abs() < 1e-12, "{step}");
        }
    }
}
