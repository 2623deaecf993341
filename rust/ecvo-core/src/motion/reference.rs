//! The per-point loops of `MOTION` as they were before the structure-of-arrays
//! rewrite: one `Residual` struct per warped point, summed point by point. Kept for
//! the tests, which run the same schedule ([`super::estimator`]) on both and compare
//! the poses.

use super::estimator::{Loops, Params};
use super::warp::NoiseGain;
use super::{CHUNK, NormalEquations};
use crate::Pose;
use crate::config::Weighting;
use crate::prepare::{ImageLevel, Sample};
use crate::scale::{self, PassSums, Whitener};

/// The old loops: residuals as structs, one vector per chunk.
#[derive(Debug, Default)]
pub(super) struct Reference {
    points: Vec<[f32; 4]>,
    chunks: Vec<Vec<Residual>>,
}

impl Reference {
    /// The residuals of the last warp, chunk after chunk.
    pub(super) fn residuals(&self) -> Vec<Residual> {
        self.chunks.iter().flatten().copied().collect()
    }
}

impl Loops for Reference {
    fn load(&mut self, points: &[[f32; 4]]) {
        self.points = points.to_vec();
    }

    fn warp(&mut self, t: &Pose, level: &ImageLevel, p: &Params) -> usize {
        let cam = level.camera();
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
        self.chunks.clear();
        for pts in self.points.chunks(CHUNK) {
            let mut buf = Vec::new();
            warp.run(pts, &mut buf);
            self.chunks.push(buf);
        }
        self.valid()
    }

    fn valid(&self) -> usize {
        self.chunks.iter().map(Vec::len).sum()
    }

    fn counts(&self) -> (usize, usize) {
        let (mut two, mut one) = (0, 0);
        for c in &self.chunks {
            let (t, o) = scale::count(c);
            two += t;
            one += o;
        }
        (two, one)
    }

    fn moments(&self, weighting: Weighting) -> PassSums {
        let mut sums = [0.0f64; 4];
        for c in &self.chunks {
            let p = scale::moments(c, weighting);
            for k in 0..4 {
                sums[k] += p[k];
            }
        }
        sums
    }

    fn pass(&mut self, wh: &Whitener, weighting: Weighting) -> (PassSums, f64) {
        let mut total = [0.0f64; 4];
        for c in &self.chunks {
            let part = scale::pass(c, wh, weighting);
            for k in 0..4 {
                total[k] += part[k];
            }
        }
        (total, self.cost(wh))
    }

    fn cost(&mut self, wh: &Whitener) -> f64 {
        let mut total = 0.0;
        for res in &self.chunks {
            let mut e = 0.0f64;
            for run in res.chunks(128) {
                let mut part = 0.0f32;
                for r in run {
                    part += wh.cost(r.ri, r.rz);
                }
                e += part as f64;
            }
            total += e;
        }
        total
    }

    fn normal_equations(&mut self, level: &ImageLevel, wh: &Whitener) -> NormalEquations {
        let cam = level.camera();
        let (fx, fy) = (cam.fx as f32, cam.fy as f32);
        let mut total = NormalEquations::default();
        for res in &self.chunks {
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
            total.merge(&acc.finish());
        }
        total.error = self.cost(wh);
        total
    }
}

/// One warped template point: its residuals and what its Jacobian needs.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Residual {
    /// Photometric residual.
    pub(super) ri: f32,
    /// Depth residual times its gain `sz`, NaN when the current depth is missing there.
    pub(super) rz: f32,
    /// The depth residual's gain: λ, or λ / z² with the quadratic noise model.
    pub(super) sz: f32,
    /// Intensity gradient at `u'` (per pixel).
    pub(super) gx: f32,
    pub(super) gy: f32,
    /// Depth gradient at `u'` (metres per pixel).
    pub(super) dx: f32,
    pub(super) dy: f32,
    /// The warped point `T q` in current-camera coordinates.
    pub(super) p: [f32; 3],
}

impl scale::Pair for Residual {
    #[inline(always)]
    fn ri(&self) -> f32 {
        self.ri
    }
    #[inline(always)]
    fn rz(&self) -> f32 {
        self.rz
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
    lambda: f32,
    noise: NoiseGain,
    photometric: bool,
}

impl Warp<'_> {
    /// Warps `points` and stores the residuals of those that land inside the level.
    fn run(&self, points: &[[f32; 4]], out: &mut Vec<Residual>) {
        let r = &self.r;
        let [fx, fy, cx, cy] = self.f;
        let [umax, vmax] = self.max;
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
            let mut s = bilinear(self.samples, self.w, u, v);
            if !self.photometric {
                (s[0], s[1], s[2]) = (q[3], 0.0, 0.0);
            }
            let ri = s[0] - q[3];
            let rz = s[3] - z;
            let depth_ok = rz.is_finite() && s[4].is_finite() && s[5].is_finite();
            // The depth residual's gain: λ, or the noise model's at z.
            let sz = self.noise.at(self.lambda, z);
            out.push(Residual {
                ri,
                rz: if depth_ok { sz * rz } else { f32::NAN },
                sz,
                gx: s[1],
                gy: s[2],
                dx: s[4],
                dy: s[5],
                p: [x, y, z],
            });
        }
    }
}

/// Bilinear lookup of all channels at `(u, v)`; the caller guarantees
/// `0 <= u < w - 1` and `0 <= v < h - 1`. Missing depth (NaN) propagates.
#[inline(always)]
fn bilinear(s: &[Sample], w: usize, u: f32, v: f32) -> Sample {
    let (x0, y0) = (u as usize, v as usize);
    let (ax, ay) = (u - x0 as f32, v - y0 as f32);
    let i = y0 * w + x0;
    let (p00, p01, p10, p11) = (&s[i], &s[i + 1], &s[i + w], &s[i + w + 1]);
    super::warp::lerp_sample(p00, p01, p10, p11, ax, ay)
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

/// The Jacobians of the photometric and (when present) scaled depth residuals of
/// one warped point with respect to a left perturbation `exp(δ) T`:
/// `J_I = ∇I · ∂π/∂p · [I | −[p]×]` and `J_Z = s (∇D · ∂π/∂p − e_z) · [I | −[p]×]`,
/// with `s` the depth residual's gain (held fixed, as IRLS holds a weight fixed).
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
