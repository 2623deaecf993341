//! Settings of the tracker, with the paper's presets and validation.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::imu::ImuCalibration;

mod schedule;
mod validate;
pub use schedule::{
    MAX_PYRAMID_LEVEL, MAX_SCHEDULE_SHIFT, MIN_LEVEL_SIDE, MIN_POINT_BUDGET, MotionLevel,
    SCHEDULE_SHIFT_SIDE, Schedule, parse_point_budget, parse_schedule,
};

/// The default memory budget, 512 MiB: what an app on a phone with 3-4 GB can spend
/// on tracking before the low-memory killer looks at it. With the default settings
/// the sequential engine fits 4096x2160 in it, the default pipeline 1920x1080
/// (`docs/reliability-jni.md` has the table).
pub const DEFAULT_MEMORY_BUDGET: usize = 512 << 20;

/// Most fixed-point passes of one scale fit.
pub const MAX_SCALE_PASSES: usize = 20;

/// Motion thresholds `(εd, εa)` of one error-correction level: `comp()` asks for a
/// correction when the accumulated motion exceeds either (section 3.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceLevel {
    /// εd: translation threshold in metres.
    pub max_distance_m: f64,
    /// εa: rotation threshold in degrees.
    pub max_angle_deg: f64,
}

impl ReferenceLevel {
    /// A level from millimetres and degrees, as the paper writes them.
    pub const fn mm_deg(mm: f64, deg: f64) -> Self {
        ReferenceLevel {
            max_distance_m: mm / 1000.0,
            max_angle_deg: deg,
        }
    }
}

/// Which error-correction levels run: the columns of the paper's Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Plain frame-to-frame tracking, no reference frames.
    Naive,
    /// Level-one error correction only.
    L1,
    /// Level-one and level-two error correction.
    L2,
}

impl std::str::FromStr for Mode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "naive" => Ok(Mode::Naive),
            "l1" => Ok(Mode::L1),
            "l2" => Ok(Mode::L2),
            _ => Err(Error::InvalidConfig {
                field: "mode",
                why: format!("`{s}` is not naive, l1 or l2"),
            }),
        }
    }
}

/// Which thresholds and filter angles to start from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// The paper's PC values (Table 1): L1 (30 mm, 7°), L2 (120 mm, 12°), εn 28°, εg 7°.
    Pc,
    /// The paper's phone values (Table 2): L1 (30 mm, 3°), L2 (70 mm, 7°), εn 45°, εg 20°.
    Phone,
}

impl std::str::FromStr for Preset {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "pc" => Ok(Preset::Pc),
            "phone" => Ok(Preset::Phone),
            _ => Err(Error::InvalidConfig {
                field: "preset",
                why: format!("`{s}` is not pc or phone"),
            }),
        }
    }
}

/// Edge-preserving smoothing of depth over valid pixels only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BilateralConfig {
    /// Window radius in pixels (the window is `2r+1` square).
    pub radius: usize,
    /// Spatial standard deviation in pixels.
    pub sigma_space_px: f32,
    /// Range standard deviation as a fraction of the centre depth (noise grows with
    /// depth), in (0, 0.35].
    pub sigma_depth_rel: f32,
}

impl Default for BilateralConfig {
    fn default() -> Self {
        BilateralConfig {
            radius: 2,
            sigma_space_px: 1.5,
            sigma_depth_rel: 0.02,
        }
    }
}

/// Frame preparation: the filter stage of the paper (section 4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterConfig {
    /// Bilateral filter on depth; `None` switches it off.
    pub bilateral: Option<BilateralConfig>,
    /// εn: drop a pixel whose axis and diagonal normals differ by more than this
    /// angle (degrees); `None` switches the normal filter off.
    pub normal_max_angle_deg: Option<f64>,
    /// εg: drop the 3x3 neighbourhood where the surface is within this angle
    /// (degrees) of the viewing ray; `None` switches the contour filter off.
    pub contour_angle_deg: Option<f64>,
    /// Depths below this (metres) are treated as missing.
    pub min_depth_m: f64,
    /// Depths above this (metres) are treated as missing.
    pub max_depth_m: f64,
}

/// How the photometric and depth residuals of a pixel are weighted (section 3 of the
/// paper, after Kerl et al.).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// One scalar scale σ² over `r_I² + (λ r_Z)²`: the depth gain λ sets the relative
    /// trust of the two residuals once and for all (ecvo's first reading of the paper).
    Scalar,
    /// Kerl et al.'s bivariate t-distribution: a 2x2 scale matrix Σ over `(r_I, r_Z)`
    /// estimated by fixed-point iteration every iteration, so each residual is
    /// measured against its own spread and their correlation. λ cancels out here:
    /// scaling `r_Z` scales Σ's depth row and column with it.
    Bivariate,
}

/// How the noise of a depth residual depends on depth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepthNoiseModel {
    /// The same for every pixel.
    Constant,
    /// Standard deviation growing with z² (structured-light and time-of-flight
    /// sensors): the depth residual of a point at depth z is divided by z² (z in
    /// metres, at least 0.3), so the scale describes the noise at 1 m.
    #[default]
    Quadratic,
    /// `σ_Z(z)² ∝ α + z⁴` with `α = 2^(half_log2_alpha / 2)` (z at least 0.3 m): the
    /// depth residual's gain is `λ·√((α + 1) / (α + z⁴))`, λ at 1 m; between
    /// `Quadratic` (`α → 0`) and `Constant` (`α → ∞`). What [`DepthNoiseModel::Fitted`]
    /// settles on; also usable fixed.
    Mixed {
        /// `2 log2 α`.
        half_log2_alpha: i8,
    },
    /// Fitted to the data while tracking ([`crate::noise`]): the tracker starts from
    /// `Quadratic` and re-fits `σ_Z(z)² = a + b·z⁴` from the depth residuals of the
    /// registrations it believes, then uses the [`DepthNoiseModel::Mixed`] (or
    /// `Quadratic`, `Constant`) closest to it. A bare [`crate::MotionEstimator`] reads
    /// it as `Quadratic`.
    Fitted,
}

/// The depth of a frame's lookup levels under keyframe tracking
/// ([`Config::lookup_depth`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LookupDepth {
    /// The whole preparation for every frame: bilateral filter, normal and contour
    /// removal, the templates.
    Filtered,
    /// The sensor's depth as it is (in range, in metres), less the pixels at a depth
    /// edge, averaged down the pyramid.
    Raw,
    /// The bilateral filter alone, without the removal filters, less the pixels at a
    /// depth edge (the default).
    #[default]
    Bilateral,
}

/// What to start \[A\], the frame-to-frame `MOTION`, from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionPrior {
    /// The identity, as the paper does.
    Identity,
    /// Constant velocity: the previous frame's \[A\] scaled by the ratio of the frame
    /// intervals. The identity is tried too at the coarsest step and the better start
    /// is kept, so that a sudden stop costs nothing.
    ConstantVelocity,
}

/// Settings of `MOTION(Fi, Fj, Tinit)`.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionConfig {
    /// λ: gain of the depth residual relative to the intensity residual (intensity in
    /// [0, 1], depth in metres).
    pub depth_gain: f64,
    /// ν: degrees of freedom of the t-distribution that weights residuals.
    pub t_dof: f64,
    /// The coarse-to-fine steps, coarsest first.
    pub levels: Vec<MotionLevel>,
    /// Stop a level when the update's translation (m) and rotation (rad) are both
    /// below this.
    pub min_update: f64,
    /// Stop a level after an accepted update that moves the image by less than this
    /// many of the level's pixels: a bound on the flow of the update at the template's
    /// mean inverse depth, `(f + r) (|v| E[1/z] + |ω|)` for the level's focal length
    /// `f` and half-diagonal `r` (pixels). A coarse level only has to bring the next
    /// one into its basin; updates far below its pixel are noise. 0 switches it off.
    pub min_update_px: f64,
    /// Stop a level, without taking the update, when the Gauss-Newton model predicts
    /// that it lowers the weighted squared error `Σ w d²` by less than this fraction
    /// (`−gᵀδ = gᵀH⁻¹g` against `Σ w d²`; the first iteration of a level always runs).
    /// Such an update is below the residuals' noise: evaluating it costs a warp and a
    /// cost pass, and most are then rejected because the cost rose. 0 switches it off.
    pub min_predicted_decrease: f64,
    /// The scale's fixed-point iteration stops when no entry of Σ moved by more than
    /// this fraction of its diagonal scale.
    pub scale_tolerance: f64,
    /// After an accepted update, the scale is re-fitted by at most this many passes
    /// of its fixed-point iteration (1..=20; each a pass over the residuals; the
    /// first comes with the update's cost). One pass lets the scale follow the
    /// iterations instead of converging at every one; the fit at the start of each
    /// step still converges.
    pub scale_passes_per_update: usize,
    /// A result with fewer valid residuals than this at the finest level failed.
    pub min_valid_pixels: usize,
    /// A result moving more than this between the two frames (metres) failed.
    pub max_translation_m: f64,
    /// A result rotating more than this between the two frames (degrees) failed.
    pub max_rotation_deg: f64,
    /// How residuals are weighted.
    pub weighting: Weighting,
    /// How the finest step weighs its residuals, if not as `weighting` (then from a
    /// fresh scale; the spread check refits `weighting`'s form on that step's final
    /// residuals). Bivariate coarse steps and a scalar finest step is `hybrid` on the
    /// command line.
    pub fine_weighting: Option<Weighting>,
    /// At the finest step, the (gain-scaled) depth residual weighs at most this many
    /// times the photometric one: the bivariate scale is whitened with `Σ_ZZ` at least
    /// `Σ_II / max_fine_depth_weight` (the fit itself is unchanged). The fit treats
    /// every pixel as independent, but depth residuals of neighbouring pixels are not
    /// (the sensor's and the bilateral filter's smoothing, disparity quantisation), so
    /// on real Kinect data it gives depth too much of the final say. The coarse steps
    /// keep the plain fit, which the basin needs. `f64::INFINITY` switches it off; no
    /// effect with scalar weighting.
    pub max_fine_depth_weight: f64,
    /// How the depth residual's noise grows with depth.
    pub depth_noise: DepthNoiseModel,
    /// Measure the depth residuals' spread per depth at the end of the finest step
    /// ([`crate::motion::MotionResult::depth_spread`]; a pass over every 4th
    /// residual). The tracker sets it when `depth_noise` is
    /// [`DepthNoiseModel::Fitted`].
    pub depth_spread: bool,
    /// What \[A\] starts from.
    pub prior: MotionPrior,
    /// A result whose photometric residuals spread more than this (the robust scale
    /// `√Σ_II`, intensity in [0, 1]) failed: the two frames do not show the same
    /// scene at that alignment (a good registration is near 0.01-0.03, fast motion with
    /// blur up to 0.11 on fr1/xyz, an alignment of
    /// unrelated images near 0.25). `f64::INFINITY` switches the check off.
    pub max_intensity_sigma: f64,
    /// The same for the depth residuals: `√Σ_ZZ / λ` in metres (at 1 m with the
    /// quadratic noise model).
    pub max_depth_sigma_m: f64,
    /// A current frame with fewer textured pixels (depth and an intensity gradient of
    /// at least [`crate::prepare::TEXTURE_GRADIENT`]) than this fraction of its pixels
    /// registers on depth alone: its intensity residuals have no gradient, so they
    /// add nothing to the normal equations, and their spread is not checked against
    /// `max_intensity_sigma` (a black or dark frame, the lights off, with depth).
    /// A textured current frame registers on depth alone against a reference with
    /// fewer (the first frame after a black run): the reference's intensities say
    /// nothing, and the photometric term would pull the warp toward the current
    /// frame's dark pixels. 0 keeps the photometric term always.
    pub depth_only_texture_fraction: f64,
    /// When `MOTION` starts from several guesses, compare them at the coarsest step
    /// with the last guess's scale instead of the first's. The tracker sets it for
    /// an \[A\] whose last start is the gyroscope's prior ([`crate::imu`]): on a fast
    /// pan the identity's scale, fitted to a misregistration, is so wide that the
    /// identity wins against the right motion, whose template points partly leave
    /// the image. Off by default (the identity's scale).
    pub scale_from_last_start: bool,
    /// When `MOTION` starts from several guesses and this is positive, the last
    /// guess's rotation is also a prior on the motion's rotation: every coarse-to-fine
    /// step adds `info · |Log(R Rₚ⁻¹)|²` to the robust cost it minimises, so `info`
    /// times the identity to the rotation block of `JᵀWJ` and `info · Log(R Rₚ⁻¹)` to
    /// `JᵀWr`, in 1/rad² (the registration's information matrix stays the images'
    /// alone). The tracker sets it from the gyroscope with
    /// [`Config::imu_prior_term`] ([`crate::imu::Gyro::prior_information`]). 0 (the
    /// default): no prior term.
    pub rotation_prior_information: f64,
}

impl MotionConfig {
    /// Sets the point budget of every step on pyramid level `pyramid_level`.
    pub fn set_point_budget(&mut self, pyramid_level: usize, max_points: Option<usize>) {
        for l in &mut self.levels {
            if l.pyramid_level == pyramid_level {
                l.max_points = max_points;
            }
        }
    }
}

/// Everything the tracker needs to know.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// Intrinsics and depth units of the stream.
    pub camera: Camera,
    /// Frame preparation.
    pub filter: FilterConfig,
    /// Motion estimation.
    pub motion: MotionConfig,
    /// Error-correction levels, level one first; empty for naive tracking.
    pub reference_levels: Vec<ReferenceLevel>,
    /// After this many consecutive lost frames the tracker re-anchors on the next
    /// frame at the last good pose instead of insisting on the old frames.
    pub max_lost_frames: u32,
    /// A correction (\[B\], \[C\], ...) whose result moved further than this from its
    /// initial guess is rejected: the mean change it makes to the whitened residuals,
    /// `δᵀ H δ / n` for the twist δ between guess and result and the information
    /// matrix H (whitened by the estimated scale) over n residuals. A correction
    /// removes drift, which is small against the sensor noise; a large move means it
    /// converged somewhere else. `f64::INFINITY` accepts every correction.
    pub max_correction_distance: f64,
    /// A frame whose registration implies a camera speed above this (translation
    /// from the previous frame over the time between their timestamps, m/s) is not
    /// believed: it is treated as a failed \[A\] (recovery, then lost). A hand-held or
    /// head-mounted camera stays well below 4 m/s; an unannounced zoom or a
    /// teleport reads as tens of m/s. `f64::INFINITY` believes every speed.
    pub max_speed_m_s: f64,
    /// A registration whose intensity and depth residual spreads (the bivariate
    /// scale's `√Σ_II` and `√Σ_ZZ`) are both more than this many times the medians of
    /// the last believed frame-to-frame registrations' is not believed either (see
    /// [`crate::spread`]): no rigid motion explains the two frames. Checked with
    /// bivariate weighting only. `f64::INFINITY` switches it off.
    pub max_spread_jump: f64,
    /// Fuse an accepted correction with the frame-to-frame chain it corrects,
    /// weighing each by its covariance ([`crate::correction::fuse_correction`]), instead
    /// of replacing the chain's pose with the correction's as the paper does. Off in
    /// [`Config::paper`].
    pub fuse_corrections: bool,
    /// Every this many frames after the level-1 reference (counted from it), a frame
    /// that calls for no correction is also registered against that reference, seeded
    /// with its chained pose, and the result is fused with the chain as a correction
    /// is ([`crate::correction::fuse_correction`]), without making the frame a
    /// reference: while a reference lives long (slow motion), the chain's error is
    /// pulled back to it between corrections. Needs `fuse_corrections`; 0 switches it
    /// off, as [`Config::paper`] does. Chain tracking only (keyframe tracking has
    /// [`Config::keyframe_fuse_every`]).
    pub refine_every: u32,
    /// With [`Config::keyframes`]: every this many frames after the keyframe, the
    /// registration against it is also fused with the chain through the previous
    /// frame (one more `MOTION` call, and the previous frame's reference side
    /// finished), as a new keyframe's always is. 0 (the default, chosen on the
    /// suite, issue 46: it changed no group's drift by 1 % and costs a `MOTION` call
    /// and a finished frame) switches it off.
    pub keyframe_fuse_every: u32,
    /// Keyframe tracking (issue 26, as DVO-SLAM and visual-odometry-rs do): every
    /// frame is registered against the level-1 reference, the keyframe, instead of
    /// against the previous frame, seeded with the previous frame's pose and with the
    /// constant-velocity prediction (the better start at the coarsest step wins). The
    /// frame becomes the new keyframe (the level-1 reference, without a correction:
    /// it is registered against the old one already) when the motion since the
    /// keyframe passes level 1's `comp`, when fewer than
    /// [`Config::keyframe_min_overlap`] of the keyframe's finest template points
    /// still land on the frame, or when the registration against the keyframe is not
    /// believed and the frame registered against the previous frame instead. A new
    /// keyframe's registration is fused with the chain through the previous frame
    /// (its registration against the keyframe, then \[A\]) as a correction is, with
    /// `fuse_corrections`. When the keyframe is the previous frame and the
    /// registration is not believed, it is tried once more from the start that lost
    /// the coarsest step. Levels 2 and up correct as in the paper. Needs at least one
    /// reference level. On by default since issue 46 (with
    /// [`LookupDepth::Bilateral`], chosen on the suite by group geometric means of
    /// drift against the chain: real 1.024, fast 0.893, weak 0.691, noise 0.933; see
    /// `docs/accuracy.md`); off in [`Config::paper`] and with `--tracking chain`.
    pub keyframes: bool,
    /// With [`Config::keyframes`]: a frame on which fewer than this fraction of the
    /// keyframe's finest template points land (valid residuals) becomes the new
    /// keyframe. In `[0, 1]`; 0 leaves only the motion thresholds.
    pub keyframe_min_overlap: f64,
    /// With [`Config::keyframes`]: a registration against the keyframe whose
    /// intensity or depth residual spread (the bivariate scale's `√Σ_II`, `√Σ_ZZ`) is
    /// more than this many times the median of the recent believed registrations' is
    /// not believed (it may have converged to another minimum, or the keyframe is out
    /// of date): the frame registers against the previous frame and becomes the new
    /// keyframe. Bivariate weighting only; `f64::INFINITY` (the default) switches it
    /// off: at 2 it refused good registrations on noise-free depth, whose tiny spreads
    /// vary by more than that from frame to frame, and lost more on the suite than it
    /// saved (issue 26's closing note).
    pub keyframe_max_spread_growth: f64,
    /// With [`Config::keyframes`]: the depth a frame's lookup levels (what `MOTION`
    /// samples when the frame is the current one) are made from. With
    /// [`LookupDepth::Filtered`] every frame gets the whole preparation, as in the
    /// chain; otherwise a frame is prepared only as far as the warp samples it, and
    /// its reference side (the filters, the removal masks, the templates) is
    /// finished once, by the tracker, when the frame is first registered against
    /// (a keyframe, or the previous frame of a fall-back or a fusion). Ignored
    /// without keyframe tracking. [`LookupDepth::Bilateral`] by default.
    pub lookup_depth: LookupDepth,
    /// A frame becomes an anchor after a loss only with at least this fraction of
    /// its pixels carrying depth after filtering.
    pub min_anchor_depth_fraction: f64,
    /// ... and at least this fraction carrying intensity texture (gradient above
    /// [`crate::prepare::TEXTURE_GRADIENT`]) where there is depth.
    pub min_anchor_texture_fraction: f64,
    /// The most bytes the engine may allocate ([`crate::memory`]): the sequential
    /// engine and the pipeline refuse, at creation and before allocating, a size and
    /// settings that need more ([`crate::Error::MemoryBudget`]).
    /// [`crate::DEFAULT_MEMORY_BUDGET`] (512 MiB) by default.
    pub memory_budget: usize,
    /// How the IMU sits against the camera, if samples are pushed
    /// ([`crate::Odometry::push_imu`]; `camera.json`'s `imu` object). Unused without
    /// samples. By default aligned with the camera and on the frames' clock.
    pub imu: ImuCalibration,
    /// With a gyroscope: fuse each believed frame-to-frame registration with the
    /// gyro's rotation over the frame's interval, each weighed by its covariance
    /// ([`crate::imu::Gyro::fuse`]), instead of seeding the registration only. Off by
    /// default (`docs/imu.md`).
    pub imu_fusion: bool,
    /// With a gyroscope, its rotation over the frame's interval is also a prior term
    /// in the normal equations of \[A\] (and of the keyframe registration, moved by
    /// the previous frame's pose), weighted by its covariance: the white noise over
    /// the interval and the bias estimate's spread
    /// ([`MotionConfig::rotation_prior_information`]), besides seeding the coarsest
    /// step. On by default: with it, against seeding alone, fr1/desk and fr1/xyz
    /// half at steps 1-4 with six simulated gyros gave ATE geometric means of 0.825
    /// and 0.971, the pan suite 0.927 (`docs/imu.md`). No effect without samples.
    pub imu_prior_term: bool,
    /// With a gyroscope, a frame whose depth was captured at another time than its
    /// intensity ([`crate::Odometry::push_with_depth_time`]) has its depth turned by
    /// the gyro's rotation between the two times before it is prepared
    /// ([`crate::imu::depth_time`]). On by default (`docs/imu.md`). No effect without
    /// samples or without a depth time.
    pub imu_depth_time: bool,
}

impl Config {
    /// The paper's settings for a preset and a mode on the given camera.
    pub fn new(camera: Camera, preset: Preset, mode: Mode) -> Self {
        let (levels, normal, contour) = match preset {
            Preset::Pc => (
                [
                    ReferenceLevel::mm_deg(30.0, 7.0),
                    ReferenceLevel::mm_deg(120.0, 12.0),
                ],
                28.0,
                7.0,
            ),
            Preset::Phone => (
                [
                    ReferenceLevel::mm_deg(30.0, 3.0),
                    ReferenceLevel::mm_deg(70.0, 7.0),
                ],
                45.0,
                20.0,
            ),
        };
        let used = match mode {
            Mode::Naive => 0,
            Mode::L1 => 1,
            Mode::L2 => 2,
        };
        Config {
            camera,
            filter: FilterConfig {
                bilateral: Some(BilateralConfig::default()),
                normal_max_angle_deg: Some(normal),
                contour_angle_deg: Some(contour),
                min_depth_m: 0.1,
                max_depth_m: 8.0,
            },
            motion: MotionConfig {
                depth_gain: 1.8,
                t_dof: 5.0,
                levels: Schedule::PyramidStride2.levels_for(&camera),
                min_update: 1e-6,
                min_update_px: 0.1,
                min_predicted_decrease: 1e-3,
                scale_tolerance: 1e-2,
                scale_passes_per_update: 1,
                min_valid_pixels: 200,
                max_translation_m: 0.5,
                max_rotation_deg: 45.0,
                weighting: Weighting::Bivariate,
                fine_weighting: None,
                max_fine_depth_weight: 4.0,
                depth_noise: DepthNoiseModel::Fitted,
                depth_spread: false,
                prior: MotionPrior::ConstantVelocity,
                max_intensity_sigma: 0.2,
                max_depth_sigma_m: 0.05,
                depth_only_texture_fraction: 0.02,
                scale_from_last_start: false,
                rotation_prior_information: 0.0,
            },
            reference_levels: levels[..used].to_vec(),
            max_lost_frames: 10,
            max_correction_distance: 100.0,
            max_speed_m_s: 4.0,
            max_spread_jump: 5.0,
            fuse_corrections: true,
            refine_every: 3,
            keyframe_fuse_every: 0,
            // The keyframe is the level-1 reference: naive tracking has none.
            keyframes: used > 0,
            keyframe_min_overlap: 0.5,
            keyframe_max_spread_growth: f64::INFINITY,
            lookup_depth: LookupDepth::Bilateral,
            min_anchor_depth_fraction: 0.05,
            min_anchor_texture_fraction: 0.02,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            imu: ImuCalibration::default(),
            imu_fusion: false,
            imu_prior_term: true,
            imu_depth_time: true,
        }
    }

    /// The paper's method as written, to reproduce its Table 1: the 8/4/2 sampling of
    /// the full-resolution image, one scalar scale with λ, \[A\] from the identity and
    /// every converged correction accepted. (A failed correction never makes the
    /// frame a reference, in either configuration.)
    pub fn paper(camera: Camera, preset: Preset, mode: Mode) -> Self {
        let mut c = Config::new(camera, preset, mode);
        c.motion.levels = Schedule::PaperSampling.levels_for(&camera);
        c.motion.scale_tolerance = 1e-3;
        c.motion.min_predicted_decrease = 0.0;
        c.motion.min_update_px = 0.0;
        c.motion.scale_passes_per_update = MAX_SCALE_PASSES;
        c.motion.weighting = Weighting::Scalar;
        c.motion.depth_noise = DepthNoiseModel::Constant;
        c.motion.max_fine_depth_weight = f64::INFINITY;
        c.motion.prior = MotionPrior::Identity;
        c.max_correction_distance = f64::INFINITY;
        c.max_speed_m_s = f64::INFINITY;
        c.max_spread_jump = f64::INFINITY;
        c.fuse_corrections = false;
        c.refine_every = 0;
        c.keyframes = false;
        c.motion.max_intensity_sigma = f64::INFINITY;
        c.motion.max_depth_sigma_m = f64::INFINITY;
        // No depth-only `MOTION` against an untextured reference: the photometric
        // term always counts, as in the paper.
        c.motion.depth_only_texture_fraction = 0.0;
        c
    }

    /// Deepest pyramid level the schedule uses.
    pub fn pyramid_depth(&self) -> usize {
        self.motion
            .levels
            .iter()
            .map(|l| l.pyramid_level)
            .max()
            .unwrap_or(0)
    }
}

/// Parses reference levels written as `"30mm:7deg,120mm:12deg"` (metres with `m`,
/// millimetres with `mm`, degrees with `deg`). An empty string means naive tracking.
pub fn parse_levels(s: &str) -> Result<Vec<ReferenceLevel>> {
    let bad = |why: String| Error::InvalidConfig {
        field: "levels",
        why,
    };
    parse_pairs(
        s,
        ':',
        "DISTANCE:ANGLE, e.g. 30mm:7deg",
        &bad,
        |pair, d, a| {
            let d = d.trim();
            let dist = if let Some(v) = d.strip_suffix("mm") {
                v.trim().parse::<f64>().map(|x| x / 1000.0)
            } else if let Some(v) = d.strip_suffix('m') {
                v.trim().parse::<f64>()
            } else {
                return Err(bad(format!("distance `{d}` needs a unit, mm or m")));
            }
            .map_err(|e| bad(format!("distance `{d}`: {e}")))?;
            let a = a.trim();
            let ang = a
                .strip_suffix("deg")
                .ok_or_else(|| bad(format!("angle `{a}` needs the unit deg")))?
                .trim()
                .parse::<f64>()
                .map_err(|e| bad(format!("angle `{a}`: {e}")))?;
            if !(dist.is_finite() && dist >= 0.0 && ang.is_finite() && (0.0..180.0).contains(&ang))
            {
                return Err(bad(format!("`{pair}` is out of range")));
            }
            Ok(ReferenceLevel {
                max_distance_m: dist,
                max_angle_deg: ang,
            })
        },
    )
}

/// The comma-separated `LEFT<sep>RIGHT` pairs of `s`, each parsed by `each(pair,
/// left, right)`; an empty string or `none` gives no pair. A piece without `sep` is
/// refused with `bad("`piece` is not FORM")`.
pub(crate) fn parse_pairs<T>(
    s: &str,
    sep: char,
    form: &str,
    bad: &impl Fn(String) -> Error,
    mut each: impl FnMut(&str, &str, &str) -> Result<T>,
) -> Result<Vec<T>> {
    let s = s.trim();
    if s.is_empty() || s.eq_ignore_ascii_case("none") {
        return Ok(Vec::new());
    }
    s.split(',')
        .map(|pair| {
            let (left, right) = pair
                .split_once(sep)
                .ok_or_else(|| bad(format!("`{pair}` is not {form}")))?;
            each(pair, left, right)
        })
        .collect()
}

#[cfg(test)]
mod tests;
