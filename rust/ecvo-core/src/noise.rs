//! The depth-noise model fitted to the data ([`DepthNoiseModel::Fitted`]).
//!
//! The depth residual of `MOTION` is divided by the noise it is expected to have at
//! its depth, so that every residual is measured in units of its own noise before the
//! bivariate t-distribution weighs it. How that noise grows with depth depends on the
//! sensor: a Kinect's structured light grows as z² (σ ≈ 1.4 mm·z²), a phone's
//! time-of-flight sensor about linearly, a rendered or stereo-refined depth map is
//! nearly exact at any depth. A fixed z² model (a Kinect's) down-weights the far depth
//! of a sensor that is in fact precise there.
//!
//! So the shape is measured. Every \[A\] the tracker believes reports, per depth bin,
//! a robust spread of its raw depth residuals `D_i(u') − [Tq]_z` at the finest step
//! ([`DepthSpread`]: 1.4826 × the median absolute residual, from a fixed histogram).
//! A registration's residuals are the sensor's noise plus its own misregistration,
//! which is about the same at every depth and changes from frame to frame; so
//! [`NoiseFit`] takes, per depth bin, the smallest spread of each window of
//! [`REFIT_EVERY`] frames (the lower envelope: the spread of the frame registered
//! best at that depth, whose misregistration part is smallest), keeps decayed sums
//! of those minima over the last windows and fits
//! `σ_Z(z)² = a + b·z⁴` (relative least squares over the bins, `a, b ≥ 0`). Only the
//! ratio `α = a / b` shapes the weights (the bivariate fit scales them as a whole):
//! the residual's gain becomes `λ·√((α + 1) / (α + z⁴))`, which is `λ / z²` for `α = 0`
//! and λ for `α → ∞`. `α` is kept on a grid of half powers of two
//! ([`DepthNoiseModel::Mixed`]), moves only when the fit leaves its cell by a full
//! power of two, and is refitted every [`REFIT_EVERY`] believed frames: the shape
//! settles after a few dozen frames and then stays, which keeps the pipeline's \[A\]
//! computed ahead valid (it must have used the tracker's model, bit for bit).
//!
//! Exact depth: residuals below [`R_MIN`] (7.6 µm) count as `R_MIN`, so a noise-free
//! sensor has the same small spread at every depth: `b = 0`, the constant model.
//! Everything is integer counts and fixed-order sums: deterministic, and nothing is
//! allocated per frame.

use crate::config::DepthNoiseModel;

/// Depth bins of a [`DepthSpread`]: quarter octaves from [`Z_MIN`] to 8 m.
pub const DEPTH_BINS: usize = 20;
/// Lower edge of the first depth bin, metres.
pub const Z_MIN: f32 = 0.25;
/// Residual magnitude buckets: quarter octaves from [`R_MIN`] to 1 m.
pub const RESIDUAL_BUCKETS: usize = 68;
/// The smallest residual magnitude told apart, metres (2⁻¹⁷): the floor that keeps
/// exact depth from dividing by zero.
pub const R_MIN: f32 = 1.0 / 131_072.0;
/// Fewest residuals a depth bin needs for its spread to be reported.
pub const MIN_BIN_RESIDUALS: u32 = 16;
/// Every how many believed frames the shape is refitted.
pub const REFIT_EVERY: u32 = 8;
/// The weight of the past per frame (about 30 frames of memory); a window's minima
/// enter with the past weighed by `DECAY^REFIT_EVERY`.
pub const DECAY: f64 = 0.97;
/// The fitted `2 log2 α` must leave the model in use by this many grid steps (a
/// factor of 2.8 in α) for the model to change.
pub const HYSTERESIS: u32 = 3;
/// The bins entering a fit must span at least this ratio of depths, or the shape is
/// not told apart from the scene's depth range and the model stays.
pub const MIN_DEPTH_SPAN: f64 = 1.5;
/// Smallest and largest `2 log2 α` of [`DepthNoiseModel::Mixed`]; below, the fit is
/// [`DepthNoiseModel::Quadratic`] (`α = 1/16`: within a factor √2 of it at 0.5 m,
/// 3 % at 1 m), above [`DepthNoiseModel::Constant`].
pub const MIN_HALF_LOG2_ALPHA: i8 = -8;
/// See [`MIN_HALF_LOG2_ALPHA`] (`α = 4096`: within 5 % of constant up to 5 m).
pub const MAX_HALF_LOG2_ALPHA: i8 = 24;

/// Quarter-octave index of a positive finite `x` (exponent and the two leading
/// mantissa bits of its f32 form: no logarithm), relative to `2^e0`.
#[inline(always)]
fn quarter_octave(x: f32, e0: i32) -> i32 {
    (x.to_bits() >> 21) as i32 - ((127 + e0) << 2)
}

/// Lower edge of quarter-octave `k` above `2^e0`.
fn quarter_edge(k: i32, e0: i32) -> f64 {
    let e = e0 + k.div_euclid(4);
    let m = k.rem_euclid(4) as f64;
    2f64.powi(e) * (1.0 + m / 4.0)
}

/// The depth bin of a point at depth `z` (metres), if inside the bins.
#[inline(always)]
pub fn depth_bin(z: f32) -> Option<usize> {
    let k = quarter_octave(z, -2);
    (z.is_finite() && (0..DEPTH_BINS as i32).contains(&k)).then_some(k as usize)
}

/// The representative depth of bin `k`: the middle of its edges.
pub fn bin_depth(k: usize) -> f64 {
    0.5 * (quarter_edge(k as i32, -2) + quarter_edge(k as i32 + 1, -2))
}

/// The residual bucket of `|r|` (metres).
#[inline(always)]
fn residual_bucket(r: f32) -> usize {
    let a = r.abs().max(R_MIN);
    quarter_octave(a, -17).clamp(0, RESIDUAL_BUCKETS as i32 - 1) as usize
}

/// Histogram of `|r|` per depth bin: the scratch [`DepthSpread`] is computed from.
#[derive(Clone, Debug)]
pub struct SpreadHistogram {
    counts: Vec<u32>,
}

impl Default for SpreadHistogram {
    fn default() -> Self {
        SpreadHistogram {
            counts: vec![0; DEPTH_BINS * RESIDUAL_BUCKETS],
        }
    }
}

impl SpreadHistogram {
    /// Bytes held.
    pub const BYTES: usize = DEPTH_BINS * RESIDUAL_BUCKETS * size_of::<u32>();

    /// Empties it.
    pub fn clear(&mut self) {
        self.counts.fill(0);
    }

    /// Counts a raw depth residual `r` (metres) at depth `z`; ignores non-finite ones
    /// and depths outside the bins.
    #[inline]
    pub fn add(&mut self, z: f32, r: f32) {
        if let (Some(b), true) = (depth_bin(z), r.is_finite()) {
            self.counts[b * RESIDUAL_BUCKETS + residual_bucket(r)] += 1;
        }
    }

    /// The robust spread per depth bin: 1.4826 × the median `|r|`, read from the
    /// bucket that holds it (linear within the bucket).
    pub fn spread(&self) -> DepthSpread {
        let mut out = DepthSpread::default();
        for b in 0..DEPTH_BINS {
            let h = &self.counts[b * RESIDUAL_BUCKETS..(b + 1) * RESIDUAL_BUCKETS];
            let n: u32 = h.iter().sum();
            if n < MIN_BIN_RESIDUALS {
                continue;
            }
            let half = n as f64 / 2.0;
            let mut below = 0u32;
            for (k, &c) in h.iter().enumerate() {
                if c > 0 && (below + c) as f64 >= half {
                    let (lo, hi) = (quarter_edge(k as i32, -17), quarter_edge(k as i32 + 1, -17));
                    // Bucket 0 holds everything below R_MIN: its median is R_MIN.
                    let f = if k == 0 {
                        0.0
                    } else {
                        (half - below as f64) / c as f64
                    };
                    out.count[b] = n;
                    out.sigma[b] = (1.4826 * (lo + f * (hi - lo))) as f32;
                    break;
                }
                below += c;
            }
        }
        out
    }
}

/// The robust spread of one `MOTION` call's raw depth residuals per depth bin
/// ([`DEPTH_BINS`] quarter octaves from [`Z_MIN`]): residuals counted and σ (metres);
/// bins with fewer than [`MIN_BIN_RESIDUALS`] have a count of 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthSpread {
    /// Residuals per bin.
    pub count: [u32; DEPTH_BINS],
    /// 1.4826 × the median `|r|` per bin, metres.
    pub sigma: [f32; DEPTH_BINS],
}

impl DepthSpread {
    /// True when no bin has a spread.
    pub fn is_empty(&self) -> bool {
        self.count.iter().all(|&c| c == 0)
    }
}

/// `σ_Z(z)² = a + b·z⁴` fitted to decayed per-bin spreads; see the module.
#[derive(Clone, Debug)]
pub struct NoiseFit {
    /// Decayed residual counts per bin.
    weight: [f64; DEPTH_BINS],
    /// Decayed `count × σ²` per bin.
    power: [f64; DEPTH_BINS],
    /// Spreads recorded since the last refit.
    since: u32,
    /// The model in use (never `Fitted`).
    model: DepthNoiseModel,
    /// The last fit's `(a, b)`, if any.
    last: Option<(f64, f64)>,
    /// Per bin, the smallest `σ²` recorded since the last refit (∞ when none).
    window_min: [f64; DEPTH_BINS],
    /// Per bin, the residuals counted since the last refit.
    window_count: [f64; DEPTH_BINS],
}

/// Fewest (decayed) residuals a bin needs to enter the fit.
const MIN_FIT_WEIGHT: f64 = 64.0;

impl NoiseFit {
    /// Starts from `model` (`Fitted` starts from `Quadratic`).
    pub fn new(model: DepthNoiseModel) -> Self {
        NoiseFit {
            weight: [0.0; DEPTH_BINS],
            power: [0.0; DEPTH_BINS],
            since: 0,
            model: match model {
                DepthNoiseModel::Fitted => DepthNoiseModel::Quadratic,
                m => m,
            },
            last: None,
            window_min: [f64::INFINITY; DEPTH_BINS],
            window_count: [0.0; DEPTH_BINS],
        }
    }

    /// The model in use.
    pub fn model(&self) -> DepthNoiseModel {
        self.model
    }

    /// The last fit's `(a, b)` of `σ² = a + b·z⁴` (m², m²/m⁴), if one was made.
    pub fn coefficients(&self) -> Option<(f64, f64)> {
        self.last
    }

    /// Adds one believed registration's spreads; every [`REFIT_EVERY`] calls the
    /// window's per-bin minima join the decayed sums and the shape is refitted.
    /// Returns the model when it changed.
    pub fn record(&mut self, s: &DepthSpread) -> Option<DepthNoiseModel> {
        if s.is_empty() {
            return None;
        }
        for b in 0..DEPTH_BINS {
            if s.count[b] > 0 {
                let sg = s.sigma[b] as f64;
                self.window_count[b] += s.count[b] as f64;
                self.window_min[b] = self.window_min[b].min(sg * sg);
            }
        }
        self.since += 1;
        if self.since < REFIT_EVERY {
            return None;
        }
        self.since = 0;
        let d = DECAY.powi(REFIT_EVERY as i32);
        for b in 0..DEPTH_BINS {
            let n = self.window_count[b];
            let y = if n > 0.0 { self.window_min[b] } else { 0.0 };
            self.weight[b] = d * self.weight[b] + n;
            self.power[b] = d * self.power[b] + n * y;
            self.window_count[b] = 0.0;
            self.window_min[b] = f64::INFINITY;
        }
        let (a, b) = self.fit()?;
        self.last = Some((a, b));
        let new = model_of(a, b);
        (grid(new).abs_diff(grid(self.model)) >= HYSTERESIS).then(|| {
            self.model = new;
            new
        })
    }

    /// `(a, b)` by least squares on the relative error of `σ²` over the bins with
    /// enough residuals, `a, b ≥ 0`; `None` unless such bins span [`MIN_DEPTH_SPAN`].
    fn fit(&self) -> Option<(f64, f64)> {
        let floor = (1.4826 * R_MIN as f64).powi(2);
        let (mut s, mut sx, mut sxx, mut sy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut zlo, mut zhi) = (f64::INFINITY, 0.0f64);
        for b in 0..DEPTH_BINS {
            let w = self.weight[b];
            if w < MIN_FIT_WEIGHT {
                continue;
            }
            let y = (self.power[b] / w).max(floor);
            let z = bin_depth(b);
            let x = z.powi(4);
            // Relative least squares: each bin's σ² error over σ², times its residuals.
            let u = w / (y * y);
            s += u;
            sx += u * x;
            sxx += u * x * x;
            sy += u * y;
            sxy += u * x * y;
            zlo = zlo.min(z);
            zhi = zhi.max(z);
        }
        if zhi < MIN_DEPTH_SPAN * zlo {
            return None;
        }
        let det = s * sxx - sx * sx;
        let (mut a, mut b) = if det > 0.0 {
            ((sy * sxx - sx * sxy) / det, (s * sxy - sx * sy) / det)
        } else {
            (-1.0, -1.0)
        };
        if a < 0.0 || b < 0.0 {
            // One of the two terms alone: the better of the two one-parameter fits.
            let b_only = sxy / sxx;
            let a_only = sy / s;
            let cost = |a: f64, b: f64| -> f64 {
                (0..DEPTH_BINS)
                    .filter(|&k| self.weight[k] >= MIN_FIT_WEIGHT)
                    .map(|k| {
                        let y = (self.power[k] / self.weight[k]).max(floor);
                        let e = (y - a - b * bin_depth(k).powi(4)) / y;
                        self.weight[k] * e * e
                    })
                    .sum()
            };
            (a, b) = if cost(0.0, b_only) < cost(a_only, 0.0) {
                (0.0, b_only)
            } else {
                (a_only, 0.0)
            };
        }
        Some((a, b))
    }
}

/// The model on the grid closest to `σ² = a + b·z⁴`.
pub fn model_of(a: f64, b: f64) -> DepthNoiseModel {
    if b <= 0.0 {
        return DepthNoiseModel::Constant;
    }
    if a <= 0.0 {
        return DepthNoiseModel::Quadratic;
    }
    let k = (2.0 * (a / b).log2()).round();
    if k > MAX_HALF_LOG2_ALPHA as f64 {
        DepthNoiseModel::Constant
    } else if k < MIN_HALF_LOG2_ALPHA as f64 {
        DepthNoiseModel::Quadratic
    } else {
        DepthNoiseModel::Mixed {
            half_log2_alpha: k as i8,
        }
    }
}

/// Position of a (non-`Fitted`) model on the grid of `2 log2 α`.
fn grid(m: DepthNoiseModel) -> i32 {
    match m {
        DepthNoiseModel::Quadratic | DepthNoiseModel::Fitted => MIN_HALF_LOG2_ALPHA as i32 - 1,
        DepthNoiseModel::Constant => MAX_HALF_LOG2_ALPHA as i32 + 1,
        DepthNoiseModel::Mixed { half_log2_alpha } => half_log2_alpha as i32,
    }
}

#[cfg(test)]
mod tests;
