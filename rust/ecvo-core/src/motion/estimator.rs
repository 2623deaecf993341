//! The Gauss-Newton schedule of `MOTION`: coarse-to-fine steps, the choice between
//! initial guesses, the acceptance of updates and the scale fit. The per-point loops
//! it drives are behind [`Loops`], so that the reference implementation kept for the
//! tests runs the very same schedule.

use nalgebra::{Matrix6, SymmetricEigen, UnitQuaternion, Vector3};

use super::warp::NoiseGain;
use super::{Failure, MAX_STARTS, MAX_STEPS, MotionResult, NormalEquations, Status};
use crate::Pose;
use crate::config::{MAX_SCALE_PASSES, MotionConfig, MotionLevel, Weighting};
use crate::noise::DepthSpread;
use crate::prepare::{ImageLevel, PreparedFrame};
use crate::scale::{self, PassSums, Scale, Whitener};
use crate::se3;

/// The per-point loops over the residuals of the last warp. Every sum runs over
/// fixed chunks of template points and adds their partial sums in chunk order.
pub(super) trait Loops {
    /// Takes the template points of the next coarse-to-fine step.
    fn load(&mut self, points: &[[f32; 4]]);
    /// Warps the loaded template into `level` under `t` (`T_{j→i}`) and stores the
    /// residuals of the points that land inside it; returns how many there are.
    fn warp(&mut self, t: &Pose, level: &ImageLevel, p: &Params) -> usize;
    /// Residuals stored by the last warp.
    fn valid(&self) -> usize;
    /// Stored residuals with a depth residual, and without.
    fn counts(&self) -> (usize, usize);
    /// The plain second moments of the stored residuals (see
    /// [`scale::initial_scale`]).
    fn moments(&self, weighting: Weighting) -> PassSums;
    /// One fixed-point pass of the scale fit at the scale `wh`, and `Σ w d²` at it
    /// (the bits of [`Self::cost`]).
    fn pass(&mut self, wh: &Whitener, weighting: Weighting) -> (PassSums, f64);
    /// `Σ w d²` over the stored residuals at the scale `wh`.
    fn cost(&mut self, wh: &Whitener) -> f64;
    /// Weights and whitens the stored residuals and accumulates the normal
    /// equations, with their [`Self::cost`] as the error.
    fn normal_equations(&mut self, level: &ImageLevel, wh: &Whitener) -> NormalEquations;
    /// The raw depth residuals' spread per depth over the stored residuals (see
    /// [`MotionResult::depth_spread`]); none by default.
    fn depth_spread(&mut self) -> DepthSpread {
        DepthSpread::default()
    }
}

/// Smallest number of residuals a coarse step needs to be worth solving.
const MIN_STEP_RESIDUALS: usize = 24;

/// The settings of one `MOTION` call, in the form the per-pixel loops use.
#[derive(Clone, Copy, Debug)]
pub(super) struct Params {
    /// ν.
    pub(super) nu: f32,
    /// λ.
    pub(super) lambda: f32,
    /// The scale's form.
    pub(super) weighting: Weighting,
    /// The depth residual's gain as a function of depth.
    pub(super) noise: NoiseGain,
    /// [`MotionConfig::scale_tolerance`].
    pub(super) scale_tolerance: f64,
    /// `Σ_ZZ` is whitened as at least this times `Σ_II` (0 at every step but the
    /// finest, `1 / MotionConfig::max_fine_depth_weight` there).
    pub(super) zz_floor: f64,
    /// False when the reference frame has too little texture for a photometric term
    /// and the current frame has enough ([`MotionConfig::depth_only_texture_fraction`]):
    /// the reference's intensities say nothing, and the current frame's gradients
    /// would pull the warp toward its dark pixels, so every photometric residual and
    /// gradient is zero and `MOTION` runs on depth.
    pub(super) photometric: bool,
    /// A prior on the rotation ([`MotionConfig::rotation_prior_information`]).
    pub(super) rotation_prior: Option<RotationPrior>,
}

/// A prior term on the rotation of `T_{j→i}`: `info · |Log(R R_target⁻¹)|²`.
#[derive(Clone, Copy, Debug)]
pub(super) struct RotationPrior {
    /// `R_target⁻¹`: the rotation of the start it came from (`T_{i→j}`'s).
    target_inv: UnitQuaternion<f64>,
    /// Its information, 1/rad².
    info: f64,
}

impl RotationPrior {
    /// The prior of `cfg` for a call with starts `inits`: the last start's rotation,
    /// when there are several starts and `cfg` gives it an information.
    fn of(cfg: &MotionConfig, inits: &[Pose]) -> Option<RotationPrior> {
        let info = cfg.rotation_prior_information;
        (info > 0.0 && info.is_finite() && inits.len() > 1).then(|| RotationPrior {
            target_inv: inits[inits.len() - 1].rotation,
            info,
        })
    }

    /// `Log(R R_target⁻¹)` for `t` (`T_{j→i}`).
    fn residual(&self, t: &Pose) -> Vector3<f64> {
        (t.rotation * self.target_inv).scaled_axis()
    }

    /// The term's cost at `t`.
    fn cost(&self, t: &Pose) -> f64 {
        self.info * self.residual(t).norm_squared()
    }

    /// `ne` with the term linearised at `t` added.
    fn add_to(&self, ne: &NormalEquations, t: &Pose) -> NormalEquations {
        ne.with_rotation_prior(&self.residual(t), self.info)
    }
}

impl Params {
    pub(super) fn of(cfg: &MotionConfig) -> Params {
        Params {
            nu: cfg.t_dof as f32,
            lambda: cfg.depth_gain as f32,
            weighting: cfg.weighting,
            noise: NoiseGain::of(cfg.depth_noise, cfg.depth_gain as f32),
            scale_tolerance: cfg.scale_tolerance,
            zz_floor: 0.0,
            photometric: true,
            rotation_prior: None,
        }
    }

    /// The whitener of `s` under these parameters.
    fn whitener(&self, s: &Scale) -> Whitener {
        s.whitener_with(self.nu, self.zz_floor)
    }
}

/// What one coarse-to-fine step left.
#[derive(Clone, Copy, Debug)]
struct StepOutcome {
    /// `T_{j→i}` at the end of the step.
    t: Pose,
    /// The normal equations of the last linearisation (None: the step never had
    /// enough residuals).
    ne: Option<NormalEquations>,
    /// `T_{j→i}` where `ne` was linearised.
    ne_at: Pose,
    /// Gauss-Newton iterations run (steps solved).
    iterations: u32,
    /// True when the step used all its iterations, each one accepted.
    hit_max: bool,
    /// The scale at the end of the step.
    scale: Option<Scale>,
    /// Mean robust cost at `t` for `scale`.
    cost: f64,
    /// Residuals at `t`.
    valid: usize,
}

/// `MOTION` from the best of several initial guesses: the coarsest step runs from
/// each, and the one whose result explains the template best (the lowest mean
/// robust cost at a common scale, a template point that leaves the image costing
/// as much as the worst outlier) goes on to the finer steps. Ties go to the
/// earlier guess. [`MotionResult::start`] says which one won. At most
/// [`MAX_STARTS`] guesses are tried.
pub(super) fn motion_from<K: Loops>(
    lp: &mut K,
    fi: &PreparedFrame,
    fj: &PreparedFrame,
    inits: &[Pose],
    cfg: &MotionConfig,
) -> MotionResult {
    let first = inits.first().copied().unwrap_or_else(Pose::identity);
    let mut result = MotionResult {
        pose: first,
        iterations: [0; MAX_STEPS],
        steps: cfg.levels.len().min(MAX_STEPS),
        error: f64::NAN,
        valid_pixels: 0,
        template_points: 0,
        information: Matrix6::zeros(),
        scale: None,
        start: 0,
        status: Status::Failed(Failure::TooFewPixels),
        depth_spread: DepthSpread::default(),
        images_pose: None,
    };
    if inits.is_empty() || !inits.iter().all(se3::is_finite) {
        result.status = Status::Failed(Failure::NotFinite);
        return result;
    }
    // A textured current frame against an untextured reference (the first frame
    // after a black run): depth alone. Two untextured frames (low contrast
    // throughout) keep the photometric term, weak as it is.
    let p = Params {
        photometric: textured(fj, cfg) || !textured(fi, cfg),
        rotation_prior: RotationPrior::of(cfg, inits),
        ..Params::of(cfg)
    };
    let mut last_step: Option<StepOutcome> = None;
    let mut scale: Option<Scale> = None;
    let mut t = first.inverse();
    let finest = cfg.levels.len().min(MAX_STEPS).saturating_sub(1);
    // `fine_weighting`: the finest step weighs with its own form, from a fresh scale;
    // the spread check then refits the configured form on its residuals.
    let fine = cfg.fine_weighting.filter(|w| *w != p.weighting);
    let mut fine_level: Option<&ImageLevel> = None;
    let templates = fj.templates();
    for (k, step) in cfg.levels.iter().enumerate().take(MAX_STEPS) {
        let (Some(level), Some(template)) = (fi.levels.get(step.pyramid_level), templates.get(k))
        else {
            break;
        };
        // `E[1/z]` over every 8th template point, for the flow of an update
        // (`min_update_px`): a threshold's estimate, at an eighth of the cost.
        let inv_depth = if cfg.min_update_px > 0.0 && !template.points.is_empty() {
            let (s, n) = template
                .points
                .iter()
                .step_by(8)
                .fold((0.0f64, 0usize), |(s, n), q| (s + 1.0 / q[2] as f64, n + 1));
            s / n as f64
        } else {
            0.0
        };
        let pk = match fine {
            Some(weighting) if k == finest => {
                fine_level = Some(level);
                Params { weighting, ..p }
            }
            _ if k == finest => Params {
                zz_floor: 1.0 / cfg.max_fine_depth_weight,
                ..p
            },
            _ => p,
        };
        let start = if fine_level.is_some() { None } else { scale };
        lp.load(&template.points);
        result.template_points = template.points.len();
        let out = if k == 0 && inits.len() > 1 {
            let (best, out) = best_start(
                lp,
                level,
                template.points.len(),
                inits,
                step,
                cfg,
                &pk,
                inv_depth,
            );
            result.start = best as u8;
            out
        } else {
            run_step(lp, level, t, step, cfg, &pk, start, inv_depth)
        };
        result.iterations[k] = out.iterations;
        t = out.t;
        if out.scale.is_some() && fine_level.is_none() {
            scale = out.scale;
        }
        last_step = Some(out);
    }
    // The scale the spread check reads: the configured form's, refitted on the finest
    // step's residuals at its final pose when that step weighed otherwise.
    let check = match (fine_level, last_step) {
        (Some(level), Some(_)) => {
            let pose = t;
            lp.warp(&pose, level, &p);
            fit_scale(lp, &p, scale, None, MAX_SCALE_PASSES)
        }
        (_, last) => last.and_then(|l| l.scale),
    };

    let Some(last) = last_step else {
        return result;
    };
    let Some(ne) = last.ne else {
        return result;
    };
    result.error = last.cost;
    result.valid_pixels = last.valid;
    result.information = ne.hessian();
    result.scale = check.or(last.scale);
    let pose = t.inverse();
    result.status = if last.valid < cfg.min_valid_pixels {
        Status::Failed(Failure::TooFewPixels)
    } else if !se3::is_finite(&pose) {
        Status::Failed(Failure::NotFinite)
    } else if is_degenerate(&result.information) {
        Status::Failed(Failure::Degenerate)
    } else if pose.translation.vector.norm() > cfg.max_translation_m
        || se3::angle(&pose).to_degrees() > cfg.max_rotation_deg
    {
        Status::Failed(Failure::TooLarge)
    } else if check.is_some_and(|s| {
        (s.ii.sqrt() > cfg.max_intensity_sigma && textured(fi, cfg) && p.photometric)
            || s.zz.sqrt() > cfg.max_depth_sigma_m * cfg.depth_gain.max(1e-9)
    }) {
        Status::Failed(Failure::Inconsistent)
    } else if last.hit_max {
        Status::MaxIterations
    } else {
        Status::Converged
    };
    if result.is_ok() {
        result.pose = pose;
        if p.rotation_prior.is_some() {
            // The images' own Gauss-Newton step from their last linearisation.
            result.images_pose = ne
                .solve()
                .map(|d| se3::compose(&se3::exp(&d), &last.ne_at).inverse())
                .filter(se3::is_finite);
        }
        if cfg.depth_spread {
            // The residuals of the finest step's last warp (at its final pose, or at an
            // update it then rejected: close to it).
            result.depth_spread = lp.depth_spread();
        }
    }
    result
}

/// True when frame `fi` has enough texture for a photometric term: as the current
/// frame, for its photometric spread to be checked; as the reference, for the term
/// to be used at all ([`MotionConfig::depth_only_texture_fraction`]).
fn textured(fi: &PreparedFrame, cfg: &MotionConfig) -> bool {
    let pixels = fi.levels.first().map_or(0, |l| l.camera().pixels());
    fi.textured_pixels as f64 >= cfg.depth_only_texture_fraction * pixels as f64
}

/// Runs the first step from every guess and keeps the best (see
/// [`Self::motion_from`]); returns its index and outcome.
fn best_start<K: Loops>(
    lp: &mut K,
    level: &ImageLevel,
    points: usize,
    inits: &[Pose],
    step: &MotionLevel,
    cfg: &MotionConfig,
    p: &Params,
    inv_depth: f64,
) -> (usize, StepOutcome) {
    // On the stack: a warm estimator does not allocate.
    let mut slots: [Option<StepOutcome>; MAX_STARTS] = [None; MAX_STARTS];
    for (slot, init) in slots.iter_mut().zip(inits) {
        *slot = Some(run_step(
            lp,
            level,
            init.inverse(),
            step,
            cfg,
            p,
            None,
            inv_depth,
        ));
    }
    let outs = slots.iter().flatten();
    // A common scale: the first guess's (the identity's, for [A]), or with
    // `scale_from_last_start` the last one's (a trusted prior's: a wrong start's wide
    // scale would flatter it, and out-of-view points, which a large true motion
    // has, count as the worst outliers).
    let common = if cfg.scale_from_last_start {
        outs.clone().rev().find_map(|o| o.scale)
    } else {
        outs.clone().find_map(|o| o.scale)
    };
    let Some(common) = common else {
        return (0, slots[0].expect("at least one start"));
    };
    let wh = p.whitener(&common);
    let total = points.max(1) as f64;
    let mut best = (0, f64::INFINITY);
    for (k, o) in outs.enumerate() {
        if o.ne.is_none() {
            continue;
        }
        lp.warp(&o.t, level, p);
        let cost = lp.cost(&wh);
        let missing = (points - lp.valid()) as f64 * wh.max_cost() as f64;
        let c = (cost + missing) / total;
        if c < best.1 {
            best = (k, c);
        }
    }
    (best.0, slots[best.0].expect("the best start ran"))
}

/// One coarse-to-fine step: Gauss-Newton from `t` with the scale re-fitted after
/// every accepted update (by at most [`MotionConfig::scale_passes_per_update`]
/// fixed-point passes; the scale fit at the start of the step runs to convergence).
/// An update is accepted only if it lowers the mean robust cost at the scale it was
/// computed with (the IRLS majoriser, so the robust objective itself does not rise)
/// and leaves enough residuals; otherwise it is undone and the step ends (with a
/// rotation prior, the cost and the system are the images' plus the prior's). From the
/// second iteration on, an update whose predicted decrease is below
/// [`MotionConfig::min_predicted_decrease`] is not tried: the step ends there.
fn run_step<K: Loops>(
    lp: &mut K,
    level: &ImageLevel,
    mut t: Pose,
    step: &MotionLevel,
    cfg: &MotionConfig,
    p: &Params,
    start: Option<Scale>,
    inv_depth: f64,
) -> StepOutcome {
    // Pixels of flow per unit of `|v| E[1/z] + |ω|` at this level (see
    // `MotionConfig::min_update_px`).
    let px_per_unit = level.camera.map_or(0.0, |c| {
        c.fx.max(c.fy) + 0.5 * ((c.width * c.width + c.height * c.height) as f64).sqrt()
    });
    let mut out = StepOutcome {
        t,
        ne: None,
        ne_at: t,
        iterations: 0,
        hit_max: false,
        scale: start,
        cost: f64::NAN,
        valid: 0,
    };
    let mut n = lp.warp(&t, level, p);
    if n < MIN_STEP_RESIDUALS {
        return out;
    }
    let Some(mut scale) = fit_scale(lp, p, start, None, MAX_SCALE_PASSES) else {
        return out;
    };
    let mut wh = p.whitener(&scale);
    // The mean robust cost at `t` for `wh`; each linearisation sums it, so after an
    // accepted update (a new `t` and scale) it is stale until the next one.
    let mut cost = f64::NAN;
    let mut stale = true;
    out.hit_max = true;
    for it in 0..step.max_iterations {
        let ne = lp.normal_equations(level, &wh);
        cost = ne.error / n as f64;
        stale = false;
        // The registration's information stays the images' alone.
        out.ne = Some(ne);
        out.ne_at = t;
        out.iterations = it + 1;
        // What the update minimises: with a rotation prior, its term too.
        let (sys, total) = match &p.rotation_prior {
            None => (ne, cost),
            Some(prior) => {
                let sys = prior.add_to(&ne, &t);
                (sys, sys.error / n as f64)
            }
        };
        let Some(delta) = sys.solve() else {
            out.hit_max = false;
            break;
        };
        // The model's decrease of `Σ w d²` for δ: `−gᵀδ` (= `gᵀH⁻¹g`).
        let predicted = -delta.iter().zip(&sys.g).map(|(d, g)| d * g).sum::<f64>();
        if it > 0 && predicted < cfg.min_predicted_decrease * sys.error {
            out.hit_max = false;
            break;
        }
        let candidate = se3::compose(&se3::exp(&delta), &t);
        let m = lp.warp(&candidate, level, p);
        if m < MIN_STEP_RESIDUALS {
            out.hit_max = false;
            break;
        }
        // The candidate's cost and the first pass of the scale fit at `wh`, together.
        let (first, c) = lp.pass(&wh, p.weighting);
        let c = match &p.rotation_prior {
            None => c / m as f64,
            Some(prior) => (c + prior.cost(&candidate)) / m as f64,
        };
        // `!(c <= total)` also rejects NaN.
        if !(c <= total) {
            out.hit_max = false;
            break;
        }
        t = candidate;
        n = m;
        let passes = cfg.scale_passes_per_update;
        if let Some(s) = fit_scale(lp, p, Some(scale), Some(first), passes) {
            scale = s;
            wh = p.whitener(&scale);
        }
        stale = true;
        let (v, w) = (
            delta.fixed_rows::<3>(0).norm(),
            delta.fixed_rows::<3>(3).norm(),
        );
        let small = (v < cfg.min_update && w < cfg.min_update)
            || px_per_unit * (v * inv_depth + w) < cfg.min_update_px;
        if small {
            out.hit_max = false;
            break;
        }
    }
    if stale {
        cost = lp.cost(&wh) / n as f64;
    }
    out.t = t;
    out.scale = Some(scale);
    out.cost = cost;
    out.valid = n;
    out
}

/// Fits the scale to the stored residuals by at most `passes` steps of the
/// fixed-point iteration from `start` (or from their plain second moments); `None`
/// when there is no residual. `first`: the sums of a pass at `start` already made.
fn fit_scale<K: Loops>(
    lp: &mut K,
    p: &Params,
    start: Option<Scale>,
    first: Option<PassSums>,
    passes: usize,
) -> Option<Scale> {
    let (two, one) = lp.counts();
    let (mut s, mut first) = match start {
        Some(s) if s.ii > 0.0 && s.zz > 0.0 && s.ii.is_finite() && s.zz.is_finite() => (s, first),
        _ => (
            scale::next_scale(&lp.moments(p.weighting), two, one, p.weighting)?,
            None,
        ),
    };
    for _ in 0..passes.clamp(1, MAX_SCALE_PASSES) {
        let total = match first.take() {
            Some(sums) => sums,
            None => lp.pass(&p.whitener(&s), p.weighting).0,
        };
        let next = scale::next_scale(&total, two, one, p.weighting)?;
        let done = scale::settled(&s, &next, p.scale_tolerance);
        s = next;
        if done {
            break;
        }
    }
    Some(s)
}

/// True when the Jacobi-scaled information matrix is nearly singular: some motion
/// is not observed by the input (a flat, textureless plane, for instance).
fn is_degenerate(h: &Matrix6<f64>) -> bool {
    let d: [f64; 6] = std::array::from_fn(|i| h[(i, i)]);
    if d.iter().any(|&x| !(x > 0.0) || !x.is_finite()) {
        return true;
    }
    let scaled = Matrix6::from_fn(|r, c| h[(r, c)] / (d[r] * d[c]).sqrt());
    let eig = SymmetricEigen::new(scaled).eigenvalues;
    let (lo, hi) = eig.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &e| {
        (lo.min(e), hi.max(e))
    });
    !(lo > 1e-6 * hi)
}
