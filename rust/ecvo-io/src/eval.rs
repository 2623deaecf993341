//! Trajectory evaluation as the TUM RGB-D tools and evo do it: timestamp
//! association, absolute trajectory error after a rigid alignment, and relative pose
//! error.

use ecvo_core::{Num, Pose};
use nalgebra::{Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::list::associate_stamps;
use crate::trajectory::Trajectory;

/// Default largest timestamp difference (seconds, exclusive) for associating poses,
/// as in TUM's `associate.py` and `evaluate_ate.py`.
pub const DEFAULT_MAX_DT: f64 = 0.02;

/// Pairs `(gt index, est index)` of poses whose timestamps differ by less than
/// `max_dt` seconds, one-to-one and greedy by smallest difference as TUM's
/// `associate.py` does, sorted by ground-truth time.
pub fn associate(gt: &Trajectory, est: &Trajectory, max_dt: f64) -> Vec<(usize, usize)> {
    associate_stamps(&gt.stamps[..gt.len()], &est.stamps[..est.len()], max_dt)
}

/// Summary statistics of a set of non-negative errors (as evo reports them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    /// Root mean square.
    pub rmse: f64,
    /// Mean.
    pub mean: f64,
    /// Median (mean of the two middle values for an even count).
    pub median: f64,
    /// Population standard deviation.
    pub std: f64,
    /// Smallest error.
    pub min: f64,
    /// Largest error.
    pub max: f64,
    /// Number of errors.
    pub count: usize,
}

impl ErrorStats {
    /// Statistics of `errors`; `None` if it is empty.
    pub fn from_errors(errors: &[f64]) -> Option<ErrorStats> {
        let n = errors.len();
        if n == 0 {
            return None;
        }
        let nf = n as f64;
        let mean = errors.iter().sum::<f64>() / nf;
        let rmse = (errors.iter().map(|e| e * e).sum::<f64>() / nf).sqrt();
        let std = (errors.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / nf).sqrt();
        let mut sorted = errors.to_vec();
        sorted.sort_by(f64::total_cmp);
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        Some(ErrorStats {
            rmse,
            mean,
            median,
            std,
            min: sorted[0],
            max: sorted[n - 1],
            count: n,
        })
    }
}

/// Refuses statistics that are not finite: the inputs were finite, but their
/// magnitudes overflowed a sum (a score of NaN or infinity means nothing).
fn check_finite(what: &str, s: &ErrorStats) -> Result<()> {
    let all = [s.rmse, s.mean, s.median, s.std, s.min, s.max];
    if all.iter().all(|v| v.is_finite()) {
        return Ok(());
    }
    Err(Error::InvalidInput(format!(
        "{what} cannot be scored: its statistics overflow (RMSE {}, max {}); the \
         trajectories' values are too large",
        Num(s.rmse),
        Num(s.max)
    )))
}

/// The rigid motion `T` (rotation and translation, no scale) minimising
/// `sum |dst_i - T src_i|^2`, in closed form (Umeyama 1991 / Horn 1987): SVD of the
/// cross-covariance, with the sign of the smallest singular direction flipped when
/// needed so that the result is a rotation, never a reflection.
///
/// Needs at least 3 point pairs of equal-length slices with finite coordinates.
pub fn align_rigid(src: &[Vector3<f64>], dst: &[Vector3<f64>]) -> Result<Pose> {
    if src.len() != dst.len() {
        return Err(Error::InvalidInput(format!(
            "align_rigid: {} source points but {} destination points",
            src.len(),
            dst.len()
        )));
    }
    if src.len() < 3 {
        return Err(Error::TooFewPairs {
            found: src.len(),
            needed: 3,
        });
    }
    if src
        .iter()
        .chain(dst)
        .any(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(Error::InvalidInput(
            "align_rigid: non-finite coordinates".into(),
        ));
    }
    let n = src.len() as f64;
    let mu_s = src.iter().sum::<Vector3<f64>>() / n;
    let mu_d = dst.iter().sum::<Vector3<f64>>() / n;
    let mut sigma = Matrix3::zeros();
    for (s, d) in src.iter().zip(dst) {
        sigma += (d - mu_d) * (s - mu_s).transpose();
    }
    sigma /= n;
    let svd = sigma.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err(Error::InvalidInput("align_rigid: SVD failed".into()));
    };
    let mut d = Matrix3::identity();
    if u.determinant() * v_t.determinant() < 0.0 {
        let k = svd.singular_values.imin();
        d[(k, k)] = -1.0;
    }
    let r = u * d * v_t;
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = mu_d - rot * mu_s;
    Ok(Pose::from_parts(Translation3::from(t), rot))
}

/// Absolute trajectory error: statistics of the translational errors after the rigid
/// alignment of the estimate to the ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct AteResult {
    /// Root mean square of the translational errors, in metres (the ATE of the papers).
    pub rmse: f64,
    /// Mean error in metres.
    pub mean: f64,
    /// Median error in metres.
    pub median: f64,
    /// Population standard deviation of the errors in metres.
    pub std: f64,
    /// Smallest error in metres.
    pub min: f64,
    /// Largest error in metres.
    pub max: f64,
    /// Number of associated pose pairs.
    pub count: usize,
    /// The aligning transform: `gt ≈ alignment * est` (applied on the left of the
    /// estimated camera-to-world poses).
    pub alignment: Pose,
    /// Associated `(gt index, est index)` pairs, in ground-truth time order.
    pub pairs: Vec<(usize, usize)>,
    /// Translational error of each pair in metres, in the order of `pairs`.
    pub errors: Vec<f64>,
}

impl AteResult {
    /// The statistics as one value.
    pub fn stats(&self) -> ErrorStats {
        ErrorStats {
            rmse: self.rmse,
            mean: self.mean,
            median: self.median,
            std: self.std,
            min: self.min,
            max: self.max,
            count: self.count,
        }
    }

    /// `est` with the alignment applied to every pose (for plots against the ground
    /// truth).
    pub fn aligned(&self, est: &Trajectory) -> Trajectory {
        Trajectory {
            stamps: est.stamps.clone(),
            poses: est.poses.iter().map(|p| self.alignment * p).collect(),
        }
    }
}

/// Absolute trajectory error as TUM's `evaluate_ate.py` and `evo_ape tum GT EST -a`
/// compute it: associate poses by timestamp ([`associate`] with
/// [`DEFAULT_MAX_DT`]), find the rigid transform (no scale) that best maps the
/// estimated positions onto the ground-truth positions ([`align_rigid`]), and
/// take the statistics of the remaining position differences. Rotations do not enter.
///
/// Fewer than 3 associated pairs is [`Error::TooFewPairs`].
pub fn ate(gt: &Trajectory, est: &Trajectory) -> Result<AteResult> {
    ate_with_max_dt(gt, est, DEFAULT_MAX_DT)
}

/// [`ate`] with a chosen association threshold `max_dt` in seconds.
pub fn ate_with_max_dt(gt: &Trajectory, est: &Trajectory, max_dt: f64) -> Result<AteResult> {
    let pairs = associate(gt, est, max_dt);
    if pairs.len() < 3 {
        return Err(Error::TooFewPairs {
            found: pairs.len(),
            needed: 3,
        });
    }
    let g: Vec<Vector3<f64>> = pairs
        .iter()
        .map(|&(i, _)| gt.poses[i].translation.vector)
        .collect();
    let e: Vec<Vector3<f64>> = pairs
        .iter()
        .map(|&(_, j)| est.poses[j].translation.vector)
        .collect();
    let alignment = align_rigid(&e, &g)?;
    let errors: Vec<f64> = g
        .iter()
        .zip(&e)
        .map(|(g, e)| (g - (alignment.rotation * e + alignment.translation.vector)).norm())
        .collect();
    let s = ErrorStats::from_errors(&errors).ok_or(Error::TooFewPairs {
        found: 0,
        needed: 3,
    })?;
    check_finite("ATE", &s)?;
    Ok(AteResult {
        rmse: s.rmse,
        mean: s.mean,
        median: s.median,
        std: s.std,
        min: s.min,
        max: s.max,
        count: s.count,
        alignment,
        pairs,
        errors,
    })
}

/// Relative pose error: drift of the estimate over a fixed interval.
#[derive(Clone, Debug, PartialEq)]
pub struct RpeResult {
    /// The interval: seconds for [`rpe`], 1 frame for [`rpe_per_frame`].
    pub delta: f64,
    /// Translational errors in metres per interval.
    pub trans: ErrorStats,
    /// Rotational errors in degrees per interval.
    pub rot_deg: ErrorStats,
    /// The estimated-pose index pairs `(i, j)` that were compared.
    pub pairs: Vec<(usize, usize)>,
    /// Translational error of each pair, metres.
    pub trans_errors: Vec<f64>,
    /// Rotational error of each pair, degrees.
    pub rot_errors_deg: Vec<f64>,
}

/// Index of the element of ascending `sorted` closest to `t` (lower index on ties).
fn closest(sorted: &[f64], t: f64) -> usize {
    let k = sorted.partition_point(|&s| s < t);
    if k == 0 {
        0
    } else if k == sorted.len() || (t - sorted[k - 1]) <= (sorted[k] - t) {
        k - 1
    } else {
        k
    }
}

/// The error of estimated relative motion `E0 -> E1` against true motion `G0 -> G1`:
/// `(E0^-1 E1)^-1 (G0^-1 G1)`, as translation norm (m) and rotation angle (deg).
fn relative_error(e0: &Pose, e1: &Pose, g0: &Pose, g1: &Pose) -> (f64, f64) {
    let err = (e0.inv_mul(e1)).inv_mul(&g0.inv_mul(g1));
    (
        err.translation.vector.norm(),
        err.rotation.angle().to_degrees(),
    )
}

fn rpe_result(
    delta: f64,
    pairs: Vec<(usize, usize)>,
    errs: Vec<(f64, f64)>,
    needed: usize,
) -> Result<RpeResult> {
    let trans_errors: Vec<f64> = errs.iter().map(|e| e.0).collect();
    let rot_errors_deg: Vec<f64> = errs.iter().map(|e| e.1).collect();
    let too_few = Error::TooFewPairs {
        found: errs.len(),
        needed,
    };
    let (Some(trans), Some(rot_deg)) = (
        ErrorStats::from_errors(&trans_errors),
        ErrorStats::from_errors(&rot_errors_deg),
    ) else {
        return Err(too_few);
    };
    check_finite("RPE (translation)", &trans)?;
    check_finite("RPE (rotation)", &rot_deg)?;
    Ok(RpeResult {
        delta,
        trans,
        rot_deg,
        pairs,
        trans_errors,
        rot_errors_deg,
    })
}

/// Relative pose error over `delta_s` seconds, as TUM's `evaluate_rpe.py --fixed_delta
/// --delta 1 --delta_unit s` computes it (all pairs, no random subsampling):
///
/// - For every estimated pose `i` (in time order), `j` is the estimated pose whose
///   timestamp is closest to `t_i + delta_s`; the pair is skipped when `j` is the last
///   pose (the interval ran past the end) or `j == i`.
/// - Each of `t_i`, `t_j` is matched to the ground-truth pose with the closest
///   timestamp; the pair is skipped if either is further than twice the median
///   ground-truth sampling interval.
/// - The error is `E = (Ei^-1 Ej)^-1 (Gi^-1 Gj)`; its translation norm (m) and
///   rotation angle (deg) are the errors of the pair. They are not divided by the
///   actual time difference, so with `delta_s = 1` they are the drift in m/s and
///   deg/s that the TUM benchmark reports (`trans.rmse`, `rot_deg.rmse`).
///
/// No alignment is needed: relative motions do not depend on the world frame. No
/// usable pair is [`Error::TooFewPairs`].
pub fn rpe(gt: &Trajectory, est: &Trajectory, delta_s: f64) -> Result<RpeResult> {
    if !(delta_s.is_finite() && delta_s > 0.0) {
        return Err(Error::InvalidInput(format!(
            "rpe: delta must be positive seconds, got {delta_s}"
        )));
    }
    let order = |t: &Trajectory| {
        let mut idx: Vec<usize> = (0..t.len()).filter(|&i| t.stamps[i].is_finite()).collect();
        idx.sort_by(|&a, &b| t.stamps[a].total_cmp(&t.stamps[b]));
        idx
    };
    let (gi, ei) = (order(gt), order(est));
    if gi.len() < 2 || ei.len() < 2 {
        return Err(Error::TooFewPairs {
            found: 0,
            needed: 1,
        });
    }
    let gs: Vec<f64> = gi.iter().map(|&i| gt.stamps[i]).collect();
    let es: Vec<f64> = ei.iter().map(|&i| est.stamps[i]).collect();
    let mut intervals: Vec<f64> = gs.windows(2).map(|w| w[1] - w[0]).collect();
    intervals.sort_by(f64::total_cmp);
    let n = intervals.len();
    let median = if n % 2 == 1 {
        intervals[n / 2]
    } else {
        0.5 * (intervals[n / 2 - 1] + intervals[n / 2])
    };
    let max_gt_dt = 2.0 * median;

    let mut pairs = Vec::new();
    let mut errs = Vec::new();
    for a in 0..es.len() {
        let b = closest(&es, es[a] + delta_s);
        if b == es.len() - 1 || b <= a {
            continue;
        }
        let (g0, g1) = (closest(&gs, es[a]), closest(&gs, es[b]));
        if (gs[g0] - es[a]).abs() > max_gt_dt || (gs[g1] - es[b]).abs() > max_gt_dt {
            continue;
        }
        let (i, j) = (ei[a], ei[b]);
        errs.push(relative_error(
            &est.poses[i],
            &est.poses[j],
            &gt.poses[gi[g0]],
            &gt.poses[gi[g1]],
        ));
        pairs.push((i, j));
    }
    rpe_result(delta_s, pairs, errs, 1)
}

/// Relative pose error between consecutive frames, in metres and degrees per frame.
///
/// Poses are associated as in [`ate`] ([`associate`], [`DEFAULT_MAX_DT`]); for each
/// estimated pose `i` (the estimate is taken in its stored order) such that `i` and
/// `i + 1` are both associated, the error is `E = (Ei^-1 Ei+1)^-1 (Gi^-1 Gi+1)` with
/// the associated ground-truth poses, reported as its translation norm and rotation
/// angle. Fewer than 2 associated consecutive poses is [`Error::TooFewPairs`].
pub fn rpe_per_frame(gt: &Trajectory, est: &Trajectory) -> Result<RpeResult> {
    let assoc = associate(gt, est, DEFAULT_MAX_DT);
    let mut gt_of = vec![None; est.len()];
    for &(g, e) in &assoc {
        gt_of[e] = Some(g);
    }
    let mut pairs = Vec::new();
    let mut errs = Vec::new();
    for i in 0..est.len().saturating_sub(1) {
        if let (Some(g0), Some(g1)) = (gt_of[i], gt_of[i + 1]) {
            errs.push(relative_error(
                &est.poses[i],
                &est.poses[i + 1],
                &gt.poses[g0],
                &gt.poses[g1],
            ));
            pairs.push((i, i + 1));
        }
    }
    rpe_result(1.0, pairs, errs, 1)
}
