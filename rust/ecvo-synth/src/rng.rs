//! Small deterministic pseudo-random number generation (SplitMix64).
//!
//! Two flavours are provided: a sequential generator [`Rng`] used to build scenes and
//! paths, and counter-based helpers ([`pixel_uniform`], [`pixel_gaussian`]) that derive
//! an independent random value from a stream key ([`stream_key`]) and an index so that noise does not
//! depend on the order in which pixels are visited.

/// One SplitMix64 finaliser step: a high-quality 64-bit mixing function.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Hash of three 64-bit words (order matters).
#[inline]
pub fn hash3(a: u64, b: u64, c: u64) -> u64 {
    mix64(a ^ mix64(b ^ mix64(c)))
}

/// Maps a 64-bit hash to a uniform double in `[0, 1)` (53 random bits).
#[inline]
pub fn unit_f64(h: u64) -> f64 {
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Key of random stream `stream` under `seed`, for [`pixel_uniform`] / [`pixel_gaussian`].
#[inline]
pub fn stream_key(seed: u64, stream: u64) -> u64 {
    mix64(seed ^ mix64(stream))
}

/// Uniform value in `[0, 1)` for element `index` of the stream with key `key`.
#[inline]
pub fn pixel_uniform(key: u64, index: u64) -> f64 {
    unit_f64(mix64(key ^ index.wrapping_mul(0xD6E8_FEB8_6659_FD93)))
}

/// Standard normal value for element `index` of the stream with key `key` (Box–Muller on
/// two counter-based uniforms).
#[inline]
pub fn pixel_gaussian(key: u64, index: u64) -> f64 {
    let h = mix64(key ^ index.wrapping_mul(0xD6E8_FEB8_6659_FD93));
    let u1 = 1.0 - unit_f64(h); // (0, 1]
    let u2 = unit_f64(mix64(h ^ 0xD1B5_4A32_D192_ED03));
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Sequential SplitMix64 generator.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// Creates a generator from a seed (any value, including 0, is fine).
    pub fn new(seed: u64) -> Self {
        Self {
            state: mix64(seed ^ 0x0005_EED0_FEC0_5EED),
        }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.state)
    }

    /// Uniform double in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        unit_f64(self.next_u64())
    }

    /// Uniform double in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Uniform angle in `[0, 2π)`.
    pub fn angle(&mut self) -> f64 {
        self.range(0.0, std::f64::consts::TAU)
    }

    /// `+1.0` or `-1.0` with equal probability.
    pub fn sign(&mut self) -> f64 {
        if self.next_u64() & 1 == 0 { 1.0 } else { -1.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_moments() {
        let n = 200_000u64;
        let (mut s, mut s2) = (0.0, 0.0);
        for i in 0..n {
            let g = pixel_gaussian(stream_key(7, 3), i);
            s += g;
            s2 += g * g;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.02, "var {var}");
    }

    #[test]
    fn uniform_range_and_spread() {
        let mut r = Rng::new(1);
        let v: Vec<f64> = (0..10_000).map(|_| r.uniform()).collect();
        assert!(v.iter().all(|&x| (0.0..1.0).contains(&x)));
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        assert!((mean - 0.5).abs() < 0.02);
        assert_ne!(Rng::new(1).next_u64(), Rng::new(2).next_u64());
    }
}
