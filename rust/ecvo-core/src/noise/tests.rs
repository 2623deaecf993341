use super::*;

/// A deterministic standard normal sequence (splitmix64 and Box-Muller).
struct Normal(u64);

impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

/// The spread of one registration's residuals: `n` points spread evenly in depth
/// over 0.5–4 m, with noise `σ(z)² = a + b z⁴` and 5 % gross outliers.
fn registration(a: f64, b: f64, n: usize, seed: u64) -> DepthSpread {
    let mut rng = Normal(seed);
    let mut h = SpreadHistogram::default();
    for k in 0..n {
        let z = 0.5 + 3.5 * (k as f64 + 0.5) / n as f64;
        let sigma = (a + b * z.powi(4)).sqrt();
        let r = if k % 20 == 7 {
            0.2 * rng.next()
        } else {
            sigma * rng.next()
        };
        h.add(z as f32, r as f32);
    }
    h.spread()
}

#[test]
fn the_histogram_reads_the_spread_of_each_depth_bin() {
    for sigma in [0.0005, 0.003, 0.02] {
        let mut rng = Normal(7);
        let mut h = SpreadHistogram::default();
        for _ in 0..4000 {
            h.add(1.1, (sigma * rng.next()) as f32);
            h.add(3.0, (2.0 * sigma * rng.next()) as f32);
        }
        let s = h.spread();
        let (b1, b3) = (depth_bin(1.1).unwrap(), depth_bin(3.0).unwrap());
        assert_eq!(s.count[b1], 4000);
        assert_eq!(s.count[b3], 4000);
        for (b, want) in [(b1, sigma), (b3, 2.0 * sigma)] {
            let got = s.sigma[b] as f64;
            assert!((got / want - 1.0).abs() < 0.06, "σ {want}: read {got}");
        }
        assert_eq!(s.count.iter().filter(|&&c| c > 0).count(), 2);
    }
    // Outside the bins, not finite, or too few: nothing.
    let mut h = SpreadHistogram::default();
    h.add(0.1, 0.01);
    h.add(9.0, 0.01);
    h.add(1.0, f32::NAN);
    h.add(f32::NAN, 0.01);
    for _ in 0..MIN_BIN_RESIDUALS - 1 {
        h.add(1.0, 0.01);
    }
    assert!(h.spread().is_empty());
}

#[test]
fn depth_bins_are_quarter_octaves() {
    assert_eq!(depth_bin(0.25), Some(0));
    assert_eq!(depth_bin(0.249), None);
    assert_eq!(depth_bin(0.5), Some(4));
    assert_eq!(depth_bin(1.0), Some(8));
    assert_eq!(depth_bin(7.99), Some(DEPTH_BINS - 1));
    assert_eq!(depth_bin(8.0), None);
    assert!((bin_depth(8) - 1.125).abs() < 1e-12);
}

/// Feeds `frames` registrations of the given noise and returns the fit.
fn fit(a: f64, b: f64, frames: u64) -> NoiseFit {
    let mut f = NoiseFit::new(DepthNoiseModel::Fitted);
    for k in 0..frames {
        f.record(&registration(a, b, 6000, 11 + k));
    }
    f
}

/// The noise of synthetic residuals at three known levels is recovered: none (exact
/// depth: the constant model), a Kinect's `1.4 mm·z²` (quadratic), and a sensor with a
/// 2 mm floor and a smaller z² term (mixed, α = a / b on the grid).
#[test]
fn the_fit_recovers_known_noise_including_none() {
    // Exact depth.
    let f = fit(0.0, 0.0, 24);
    assert_eq!(f.model(), DepthNoiseModel::Constant);
    let (a, b) = f.coefficients().expect("fitted");
    assert!(
        a > 0.0 && a.sqrt() < 2.0 * 1.4826 * R_MIN as f64,
        "floor {a}"
    );
    assert!(b < 1e-6 * a, "no z⁴ term: {b}");

    // A Kinect: σ = 1.4 mm · z².
    let kb = 0.0014f64.powi(2);
    let f = fit(0.0, kb, 24);
    let (a, b) = f.coefficients().expect("fitted");
    assert!((b / kb - 1.0).abs() < 0.15, "b {b} against {kb}");
    assert!(a < 0.1 * kb, "a {a}");
    assert!(
        matches!(f.model(), DepthNoiseModel::Quadratic)
            || matches!(f.model(), DepthNoiseModel::Mixed { half_log2_alpha } if half_log2_alpha <= -6),
        "{:?}",
        f.model()
    );

    // A 2 mm floor with a 1 mm·z² term: α = 4, 2 log2 α = 4.
    let (ta, tb) = (0.002f64.powi(2), 0.001f64.powi(2));
    let f = fit(ta, tb, 24);
    let (a, b) = f.coefficients().expect("fitted");
    assert!((a / ta - 1.0).abs() < 0.25, "a {a} against {ta}");
    assert!((b / tb - 1.0).abs() < 0.25, "b {b} against {tb}");
    match f.model() {
        DepthNoiseModel::Mixed { half_log2_alpha } => {
            assert!((half_log2_alpha - 4).abs() <= 1, "{half_log2_alpha}")
        }
        m => panic!("{m:?}"),
    }

    // A constant 3 mm: constant, or a mixed model within 6 % of it up to 4 m. The
    // window minimum reads bins with few residuals (here the near ones) slightly
    // lower, which leaves a trace of a z⁴ term.
    let f = fit(0.003f64.powi(2), 0.0, 24);
    assert!(
        matches!(f.model(), DepthNoiseModel::Constant)
            || matches!(f.model(), DepthNoiseModel::Mixed { half_log2_alpha } if half_log2_alpha >= 22),
        "{:?} {:?}",
        f.model(),
        f.coefficients()
    );
}

#[test]
fn the_model_holds_still_on_steady_noise_and_waits_for_data() {
    let mut f = NoiseFit::new(DepthNoiseModel::Fitted);
    assert_eq!(f.model(), DepthNoiseModel::Quadratic);
    let mut changes = 0;
    for k in 0..200 {
        changes += f
            .record(&registration(0.002f64.powi(2), 0.001f64.powi(2), 6000, k))
            .is_some() as u32;
    }
    assert_eq!(changes, 1, "one move to the fitted shape, then it stays");
    // Empty spreads (failed calls, the spread not measured) change nothing.
    let before = f.model();
    for _ in 0..50 {
        assert_eq!(f.record(&DepthSpread::default()), None);
    }
    assert_eq!(f.model(), before);
    // One depth only: the shape cannot be told, the model stays.
    let mut f = NoiseFit::new(DepthNoiseModel::Fitted);
    let mut h = SpreadHistogram::default();
    let mut rng = Normal(3);
    for _ in 0..5000 {
        h.add(2.0, (0.001 * rng.next()) as f32);
    }
    for _ in 0..40 {
        f.record(&h.spread());
    }
    assert_eq!(f.model(), DepthNoiseModel::Quadratic);
    assert_eq!(f.coefficients(), None);
}

#[test]
fn models_map_to_the_grid() {
    assert_eq!(model_of(1.0, 0.0), DepthNoiseModel::Constant);
    assert_eq!(model_of(0.0, 1.0), DepthNoiseModel::Quadratic);
    assert_eq!(
        model_of(4.0, 1.0),
        DepthNoiseModel::Mixed { half_log2_alpha: 4 }
    );
    assert_eq!(model_of(1e-6, 1.0), DepthNoiseModel::Quadratic);
    assert_eq!(model_of(1e6, 1.0), DepthNoiseModel::Constant);
}

/// Misregistration adds a depth-independent spread that differs from frame to frame
/// (here up to 4 mm on a Kinect's `1.4 mm·z²`, about α = 2.7 on average). The fit
/// takes each window's best-registered frame per bin, so it stays close to the
/// sensor's z² shape instead of reading the average misregistration as a floor.
#[test]
fn misregistration_varying_by_frame_does_not_read_as_a_noise_floor() {
    let kb = 0.0014f64.powi(2);
    let mut rng = Normal(21);
    let mut f = NoiseFit::new(DepthNoiseModel::Fitted);
    let mut mean_a = 0.0;
    let frames = 48;
    for k in 0..frames {
        let a = (0.004 * rng.uniform()).powi(2);
        mean_a += a / frames as f64;
        f.record(&registration(a, kb, 6000, 100 + k));
    }
    assert!(
        mean_a / kb > 2.0,
        "the average misregistration is a floor: {mean_a}"
    );
    let (a, b) = f.coefficients().expect("fitted");
    assert!(
        a / b < 0.25 * mean_a / kb,
        "α {} against {}",
        a / b,
        mean_a / kb
    );
    assert!((b / kb - 1.0).abs() < 0.3, "b {b} against {kb}");
    assert!(
        matches!(f.model(), DepthNoiseModel::Quadratic)
            || matches!(f.model(), DepthNoiseModel::Mixed { half_log2_alpha } if half_log2_alpha <= -2),
        "{:?}",
        f.model()
    );
}
