//! The Gauss-Newton system of one linearisation and the Jacobians that fill it.

use nalgebra::{Matrix6, Vector6};

use super::warp::Residual;

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
pub(super) type JRow = [f32; 8];

/// Accumulates weighted Jacobian rows in single precision over short runs and
/// flushes them into double precision, keeping both speed and accuracy. Each row
/// of `JᵀWJ` is updated whole (eight lanes, the lower triangle too, which is never
/// read): every upper-triangle entry sees exactly the operations of a scalar loop.
pub(super) struct Accumulator {
    h: [JRow; 6],
    g: JRow,
    run: usize,
    total: NormalEquations,
}

impl Accumulator {
    const RUN: usize = 128;

    pub(super) fn new() -> Self {
        Accumulator {
            h: [[0.0; 8]; 6],
            g: [0.0; 8],
            run: 0,
            total: NormalEquations::default(),
        }
    }

    #[inline(always)]
    pub(super) fn add(&mut self, j: &JRow, r: f32, w: f32) {
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
    pub(super) fn end_pixel(&mut self) {
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

    pub(super) fn finish(mut self) -> NormalEquations {
        self.flush();
        self.total
    }
}

/// The Jacobians of the photometric and (when present) scaled depth residuals of
/// one warped point with respect to a left perturbation `exp(δ) T`:
/// `J_I = ∇I · ∂π/∂p · [I | −[p]×]` and `J_Z = s (∇D · ∂π/∂p − e_z) · [I | −[p]×]`,
/// with `s` the depth residual's gain (held fixed, as IRLS holds a weight fixed).
#[inline(always)]
pub(super) fn jacobians(r: &Residual, fx: f32, fy: f32) -> (JRow, Option<JRow>) {
    let [x, y, z] = r.p;
    let iz = 1.0 / z;
    let a = [
        r.gx * fx * iz,
        r.gy * fy * iz,
        -(r.gx * fx * x + r.gy * fy * y) * iz * iz,
    ];
    let jz = r.rz.is_finite().then(|| {
        let s = r.sz;
        let b = [
            s * r.dx * fx * iz,
            s * r.dy * fy * iz,
            s * (-(r.dx * fx * x + r.dy * fy * y) * iz * iz - 1.0),
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
