//! The procedural textures of the scene's surfaces: plane waves and value noise through a
//! smooth sigmoid, band-limited so that a rendered pixel is a clean sample.

use crate::rng::{Rng, mix64, unit_f64};

/// A smooth, band-limited procedural texture on a planar surface.
///
/// `I(u, v) = 127.5 + 122 x / sqrt(1 + x²)` with `x = c · s(u, v)` with `s` a sum of a per-surface offset,
/// four plane waves (wavelengths 7–40 cm, amplitude decreasing with frequency) and two
/// octaves of value noise (cells 30 cm and 16 cm) with quintic (C2) interpolation.
#[derive(Clone, Debug)]
pub struct Texture {
    base: f64,
    contrast: f64,
    waves: [[f64; 4]; 4],                    // kx, ky (rad/m), phase, amplitude
    octaves: [(f64, f64, f64, f64, u64); 2], // 1/cell, amplitude, offset u, offset v, seed
}

/// Quintic fade `6t^5 - 15t^4 + 10t^3` (C2 continuous value-noise interpolation).
#[inline]
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Smooth sine approximation (range reduction + degree-11 odd Taylor polynomial on
/// `[-π/2, π/2]`, absolute error < 1e-7), much cheaper than `f64::sin`.
#[inline]
fn fast_sin(x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    let k = fast_floor(x * (1.0 / TAU) + 0.5) as f64;
    let mut r = x - k * TAU; // [-π, π]
    if r > FRAC_PI_2 {
        r = PI - r;
    } else if r < -FRAC_PI_2 {
        r = -PI - r;
    }
    let r2 = r * r;
    r * (1.0
        + r2 * (-1.0 / 6.0
            + r2 * (1.0 / 120.0
                + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0 + r2 * (-1.0 / 39_916_800.0))))))
}

/// `floor` for moderate values without a libm call.
#[inline]
fn fast_floor(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x { i - 1 } else { i }
}

/// Smooth 2-D value noise in `[-1, 1]`.
#[inline]
fn value_noise(x: f64, y: f64, seed: u64) -> f64 {
    let (ix, iy) = (fast_floor(x), fast_floor(y));
    let (sx, sy) = (fade(x - ix as f64), fade(y - iy as f64));
    let lattice = |i: i64, j: i64| {
        let key = seed
            ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        unit_f64(mix64(key)) * 2.0 - 1.0
    };
    let a = lattice(ix, iy);
    let b = lattice(ix + 1, iy);
    let c = lattice(ix, iy + 1);
    let d = lattice(ix + 1, iy + 1);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sy
}

impl Texture {
    /// Draws a random texture.
    pub fn random(rng: &mut Rng) -> Self {
        // (min wavelength, max wavelength, amplitude): coarse structure carries the
        // energy, fine structure is weak so that bilinear interpolation stays accurate.
        const BANDS: [(f64, f64, f64); 4] = [
            (0.25, 0.40, 0.35),
            (0.16, 0.25, 0.26),
            (0.11, 0.16, 0.14),
            (0.07, 0.11, 0.05),
        ];
        let mut waves = [[0.0; 4]; 4];
        for (w, &(lo, hi, amp)) in waves.iter_mut().zip(BANDS.iter()) {
            let lambda = rng.range(lo, hi);
            let k = std::f64::consts::TAU / lambda;
            let theta = rng.angle();
            *w = [
                k * theta.cos(),
                k * theta.sin(),
                rng.angle(),
                amp * rng.range(0.8, 1.2),
            ];
        }
        let mut octave = |cell: f64, amp: f64| {
            (
                1.0 / cell,
                amp,
                rng.range(0.0, 100.0),
                rng.range(0.0, 100.0),
                rng.next_u64(),
            )
        };
        let octaves = [octave(0.30, 0.8), octave(0.16, 0.35)];
        Self {
            base: rng.range(-0.5, 0.5),
            contrast: rng.range(0.9, 1.3),
            waves,
            octaves,
        }
    }

    /// The same texture stretched by `scale` (every wavelength and noise cell times
    /// `scale`): `scaled(s).eval(s u, s v) = eval(u, v)`.
    pub fn scaled(&self, scale: f64) -> Self {
        let mut t = self.clone();
        for w in &mut t.waves {
            w[0] /= scale;
            w[1] /= scale;
        }
        for o in &mut t.octaves {
            o.0 /= scale;
        }
        t
    }

    /// The same texture with its contrast multiplied by `factor`: towards a plain
    /// mid-grey surface (a blank wall) as `factor` goes to 0.
    pub fn with_contrast(&self, factor: f64) -> Self {
        let mut t = self.clone();
        t.contrast *= factor;
        t
    }

    /// Intensity (0–255, not rounded) at surface coordinates `(u, v)` in metres.
    #[inline]
    pub fn eval(&self, u: f64, v: f64) -> f64 {
        let mut s = self.base;
        for w in &self.waves {
            s += w[3] * fast_sin(w[0] * u + w[1] * v + w[2]);
        }
        for &(f, a, ou, ov, seed) in &self.octaves {
            s += a * value_noise(u * f + ou, v * f + ov, seed);
        }
        let x = self.contrast * s;
        // Smooth sigmoid x / sqrt(1 + x^2), cheaper than tanh.
        127.5 + 122.0 * x / (1.0 + x * x).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_sin_is_accurate() {
        for i in -100_000..100_000 {
            let x = i as f64 * 0.00731;
            assert!((fast_sin(x) - x.sin()).abs() < 1e-7, "x = {x}");
        }
    }

    #[test]
    fn texture_is_continuous_and_varied() {
        let mut rng = Rng::new(5);
        let t = Texture::random(&mut rng);
        let (mut lo, mut hi) = (255.0f64, 0.0f64);
        let (mut step_1mm, mut step_01mm) = (0.0f64, 0.0f64);
        for i in 0..20_000 {
            let u = i as f64 * 0.0005;
            let v = 0.3 * u + 0.1;
            let a = t.eval(u, v);
            lo = lo.min(a);
            hi = hi.max(a);
            step_1mm = step_1mm.max((t.eval(u + 1e-3, v) - a).abs());
            step_01mm = step_01mm.max((t.eval(u + 1e-4, v) - a).abs());
        }
        assert!(hi - lo > 120.0, "range {lo}..{hi}");
        // Bounded slope (no jumps): at most a few gray levels per millimetre...
        assert!(step_1mm < 6.0, "max step {step_1mm}");
        // ...and differentiable: steps shrink linearly with the step length.
        let ratio = step_1mm / step_01mm;
        assert!((ratio - 10.0).abs() < 1.0, "ratio {ratio}");
    }
}
