//! The robust scale of MOTION's residuals and the weights it gives (Kerl et al.,
//! "Robust Odometry Estimation for RGB-D Cameras", and DVO SLAM, which the paper
//! takes its weights from).
//!
//! A pixel's residual is `r = (r_I, r_Z)`: photometric and depth. Under a
//! t-distribution with ν degrees of freedom and scale matrix Σ, its squared
//! Mahalanobis distance is `d² = rᵀ Σ⁻¹ r` and its IRLS weight
//! `w = (ν + k) / (ν + d²)`, `k` the residual's dimension (2, or 1 where the current
//! frame has no depth and only `r_I` exists, measured against `Σ_II`). Σ is fitted by
//! the fixed-point iteration `Σ ← (1/n) Σ w r rᵀ` (the maximum-likelihood scale for
//! the given weights), warm-started from the previous iteration's Σ.
//!
//! [`Weighting::Scalar`] is the special case `Σ = σ² I` on `(r_I, λ r_Z)` that ecvo
//! used first: σ² is fitted the same way over `r_I² + λ² r_Z²`.
//!
//! The weight and the whitening are kept apart from the fit: [`Whitener`] turns a
//! residual and its Jacobian rows into whitened ones (`L r`, `L J` with
//! `Σ⁻¹ = Lᵀ L`), so the normal equations stay sums of rank-one updates.

use crate::config::Weighting;

/// Fewest pixels with both residuals a bivariate fit needs; with fewer, the scale
/// is fitted to the photometric residuals alone and the depth residuals are measured
/// against it.
pub const MIN_BIVARIATE_PIXELS: usize = 24;

/// A residual as the scale sees it: photometric, and depth (NaN when missing).
pub trait Pair {
    /// `r_I`.
    fn ri(&self) -> f32;
    /// `r_Z`, NaN when the current frame has no depth there.
    fn rz(&self) -> f32;
}

/// The scale matrix Σ of the t-distribution over `(r_I, r_Z)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// `Σ_II`.
    pub ii: f64,
    /// `Σ_IZ`.
    pub iz: f64,
    /// `Σ_ZZ`.
    pub zz: f64,
}

impl Scale {
    /// `σ² I`.
    pub fn isotropic(s2: f64) -> Scale {
        Scale {
            ii: s2,
            iz: 0.0,
            zz: s2,
        }
    }

    /// The whitening factor `L` with `Σ⁻¹ = Lᵀ L` (upper triangular), in f32 for the
    /// per-pixel loops. A near-singular Σ is regularised by bounding the correlation.
    pub fn whitener(&self, nu: f32) -> Whitener {
        self.whitener_with(nu, 0.0)
    }

    /// [`Scale::whitener`] with `Σ_ZZ` raised to at least `zz_floor · Σ_II`: the
    /// depth residual then weighs at most `1 / zz_floor` times the photometric one
    /// (`MotionConfig::max_fine_depth_weight`). The fit itself is not changed.
    pub fn whitener_with(&self, nu: f32, zz_floor: f64) -> Whitener {
        let ii = self.ii.max(1e-12);
        let zz = self.zz.max(1e-12).max(zz_floor * ii);
        // |ρ| ≤ 0.95 keeps Σ well conditioned.
        let lim = 0.95 * (ii * zz).sqrt();
        let iz = self.iz.clamp(-lim, lim);
        let det = ii * zz - iz * iz;
        let (a, b, c) = (zz / det, -iz / det, ii / det);
        let l11 = a.sqrt();
        let l12 = b / l11;
        let l22 = (c - l12 * l12).max(0.0).sqrt();
        Whitener {
            l11: l11 as f32,
            l12: l12 as f32,
            l22: l22 as f32,
            l1d: (1.0 / ii.sqrt()) as f32,
            nu,
        }
    }
}

/// `L` of `Σ⁻¹ = Lᵀ L`: maps a residual to one with unit covariance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Whitener {
    /// Entries of `L = [[l11, l12], [0, l22]]`.
    pub l11: f32,
    /// See `l11`.
    pub l12: f32,
    /// See `l11`.
    pub l22: f32,
    /// `1 / √Σ_II`, for a pixel with only a photometric residual.
    pub l1d: f32,
    /// ν.
    pub nu: f32,
}

impl Whitener {
    /// `d²` and the weight `(ν + k) / (ν + d²)` of a residual.
    #[inline(always)]
    pub fn weigh(&self, ri: f32, rz: f32) -> (f32, f32) {
        if rz.is_finite() {
            let a = self.l11 * ri + self.l12 * rz;
            let b = self.l22 * rz;
            let d2 = a * a + b * b;
            (d2, (self.nu + 2.0) / (self.nu + d2))
        } else {
            let a = self.l1d * ri;
            let d2 = a * a;
            (d2, (self.nu + 1.0) / (self.nu + d2))
        }
    }

    /// The robust cost of a residual, `w d² = (ν + k) d² / (ν + d²)`: increasing in
    /// `d²` and bounded by `ν + k`, so a gross outlier costs no more than a missing
    /// pixel. Summed at a fixed scale it is the error a Gauss-Newton step must lower.
    #[inline(always)]
    pub fn cost(&self, ri: f32, rz: f32) -> f32 {
        let (d2, w) = self.weigh(ri, rz);
        w * d2
    }

    /// The largest cost one residual can have.
    pub fn max_cost(&self) -> f32 {
        self.nu + 2.0
    }
}

/// Per-chunk sums of one fixed-point pass: `Σ w r_I²`, `Σ w r_I r_Z`, `Σ w r_Z²` over
/// the pixels with both residuals, and `Σ w r_I²` over the others.
pub type PassSums = [f64; 4];

/// Counts of a chunk: pixels with both residuals, with only the photometric one.
pub fn count<R: Pair>(chunk: &[R]) -> (usize, usize) {
    let two = chunk.iter().filter(|r| r.rz().is_finite()).count();
    (two, chunk.len() - two)
}

/// One fixed-point pass over a chunk for the current scale (its whitener), summed in
/// f32 over runs of 256 pixels and in f64 across runs.
pub fn pass<R: Pair>(chunk: &[R], wh: &Whitener, weighting: Weighting) -> PassSums {
    let mut acc = [0.0f64; 4];
    for run in chunk.chunks(256) {
        let mut p = [0.0f32; 4];
        for r in run {
            let (ri, rz) = (r.ri(), r.rz());
            let (_, w) = wh.weigh(ri, rz);
            if rz.is_finite() {
                if weighting == Weighting::Scalar {
                    // σ² I over (r_I, λ r_Z): one scale for both.
                    p[0] += w * (ri * ri + rz * rz) * 0.5;
                    p[2] += w * (ri * ri + rz * rz) * 0.5;
                } else {
                    p[0] += w * ri * ri;
                    p[1] += w * ri * rz;
                    p[2] += w * rz * rz;
                }
            } else {
                p[3] += w * ri * ri;
            }
        }
        for k in 0..4 {
            acc[k] += p[k] as f64;
        }
    }
    acc
}

/// The next scale from the summed pass (`two` and `one` pixels with two residuals and
/// with one), or `None` when there is nothing to fit.
pub fn next_scale(s: &PassSums, two: usize, one: usize, weighting: Weighting) -> Option<Scale> {
    let floor = 1e-12;
    match weighting {
        Weighting::Scalar => {
            // Σ w e² / Σ k over all pixels: 2 dimensions with depth, 1 without.
            let dims = (2 * two + one) as f64;
            (dims > 0.0).then(|| Scale::isotropic(((s[0] + s[2] + s[3]) / dims).max(floor)))
        }
        Weighting::Bivariate => {
            if two >= MIN_BIVARIATE_PIXELS {
                let n = two as f64;
                Some(Scale {
                    ii: (s[0] / n).max(floor),
                    iz: s[1] / n,
                    zz: (s[2] / n).max(floor),
                })
            } else if two + one > 0 {
                // Too few depth residuals to fit their spread: measure them against the
                // photometric one.
                Some(Scale::isotropic(
                    ((s[0] + s[3]) / (two + one) as f64).max(floor),
                ))
            } else {
                None
            }
        }
    }
}

/// The starting scale when there is no previous one: the plain (unweighted) second
/// moments, which the fixed point then shrinks towards the inliers.
pub fn initial_scale<R: Pair>(chunks: &[Vec<R>], weighting: Weighting) -> Option<Scale> {
    let mut sums = [0.0f64; 4];
    let (mut two, mut one) = (0, 0);
    for c in chunks {
        let p = moments(c, weighting);
        for k in 0..4 {
            sums[k] += p[k];
        }
        let (t, o) = count(c);
        two += t;
        one += o;
    }
    next_scale(&sums, two, one, weighting)
}

/// The plain second moments of a chunk (weight 1 everywhere, ν → ∞), in f64 and
/// point order.
pub fn moments<R: Pair>(chunk: &[R], weighting: Weighting) -> PassSums {
    let mut acc = [0.0f64; 4];
    for r in chunk {
        add_moments(&mut acc, r.ri(), r.rz(), weighting);
    }
    acc
}

/// Adds one residual pair's plain second moments to `acc` (see [`moments`]).
#[inline]
pub fn add_moments(acc: &mut PassSums, ri: f32, rz: f32, weighting: Weighting) {
    let (ri, rz) = (ri as f64, rz as f64);
    if rz.is_finite() {
        if weighting == Weighting::Scalar {
            acc[0] += 0.5 * (ri * ri + rz * rz);
            acc[2] += 0.5 * (ri * ri + rz * rz);
        } else {
            acc[0] += ri * ri;
            acc[1] += ri * rz;
            acc[2] += rz * rz;
        }
    } else {
        acc[3] += ri * ri;
    }
}

/// True when the fixed point has settled: every entry of Σ moved by less than `tol`
/// (a fraction) of its diagonal scale.
pub fn settled(a: &Scale, b: &Scale, tol: f64) -> bool {
    (a.ii - b.ii).abs() < tol * a.ii
        && (a.zz - b.zz).abs() < tol * a.zz
        && (a.iz - b.iz).abs() < tol * (a.ii * a.zz).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy)]
    struct R(f32, f32);
    impl Pair for R {
        fn ri(&self) -> f32 {
            self.0
        }
        fn rz(&self) -> f32 {
            self.1
        }
    }

    fn fit(chunks: &[Vec<R>], weighting: Weighting, nu: f32) -> Scale {
        let mut s = initial_scale(chunks, weighting).unwrap();
        for _ in 0..200 {
            let wh = s.whitener(nu);
            let mut sums = [0.0; 4];
            let (mut two, mut one) = (0, 0);
            for c in chunks {
                let p = pass(c, &wh, weighting);
                for k in 0..4 {
                    sums[k] += p[k];
                }
                let (t, o) = count(c);
                two += t;
                one += o;
            }
            let next = next_scale(&sums, two, one, weighting).unwrap();
            let done = settled(&s, &next, 1e-3);
            s = next;
            if done {
                break;
            }
        }
        s
    }

    /// A deterministic standard normal sample (Box-Muller on a fixed LCG).
    fn normals(n: usize, seed: u64) -> Vec<f64> {
        let mut x = seed;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (next(), next());
                (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
            })
            .collect()
    }

    #[test]
    fn bivariate_fixed_point_recovers_a_known_scale_matrix() {
        // Residuals with σ_I = 0.02, σ_Z = 0.005 and correlation 0.5.
        let (si, sz, rho) = (0.02f64, 0.005f64, 0.5f64);
        let a = normals(20000, 1);
        let b = normals(20000, 2);
        let clean: Vec<R> = a
            .iter()
            .zip(&b)
            .map(|(&x, &y)| {
                let ri = si * x;
                let rz = sz * (rho * x + (1.0 - rho * rho).sqrt() * y);
                R(ri as f32, rz as f32)
            })
            .collect();
        let chunks = |v: &[R]| -> Vec<Vec<R>> { v.chunks(4096).map(|c| c.to_vec()).collect() };
        // Without outliers the scale sits near the covariance (the t-distribution's
        // scale on Gaussian data is a little below it for ν = 5).
        let s = fit(&chunks(&clean), Weighting::Bivariate, 5.0);
        assert!((s.ii.sqrt() / si - 1.0).abs() < 0.15, "σ_I {}", s.ii.sqrt());
        assert!((s.zz.sqrt() / sz - 1.0).abs() < 0.15, "σ_Z {}", s.zz.sqrt());
        let r = s.iz / (s.ii * s.zz).sqrt();
        assert!((r - rho).abs() < 0.05, "correlation {r}");

        // 10 % gross outliers: the plain covariance is off by an order of magnitude,
        // the t-scale stays within 40 % of the inliers' and down-weights the outliers.
        let mut dirty = clean.clone();
        for k in (0..dirty.len()).step_by(10) {
            dirty[k] = R(0.5, -0.2);
        }
        let c = chunks(&dirty);
        let plain = initial_scale(&c, Weighting::Bivariate).unwrap();
        assert!(plain.zz.sqrt() > 5.0 * sz, "plain σ_Z {}", plain.zz.sqrt());
        let s = fit(&c, Weighting::Bivariate, 5.0);
        assert!((s.ii.sqrt() / si - 1.0).abs() < 0.4, "σ_I {}", s.ii.sqrt());
        assert!((s.zz.sqrt() / sz - 1.0).abs() < 0.4, "σ_Z {}", s.zz.sqrt());
        let wh = s.whitener(5.0);
        let (d2o, wo) = wh.weigh(0.5, -0.2);
        assert!(d2o > 100.0 && wo < 0.1, "outlier d² {d2o} w {wo}");

        // It is a fixed point: one more pass returns the same Σ.
        let mut sums = [0.0; 4];
        for ch in &c {
            let p = pass(ch, &wh, Weighting::Bivariate);
            for k in 0..4 {
                sums[k] += p[k];
            }
        }
        let again = next_scale(&sums, dirty.len(), 0, Weighting::Bivariate).unwrap();
        assert!((again.ii / s.ii - 1.0).abs() < 5e-3, "{again:?} vs {s:?}");
        assert!((again.zz / s.zz - 1.0).abs() < 5e-3, "{again:?} vs {s:?}");
    }

    #[test]
    fn scalar_scale_fits_a_known_spread() {
        // ±s photometric residuals without depth: σ² sits near s².
        let s = 0.05f32;
        let res: Vec<R> = (0..1000)
            .map(|i| R(if i % 2 == 0 { s } else { -s }, f32::NAN))
            .collect();
        let sc = fit(&[res], Weighting::Scalar, 5.0);
        assert!((sc.ii as f32 / (s * s) - 1.0).abs() < 0.05, "σ² {}", sc.ii);
        assert_eq!(sc.ii, sc.zz);
        assert!(initial_scale::<R>(&[], Weighting::Scalar).is_none());
    }

    #[test]
    fn the_scalar_special_case_weighs_like_one_sigma() {
        let wh = Scale::isotropic(0.01).whitener(5.0);
        let (d2, w) = wh.weigh(0.1, 0.1);
        assert!((d2 - 2.0).abs() < 1e-5);
        assert!((w - 7.0 / 7.0).abs() < 1e-6);
        let (d2, w) = wh.weigh(0.1, f32::NAN);
        assert!((d2 - 1.0).abs() < 1e-5 && (w - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_depth_weight_cap_raises_only_a_small_depth_spread() {
        // Depth residuals 10x tighter than the photometric ones: uncapped, a depth
        // residual weighs 100x a photometric one of the same size; capped at 3x, Σ_ZZ is
        // whitened as Σ_II / 3.
        let s = Scale {
            ii: 1e-4,
            iz: 0.0,
            zz: 1e-6,
        };
        let (d2, _) = s.whitener(5.0).weigh(0.0, 0.01);
        assert!((d2 - 100.0).abs() < 1e-2, "{d2}");
        let capped = s.whitener_with(5.0, 1.0 / 3.0);
        let (d2, _) = capped.weigh(0.0, 0.01);
        assert!((d2 - 3.0).abs() < 1e-4, "{d2}");
        let (d2, _) = capped.weigh(0.01, f32::NAN);
        assert!((d2 - 1.0).abs() < 1e-5, "{d2}");
        // A depth spread already above the floor is left alone.
        let wide = Scale { zz: 1e-3, ..s };
        assert_eq!(wide.whitener(5.0), wide.whitener_with(5.0, 1.0 / 3.0));
    }

    #[test]
    fn few_depth_residuals_fall_back_to_the_photometric_scale() {
        let res: Vec<R> = (0..100)
            .map(|i| R(0.01 * if i % 2 == 0 { 1.0 } else { -1.0 }, f32::NAN))
            .collect();
        let s = initial_scale(&[res], Weighting::Bivariate).unwrap();
        assert_eq!(s.ii, s.zz);
        assert!((s.ii / 1e-4 - 1.0).abs() < 1e-3);
    }
}
