//! The settings `ecvo run` and `ecvo table` share, as command-line arguments, and their
//! translation into [`TrackSettings`].

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use ecvo_core::{DepthNoiseModel, Mode, MotionPrior, Preset, Weighting};

use crate::settings::{EngineChoice, TrackSettings};

/// Settings shared by `run` and `table`. `--help` groups them under headings, the
/// most used first in each (display_order): input, method, tuning (and, in
/// [`LimitArgs`], limits).
#[derive(Args)]
pub(crate) struct TrackArgs {
    /// A camera.json overriding the sequence's.
    #[arg(help_heading = "Input", display_order = 1, long)]
    pub(crate) camera: Option<PathBuf>,
    /// Track only the first N frames.
    #[arg(help_heading = "Input", display_order = 2, long)]
    pub(crate) max_frames: Option<usize>,
    /// Track every Nth frame only (frames 0, N, 2N, ...): N times the motion between
    /// tracked frames, the standard way to test fast motion on recorded data.
    #[arg(help_heading = "Input", display_order = 3, long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub(crate) frame_step: u32,
    /// Make any skipped frame an error: a list entry without a partner within
    /// 0.02 s, a frame identical to the previous one, a timestamp not after the
    /// previous one (by default each is a warning, counted in the frame account).
    #[arg(help_heading = "Input", display_order = 4, long)]
    pub(crate) strict: bool,
    /// Read list entries that lead outside the sequence folder (absolute paths, `..`,
    /// symlinks out); refused by default.
    #[arg(help_heading = "Input", display_order = 5, long)]
    pub(crate) allow_outside: bool,
    /// Use this imu.txt (gyroscope samples, `docs/imu.md`) instead of the sequence's;
    /// its calibration is the `imu` object of the camera.json beside it, else of the
    /// sequence's.
    #[arg(
        help_heading = "Input",
        display_order = 6,
        long,
        conflicts_with = "no_imu"
    )]
    pub(crate) imu: Option<PathBuf>,
    /// Ignore the sequence's imu.txt: track without the gyroscope.
    #[arg(help_heading = "Input", display_order = 7, long)]
    pub(crate) no_imu: bool,
    /// Thresholds and filter angles: the paper's PC (Table 1) or phone (Table 2) values.
    #[arg(help_heading = "Method", display_order = 10, long, value_enum, default_value_t = PresetArg::Pc)]
    pub(crate) preset: PresetArg,
    /// What each frame is registered against: the previous frame (chain, the
    /// paper's frame-to-frame tracking) or the level-1 reference (keyframe: a new
    /// keyframe when the motion since it passes level 1's thresholds or the overlap
    /// drops; refinement is then off).
    #[arg(help_heading = "Method", display_order = 14, long, value_enum)]
    pub(crate) tracking: Option<TrackingArg>,
    /// The paper's method as written (Table 1): its 8/4/2 sampling, one scalar
    /// scale with λ, [A] from the identity, every converged correction accepted.
    /// The options below override single parts of it.
    #[arg(help_heading = "Method", display_order = 15, long)]
    pub(crate) paper: bool,
    /// Depth residual noise: constant, quadratic (σ grows with z²), or fitted
    /// (σ² = a + b·z⁴ fitted to the depth residuals while tracking).
    #[arg(help_heading = "Tuning", display_order = 20, long, value_enum)]
    pub(crate) depth_noise: Option<DepthNoiseArg>,
    /// Residual weighting: scalar (one σ² over r_I and λ r_Z), bivariate (Kerl et
    /// al.'s 2x2 scale matrix), or hybrid (bivariate at the coarse steps, scalar at the
    /// finest).
    #[arg(help_heading = "Tuning", display_order = 21, long, value_enum)]
    pub(crate) weighting: Option<WeightingArg>,
    /// Coarse-to-fine schedule: paper (every 8th/4th/2nd full-resolution pixel),
    /// pyramid (1/8 to full resolution), pyramid-stride2 (1/8 to 1/2, then every
    /// second full-resolution pixel), or explicit steps LEVEL/STRIDE/ITERATIONS,
    /// coarsest first, e.g. "3/1/20,2/1/15,1/1/10,0/2/8".
    #[arg(help_heading = "Tuning", display_order = 22, long)]
    pub(crate) schedule: Option<String>,
    /// Template point budgets per pyramid level, LEVEL=POINTS comma-separated (e.g.
    /// "1=4096,0=4096"; POINTS `all` for every sampled pixel): the steps on that level
    /// keep the best-scoring points by intensity and depth gradient, spread over the
    /// image. Applied after --schedule.
    #[arg(help_heading = "Tuning", display_order = 23, long)]
    pub(crate) point_budget: Option<String>,
    /// What [A] starts from: identity, or velocity (constant-velocity prediction,
    /// with the identity tried too).
    #[arg(help_heading = "Tuning", display_order = 24, long, value_enum)]
    pub(crate) prior: Option<PriorArg>,
    /// With a gyroscope: fuse its rotation into each frame-to-frame registration,
    /// weighed by the two covariances, besides starting the registration from it.
    #[arg(help_heading = "Tuning", display_order = 39, long)]
    pub(crate) imu_fusion: bool,
    /// With a gyroscope: its rotation is also a prior term in the normal equations
    /// of each registration it starts, weighted by its covariance (`docs/imu.md`).
    #[arg(
        help_heading = "Tuning",
        display_order = 40,
        long,
        value_name = "true|false"
    )]
    pub(crate) imu_prior_term: Option<bool>,
    /// With a gyroscope: turn each frame's depth, when its image was taken at another
    /// time than the intensity (TUM's depth.txt stamps), to the intensity's time by
    /// the gyro's rotation between the two (on by default; docs/imu.md)
    #[arg(
        help_heading = "Tuning",
        display_order = 41,
        long,
        value_name = "true|false"
    )]
    pub(crate) imu_depth_time: Option<bool>,
    /// What an accepted correction does to the frame-to-frame chain: fuse (weighed by
    /// their covariances) or replace (the paper's).
    #[arg(help_heading = "Tuning", display_order = 25, long, value_enum)]
    pub(crate) corrections: Option<CorrectionsArg>,
    /// Between corrections, register every Nth frame after the level-1 reference
    /// against it too and fuse the result with the chain (needs --corrections fuse;
    /// 0: off, as --paper does).
    #[arg(help_heading = "Tuning", display_order = 26, long)]
    pub(crate) refine_every: Option<u32>,
    /// Reject a correction that moves further than this from its initial guess
    /// (mean change of the whitened squared residuals; `inf` accepts all).
    #[arg(help_heading = "Tuning", display_order = 27, long)]
    pub(crate) max_correction_distance: Option<f64>,
    /// At the finest step, the depth residual weighs at most this many times the
    /// photometric one under bivariate weighting (`inf` leaves the fit alone).
    #[arg(help_heading = "Tuning", display_order = 28, long)]
    pub(crate) max_fine_depth_weight: Option<f64>,
    /// Stop a coarse-to-fine level when the Gauss-Newton model predicts that the next
    /// update lowers the weighted squared error by less than this fraction (0: run
    /// until the cost rises or the iterations run out, as --paper does).
    #[arg(help_heading = "Tuning", display_order = 29, long)]
    pub(crate) min_predicted_decrease: Option<f64>,
    /// Stop a coarse-to-fine level after an update that moves the image by less than
    /// this many of the level's pixels (0: off, as --paper does).
    #[arg(help_heading = "Tuning", display_order = 30, long)]
    pub(crate) min_update_px: Option<f64>,
    /// Fixed-point passes of the scale fit after each accepted update, 1 to 20 (1:
    /// the scale follows the iterations; 20: it converges at every one, as --paper
    /// does).
    #[arg(help_heading = "Tuning", display_order = 31, long)]
    pub(crate) scale_passes: Option<usize>,
    /// With --tracking keyframe: a new keyframe when fewer than this fraction of the
    /// keyframe's finest template points land on the frame (0 to 1).
    #[arg(help_heading = "Tuning", display_order = 32, long)]
    pub(crate) keyframe_overlap: Option<f64>,
    /// With --tracking keyframe: refuse a registration against the keyframe whose
    /// residuals spread more than this many times wider than the recent ones' (the
    /// frame registers against the previous frame and becomes the keyframe; inf: off).
    #[arg(help_heading = "Tuning", display_order = 33, long)]
    pub(crate) keyframe_spread: Option<f64>,
    /// With --tracking keyframe: the depth of a frame's lookup levels (what the warp
    /// samples): filtered (every frame gets the whole preparation), raw or bilateral
    /// (the bilateral filter alone); with raw and bilateral a frame's reference side
    /// (removal filters, templates) is finished only when it is registered against.
    #[arg(help_heading = "Tuning", display_order = 34, long, value_enum)]
    pub(crate) lookup_depth: Option<LookupDepthArg>,
    /// With --tracking keyframe: every Nth frame after the keyframe, fuse its
    /// registration with the chain through the previous frame, as a new keyframe's
    /// always is (one more MOTION call; 0: off).
    #[arg(help_heading = "Tuning", display_order = 35, long)]
    pub(crate) keyframe_fuse_every: Option<u32>,
}

/// The limits of `run` and `table` (threads and memory): in `--help` after the output
/// options, so declared apart from [`TrackArgs`].
#[derive(Args)]
pub(crate) struct LimitArgs {
    /// Compute threads of the tracking pipeline (2 lets the filter and tracker
    /// stages overlap; the poses are the same whatever the number).
    #[arg(help_heading = "Limits", display_order = 50, long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub(crate) threads: u32,
    /// Memory the run may allocate for frames (the engine's pools, pyramids and
    /// templates plus the frames decoded ahead), e.g. 512M, 2G or a number of bytes;
    /// a larger need is refused before anything is allocated. Default 512M (the
    /// engine's default budget, sized for a phone).
    #[arg(help_heading = "Limits", display_order = 51, long, value_parser = parse_bytes)]
    pub(crate) max_memory: Option<usize>,
}

/// `512M`, `2G`, `64MiB`, `1048576`: a size in bytes (K, M, G are powers of 1024).
fn parse_bytes(text: &str) -> std::result::Result<usize, String> {
    let t = text.trim();
    let digits = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(digits);
    let value: f64 = num
        .parse()
        .map_err(|_| format!("`{text}` is not a size (e.g. 512M, 2G)"))?;
    let unit = unit.trim().to_ascii_uppercase();
    let scale = match unit.trim_end_matches("IB").trim_end_matches('B') {
        "" => 1.0,
        "K" => 1024.0,
        "M" => 1024.0 * 1024.0,
        "G" => 1024.0 * 1024.0 * 1024.0,
        _ => return Err(format!("`{text}`: unknown unit (use K, M or G)")),
    };
    let bytes = value * scale;
    if !(1.0..1e18).contains(&bytes) {
        return Err(format!("`{text}` is not a usable size"));
    }
    Ok(bytes as usize)
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum TrackingArg {
    Chain,
    Keyframe,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum LookupDepthArg {
    Filtered,
    Raw,
    Bilateral,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum CorrectionsArg {
    Fuse,
    Replace,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum WeightingArg {
    Scalar,
    Bivariate,
    Hybrid,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum DepthNoiseArg {
    /// The same noise at every depth.
    Constant,
    /// Noise growing as z² (a Kinect's structured light).
    Quadratic,
    /// σ² = a + b·z⁴ fitted to the depth residuals while tracking.
    Fitted,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum PriorArg {
    Identity,
    Velocity,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ModeArg {
    Naive,
    L1,
    L2,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum PresetArg {
    Pc,
    Phone,
}

impl TrackArgs {
    pub(crate) fn settings(&self, mode: Mode, limits: &LimitArgs) -> TrackSettings {
        let engine = EngineChoice {
            paper: self.paper,
            schedule: self.schedule.clone(),
            point_budget: self.point_budget.clone(),
            weighting: self.weighting.map(|w| match w {
                WeightingArg::Scalar => (Weighting::Scalar, None),
                WeightingArg::Bivariate => (Weighting::Bivariate, None),
                WeightingArg::Hybrid => (Weighting::Bivariate, Some(Weighting::Scalar)),
            }),
            depth_noise: self.depth_noise.map(|d| match d {
                DepthNoiseArg::Constant => DepthNoiseModel::Constant,
                DepthNoiseArg::Quadratic => DepthNoiseModel::Quadratic,
                DepthNoiseArg::Fitted => DepthNoiseModel::Fitted,
            }),
            prior: self.prior.map(|p| match p {
                PriorArg::Identity => MotionPrior::Identity,
                PriorArg::Velocity => MotionPrior::ConstantVelocity,
            }),
            max_correction_distance: self.max_correction_distance,
            max_fine_depth_weight: self.max_fine_depth_weight,
            min_predicted_decrease: self.min_predicted_decrease,
            min_update_px: self.min_update_px,
            scale_passes: self.scale_passes,
            fuse_corrections: self.corrections.map(|c| matches!(c, CorrectionsArg::Fuse)),
            refine_every: self.refine_every,
            keyframes: self.tracking.map(|t| matches!(t, TrackingArg::Keyframe)),
            keyframe_min_overlap: self.keyframe_overlap,
            keyframe_max_spread_growth: self.keyframe_spread,
            lookup_depth: self.lookup_depth.map(|d| match d {
                LookupDepthArg::Filtered => ecvo_core::LookupDepth::Filtered,
                LookupDepthArg::Raw => ecvo_core::LookupDepth::Raw,
                LookupDepthArg::Bilateral => ecvo_core::LookupDepth::Bilateral,
            }),
            keyframe_fuse_every: self.keyframe_fuse_every,
            imu_fusion: self.imu_fusion.then_some(true),
            imu_prior_term: self.imu_prior_term,
            imu_depth_time: self.imu_depth_time,
        };
        TrackSettings {
            frame_step: self.frame_step as usize,
            engine,
            mode,
            preset: match self.preset {
                PresetArg::Pc => Preset::Pc,
                PresetArg::Phone => Preset::Phone,
            },
            levels: None,
            bilateral: true,
            normal_filter: true,
            contour_filter: true,
            camera: self.camera.clone(),
            max_frames: self.max_frames,
            threads: limits.threads as usize,
            strict: self.strict,
            allow_outside: self.allow_outside,
            max_memory: limits.max_memory,
            imu: match (&self.imu, self.no_imu) {
                (_, true) => crate::imu::ImuSource::Off,
                (Some(p), false) => crate::imu::ImuSource::File(p.clone()),
                (None, false) => crate::imu::ImuSource::Auto,
            },
        }
    }
}
