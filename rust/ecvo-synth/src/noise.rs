//! Depth-sensor and image noise models.
//!
//! [`apply_noise`] turns a noise-free [`Rendered`] frame into what a sensor would
//! deliver: 8-bit intensity and raw 16-bit depth in `depth_scale` units (0 = missing).
//! For every pixel with clean depth `z` (metres) the steps are, in order:
//!
//! 1. **range**: missing if `z < min_depth_m` or `z > max_depth_m`;
//! 2. **grazing angle**: missing if the angle between the viewing ray and the surface
//!    normal exceeds `grazing_max_angle_deg`;
//! 3. **edge dropout**: missing if any pixel within a square window of radius
//!    `radius_px` has clean depth `z'` with `|z' - z| > relative_jump * min(z, z')`
//!    (both sides of every depth discontinuity lose data);
//! 4. **random dropout**: missing with probability `random_dropout`;
//! 5. **low signal** (only with `low_signal`, time of flight): the returned signal is
//!    taken as `a / z^2` with `a` the rendered intensity over 255 (reflectance times
//!    shading) and `z` in metres; below `min_signal` the pixel is missing, between
//!    `min_signal` and twice that it is missing with a probability falling linearly
//!    from 1 to 0 (holes on dark and far surfaces);
//! 6. **flying pixels** (only with `flying_pixels`, time of flight): a pixel whose
//!    3x3 neighbourhood holds a clean depth jump of more than `relative_jump` (as in
//!    step 3) is, with probability `probability`, given a depth drawn uniformly
//!    between the smallest and the largest clean depth of that neighbourhood (a
//!    mixed return of foreground and background); otherwise it keeps its own depth;
//! 7. **Gaussian noise**: `z += sigma(z) * N(0, 1)` with
//!    `sigma(z) = sigma_base_m + sigma_per_m * z + sigma_at_1m * z^2` (axial noise of
//!    structured light / stereo sensors grows with the square of depth, that of time
//!    of flight about linearly);
//! 8. **disparity quantisation** (only if `quantisation`): inverse depth is rounded to a
//!    multiple of `disparity_quantum` (1/m), i.e. `z = 1 / (q * round(1 / (q z)))`, a
//!    depth step of about `q z^2` (Kinect v1: 1/8 px disparity, f b ≈ 43.5 px m gives
//!    q ≈ 0.00287 /m, ≈ 2.9 mm at 1 m, 11.5 mm at 2 m);
//! 9. **depth unit**: `raw = round(z * depth_scale)`; values outside `1..=65535` become 0.
//!    Rounding to the depth unit always happens (the output is an integer).
//!
//! Intensity: `round(clamp(intensity_f32 + intensity_noise_sigma * N(0, 1), 0, 255))`.
//!
//! All random values are counter-based (hash of seed, stream, pixel index), so the result
//! depends only on the inputs and the seed. Noise is independent per pixel.

use crate::camera::SynthCamera;
use crate::render::Rendered;
use crate::rng::{pixel_gaussian, pixel_uniform, stream_key};

/// Missing depth next to depth discontinuities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeDropout {
    /// Relative depth jump `|z' - z| / min(z, z')` that counts as a discontinuity.
    pub relative_jump: f64,
    /// Half-size of the square neighbourhood searched for a jump, in pixels (>= 1).
    pub radius_px: usize,
}

/// Flying pixels of a time-of-flight sensor at depth discontinuities (step 6 of the
/// module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyingPixels {
    /// Relative depth jump `|z' - z| / min(z, z')` within the 3x3 neighbourhood that
    /// makes a pixel a candidate.
    pub relative_jump: f64,
    /// Probability that a candidate returns a mixed depth (0–1).
    pub probability: f64,
}

/// Holes where a time-of-flight sensor's return is too weak (step 5 of the module
/// documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LowSignal {
    /// Signal `intensity / 255 / z^2` (z in metres) below which depth is missing;
    /// up to twice this value it is missing with a linearly falling probability.
    pub min_signal: f64,
}

/// Parameters of the sensor noise model (see the module documentation for the exact
/// order of operations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthNoise {
    /// Quadratic term of the depth noise's standard deviation, metres at 1 m: at depth
    /// `z` it contributes `sigma_at_1m * z^2`.
    pub sigma_at_1m: f64,
    /// Constant term of the depth noise's standard deviation, metres.
    pub sigma_base_m: f64,
    /// Linear term of the depth noise's standard deviation, metres per metre of depth:
    /// it contributes `sigma_per_m * z`.
    pub sigma_per_m: f64,
    /// Enables Kinect-like disparity quantisation with step `disparity_quantum`.
    pub quantisation: bool,
    /// Inverse-depth quantisation step in 1/m (depth step ≈ `disparity_quantum * z^2`).
    pub disparity_quantum: f64,
    /// Depth is missing where the surface is seen at more than this angle from its
    /// normal (degrees); 90 or more disables the test.
    pub grazing_max_angle_deg: f64,
    /// Missing depth near depth discontinuities; `None` disables it.
    pub edge_dropout: Option<EdgeDropout>,
    /// Fraction of pixels whose depth is missing at random (0–1).
    pub random_dropout: f64,
    /// Missing depth where the time-of-flight return is weak; `None` disables it.
    pub low_signal: Option<LowSignal>,
    /// Mixed depths at discontinuities; `None` disables them.
    pub flying_pixels: Option<FlyingPixels>,
    /// Standard deviation of additive Gaussian intensity noise, gray levels.
    pub intensity_noise_sigma: f64,
    /// Minimum measurable depth, metres (closer is missing).
    pub min_depth_m: f64,
    /// Maximum measurable depth, metres (farther is missing).
    pub max_depth_m: f64,
}

impl DepthNoise {
    /// No noise, no dropouts, unlimited range: only rounding to the depth unit.
    pub fn none() -> Self {
        Self {
            sigma_at_1m: 0.0,
            sigma_base_m: 0.0,
            sigma_per_m: 0.0,
            quantisation: false,
            disparity_quantum: 0.0,
            grazing_max_angle_deg: 90.0,
            edge_dropout: None,
            random_dropout: 0.0,
            low_signal: None,
            flying_pixels: None,
            intensity_noise_sigma: 0.0,
            min_depth_m: 0.0,
            max_depth_m: f64::INFINITY,
        }
    }

    /// Kinect v1-like structured light: σ = 1.4 mm · z², 1/8-pixel disparity
    /// quantisation, 0.5–4.5 m range, dropouts beyond 75° incidence, 2-pixel shadows at
    /// jumps above 5 %, 1 % random holes, 2 gray levels of image noise.
    pub fn kinect_like() -> Self {
        Self {
            sigma_at_1m: 0.0014,
            sigma_base_m: 0.0,
            sigma_per_m: 0.0,
            quantisation: true,
            disparity_quantum: 0.125 / (580.0 * 0.075),
            grazing_max_angle_deg: 75.0,
            edge_dropout: Some(EdgeDropout {
                relative_jump: 0.05,
                radius_px: 2,
            }),
            random_dropout: 0.01,
            low_signal: None,
            flying_pixels: None,
            intensity_noise_sigma: 2.0,
            min_depth_m: 0.5,
            max_depth_m: 4.5,
        }
    }

    /// Phone depth sensor-like (time of flight / depth API, already in millimetres):
    /// σ = 4 mm · z², no disparity quantisation, 0.2–6 m range, dropouts beyond 80°
    /// incidence, 1-pixel holes at jumps above 5 %, 2 % random holes, 1.5 gray levels of
    /// image noise.
    pub fn phone_like() -> Self {
        Self {
            sigma_at_1m: 0.004,
            sigma_base_m: 0.0,
            sigma_per_m: 0.0,
            quantisation: false,
            disparity_quantum: 0.0,
            grazing_max_angle_deg: 80.0,
            edge_dropout: Some(EdgeDropout {
                relative_jump: 0.05,
                radius_px: 1,
            }),
            random_dropout: 0.02,
            low_signal: None,
            flying_pixels: None,
            intensity_noise_sigma: 1.5,
            min_depth_m: 0.2,
            max_depth_m: 6.0,
        }
    }

    /// A phone's time-of-flight depth sensor (Android `DEPTH16`, millimetres), the
    /// low-noise case: σ = 1 mm + 0.3 % of z (4 mm at 1 m, 7 mm at 2 m, 13 mm at 4 m;
    /// Kinect v1's 1.4 mm·z² is 22 mm at 4 m), no disparity quantisation, 0.1–5 m,
    /// dropouts beyond 80° incidence, 1 % random holes, holes where the return
    /// `intensity / 255 / z²` is weak (below 0.01, thinning out below 0.02: mid-grey
    /// is measured out to the 5 m range, a surface at a fifth of full brightness thins
    /// out from 3.2 m and is gone beyond 4.5 m), a mixed foreground/background depth
    /// on a quarter of the pixels next to a depth jump above 5 % (flying pixels, not
    /// holes), 1.5 gray levels of image noise. Use it with millimetre depth (`depth_scale` 1000).
    ///
    /// Why these numbers: in the two real `DEPTH16` frames of
    /// `datasets/phone_tof_samples` (240x180, one at 0.5–1.2 m, one at 1–4 m) the
    /// robust spread of `(d[x-k] + d[x+k]) / 2 - d[x]` along rows gives 1.2 mm at
    /// lag 1 at every depth (the sensor smooths its output, so neighbours share their
    /// noise) and grows with the lag to 3–4 mm at 1 m and 9–13 mm at 2–3 m at lags 3–5
    /// (where the surfaces' own shape starts to count): about linear in depth, as
    /// time of flight's phase noise is, and 1 mm + 0.3 % z sits within those bounds.
    /// The noise here is independent per pixel. The frames have 13–17 % of pixels
    /// missing (a whole first row, then more on the far, dark lower part of the far
    /// frame), their confidence bits fall with distance (the far frame's pixels beyond
    /// 2 m are nearly all at the lowest confidence, but still valid, out to 3.7 m and
    /// beyond), and about a fifth of the pixels beside a depth jump hold an in-between
    /// depth. With the 5 m range and the weak-return rule, 82 % of the depth of the
    /// slow walk round the standard room is valid (92 % with blank walls, texture
    /// contrast 0.02), near those frames' 83–87 %.
    pub fn tof_like() -> Self {
        Self {
            sigma_at_1m: 0.0,
            sigma_base_m: 0.001,
            sigma_per_m: 0.003,
            quantisation: false,
            disparity_quantum: 0.0,
            grazing_max_angle_deg: 80.0,
            edge_dropout: None,
            random_dropout: 0.01,
            low_signal: Some(LowSignal { min_signal: 0.01 }),
            flying_pixels: Some(FlyingPixels {
                relative_jump: 0.05,
                probability: 0.25,
            }),
            intensity_noise_sigma: 1.5,
            min_depth_m: 0.1,
            max_depth_m: 5.0,
        }
    }

    /// Standard deviation of the Gaussian depth noise at depth `z` (metres), before
    /// quantisation and rounding: `sigma_base_m + sigma_per_m z + sigma_at_1m z²`.
    pub fn sigma_at(&self, z: f64) -> f64 {
        self.sigma_base_m + self.sigma_per_m * z + self.sigma_at_1m * z * z
    }
}

/// Random streams (kept distinct so that enabling one effect does not change another).
const STREAM_DEPTH: u64 = 1;
const STREAM_DROPOUT: u64 = 2;
const STREAM_INTENSITY: u64 = 3;
const STREAM_SIGNAL: u64 = 4;
const STREAM_FLYING: u64 = 5;
const STREAM_FLYING_MIX: u64 = 6;

/// Converts metres to raw depth units (`round(z * depth_scale)`), 0 for missing,
/// non-positive or out-of-range values.
#[inline]
pub fn metres_to_raw(z: f64, depth_scale: f64) -> u16 {
    if !(z > 0.0 && z.is_finite()) {
        return 0;
    }
    let raw = (z * depth_scale).round();
    if (1.0..=65535.0).contains(&raw) {
        raw as u16
    } else {
        0
    }
}

/// Noise-free conversion to raw depth: `round(z * depth_scale)`, 0 where nothing was hit
/// or out of the 16-bit range. (The noise-free intensity is `Rendered::intensity`.)
pub fn to_raw_depth(rendered: &Rendered, camera: &SynthCamera) -> Vec<u16> {
    rendered
        .depth_m
        .iter()
        .map(|&z| metres_to_raw(z as f64, camera.depth_scale))
        .collect()
}

/// Mask of pixels that have a relative depth jump within `radius` pixels (clean depth).
pub fn edge_mask(depth_m: &[f32], width: usize, height: usize, edge: &EdgeDropout) -> Vec<bool> {
    let r = edge.radius_px.max(1);
    let mut mask = vec![false; width * height];
    // A pixel is marked if it is within r of a jumping neighbour pair; mark both sides by
    // comparing each pixel to all pixels in its window.
    for v in 0..height {
        for u in 0..width {
            let z = depth_m[v * width + u] as f64;
            if z <= 0.0 {
                continue;
            }
            let (v0, v1) = (v.saturating_sub(r), (v + r).min(height - 1));
            let (u0, u1) = (u.saturating_sub(r), (u + r).min(width - 1));
            'win: for y in v0..=v1 {
                for x in u0..=u1 {
                    let z2 = depth_m[y * width + x] as f64;
                    if z2 > 0.0 && (z2 - z).abs() > edge.relative_jump * z.min(z2) {
                        mask[v * width + u] = true;
                        break 'win;
                    }
                }
            }
        }
    }
    mask
}

/// Smallest and largest clean depth (> 0) in the 3x3 window around pixel `i`.
fn window_range(depth_m: &[f32], width: usize, i: usize) -> (f64, f64) {
    let height = depth_m.len() / width;
    let (u, v) = (i % width, i / width);
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for y in v.saturating_sub(1)..=(v + 1).min(height - 1) {
        for x in u.saturating_sub(1)..=(u + 1).min(width - 1) {
            let z = depth_m[y * width + x] as f64;
            if z > 0.0 {
                lo = lo.min(z);
                hi = hi.max(z);
            }
        }
    }
    (lo, hi)
}

/// Applies the noise model to a rendered frame; returns `(intensity, raw depth)` with
/// depth in `camera.depth_scale` units and 0 for missing. Deterministic in `seed`.
pub fn apply_noise(
    rendered: &Rendered,
    camera: &SynthCamera,
    noise: &DepthNoise,
    seed: u64,
) -> (Vec<u8>, Vec<u16>) {
    let count = rendered.width * rendered.height;
    let key_intensity = stream_key(seed, STREAM_INTENSITY);
    let key_dropout = stream_key(seed, STREAM_DROPOUT);
    let key_depth = stream_key(seed, STREAM_DEPTH);
    let intensity = if noise.intensity_noise_sigma > 0.0 {
        (0..count)
            .map(|i| {
                let g = pixel_gaussian(key_intensity, i as u64);
                let value = rendered.intensity_f32[i] as f64 + noise.intensity_noise_sigma * g;
                value.round().clamp(0.0, 255.0) as u8
            })
            .collect()
    } else {
        rendered.intensity.clone()
    };

    let edges = noise
        .edge_dropout
        .map(|e| edge_mask(&rendered.depth_m, rendered.width, rendered.height, &e));
    let flying = noise.flying_pixels.map(|f| {
        let edge = EdgeDropout {
            relative_jump: f.relative_jump,
            radius_px: 1,
        };
        edge_mask(&rendered.depth_m, rendered.width, rendered.height, &edge)
    });
    let (key_signal, key_flying, key_mix) = (
        stream_key(seed, STREAM_SIGNAL),
        stream_key(seed, STREAM_FLYING),
        stream_key(seed, STREAM_FLYING_MIX),
    );
    let cos_max = if noise.grazing_max_angle_deg < 90.0 {
        noise.grazing_max_angle_deg.to_radians().cos()
    } else {
        f64::NEG_INFINITY
    };
    let depth = (0..count)
        .map(|i| {
            let z = rendered.depth_m[i] as f64;
            if !(z > 0.0)
                || z < noise.min_depth_m
                || z > noise.max_depth_m
                || (rendered.normal_dot_view[i] as f64) < cos_max
                || edges.as_ref().is_some_and(|m| m[i])
                || (noise.random_dropout > 0.0
                    && pixel_uniform(key_dropout, i as u64) < noise.random_dropout)
            {
                return 0;
            }
            if let Some(low) = noise.low_signal {
                let signal = rendered.intensity_f32[i] as f64 / 255.0 / (z * z);
                let p_missing = (2.0 - signal / low.min_signal).clamp(0.0, 1.0);
                if p_missing > 0.0 && pixel_uniform(key_signal, i as u64) < p_missing {
                    return 0;
                }
            }
            let mut z = z;
            if let (Some(f), Some(mask)) = (noise.flying_pixels, &flying) {
                if mask[i] && pixel_uniform(key_flying, i as u64) < f.probability {
                    let (lo, hi) = window_range(&rendered.depth_m, rendered.width, i);
                    z = lo + pixel_uniform(key_mix, i as u64) * (hi - lo);
                }
            }
            let mut zn = z;
            let sigma = noise.sigma_at(z);
            if sigma > 0.0 {
                zn += sigma * pixel_gaussian(key_depth, i as u64);
            }
            if noise.quantisation && noise.disparity_quantum > 0.0 && zn > 0.0 {
                let q = noise.disparity_quantum;
                let level = (1.0 / (q * zn)).round();
                zn = if level >= 1.0 { 1.0 / (q * level) } else { 0.0 };
            }
            metres_to_raw(zn, camera.depth_scale)
        })
        .collect();
    (intensity, depth)
}
