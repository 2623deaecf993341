//! What the tracker does with a correction (\[B\], \[C\], ...): how far its result lies
//! from its guess ([`correction_distance`], the gate), and how it is fused with the
//! frame-to-frame chain it corrects ([`fuse_correction`]).

use nalgebra::Matrix6;

use crate::Pose;
use crate::motion::MotionResult;
use crate::se3;

/// A correction fused with the frame-to-frame chain it corrects: the motion since
/// the reference as chained (\[A\] after \[A\], `guess`, with covariance `chain`, those
/// \[A\]s' inverse information matrices carried along by [`chain_step`]) and as
/// registered directly against the reference (`result`, covariance the inverse of its
/// information matrix), combined by their covariances as a Kalman update does: the
/// result moved towards the guess by `K = Σ_result (Σ_result + Σ_chain)⁻¹` in MOTION's
/// tangent space. A chain of few, well-constrained \[A\]s keeps most of its own
/// estimate; a long one takes the direct registration. `None` when a matrix is
/// singular.
pub fn fuse_correction(guess: &Pose, chain: &Matrix6<f64>, result: &MotionResult) -> Option<Pose> {
    let corr = result.information.try_inverse()?;
    let gain = corr * (corr + chain).try_inverse()?;
    // MOTION moves T_{j→i} = pose⁻¹ by left perturbations: exp(δ) T_result = T_guess.
    let delta = se3::log(&se3::compose(&guess.inverse(), &result.pose));
    let t = se3::compose(&se3::exp(&(gain * delta)), &result.pose.inverse());
    let fused = t.inverse();
    se3::is_finite(&fused).then_some(fused)
}

/// The chain's covariance one \[A\] on: `Ad · chain · Adᵀ + step`, the earlier
/// frames' uncertainty carried into the current camera's coordinates (MOTION's
/// perturbations act there) by the adjoint of `T_{p→c} = motion⁻¹`, plus the new
/// \[A\]'s (`motion` is its `T_{c,p}`, `step` the inverse of its information matrix).
pub fn chain_step(chain: &Matrix6<f64>, motion: &Pose, step: &Matrix6<f64>) -> Matrix6<f64> {
    let ad = adjoint(&motion.inverse());
    ad * chain * ad.transpose() + step
}

/// The adjoint of `t` on twists `[v; ω]`: `[[R, [t]×R], [0, R]]`.
pub fn adjoint(t: &Pose) -> Matrix6<f64> {
    let r = t.rotation.to_rotation_matrix().into_inner();
    let tr = se3::hat(&t.translation.vector) * r;
    let mut a = Matrix6::zeros();
    a.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    a.fixed_view_mut::<3, 3>(0, 3).copy_from(&tr);
    a.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    a
}

/// How far a correction's result lies from its initial guess, in the metric of its
/// information matrix: `δᵀ H δ / n`, the mean change of the whitened squared residuals
/// (units of the residuals' variance) that the move from guess to result makes, for
/// the twist δ between them and `n` residuals.
pub fn correction_distance(init: &Pose, r: &MotionResult) -> f64 {
    // MOTION moves T_{j→i} = pose⁻¹ by left perturbations: exp(δ) = pose⁻¹ · init.
    let delta = se3::log(&se3::compose(&r.pose.inverse(), init));
    let n = r.valid_pixels.max(1) as f64;
    (delta.transpose() * r.information * delta)[(0, 0)] / n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Status;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    fn result(pose: Pose, information: Matrix6<f64>) -> MotionResult {
        MotionResult {
            pose,
            iterations: Default::default(),
            steps: 1,
            error: 0.0,
            valid_pixels: 1000,
            template_points: 1000,
            information,
            scale: None,
            start: 0,
            status: Status::Converged,
            depth_spread: Default::default(),
            images_pose: None,
        }
    }

    fn pose(x: f64, yaw: f64) -> Pose {
        Pose::from_parts(
            Translation3::new(x, 0.02, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), yaw),
        )
    }

    fn close(a: &Pose, b: &Pose, tol: f64) -> bool {
        (a.translation.vector - b.translation.vector).norm() < tol
            && a.rotation.angle_to(&b.rotation) < tol
    }

    #[test]
    fn a_certain_chain_keeps_its_guess_and_an_uncertain_one_takes_the_result() {
        let guess = pose(0.10, 0.05);
        let measured = pose(0.12, 0.06);
        let info = Matrix6::identity() * 1e6;
        let r = result(measured, info);
        let kept = fuse_correction(&guess, &(Matrix6::identity() * 1e-12), &r).unwrap();
        assert!(close(&kept, &guess, 1e-6), "{kept:?}");
        let taken = fuse_correction(&guess, &(Matrix6::identity() * 1e3), &r).unwrap();
        assert!(close(&taken, &measured, 1e-6), "{taken:?}");
    }

    #[test]
    fn the_adjoint_moves_a_perturbation_across_a_pose() {
        // exp(Ad(T) ξ) = T exp(ξ) T⁻¹.
        let t = pose(0.3, 0.4);
        let xi = crate::se3::Twist::new(0.01, -0.02, 0.03, 0.002, 0.001, -0.003);
        let lhs = se3::exp(&(adjoint(&t) * xi));
        let rhs = se3::compose(&se3::compose(&t, &se3::exp(&xi)), &t.inverse());
        assert!(close(&lhs, &rhs, 1e-12), "{lhs:?} vs {rhs:?}");
        // Carried across the identity, the chain just adds up.
        let c = Matrix6::identity() * 2.0;
        assert_eq!(chain_step(&c, &Pose::identity(), &c), c * 2.0);
    }

    #[test]
    fn equal_covariances_meet_halfway() {
        let guess = pose(0.10, 0.05);
        let measured = pose(0.12, 0.07);
        let info = Matrix6::identity() * 1e4;
        let r = result(measured, info);
        let half = fuse_correction(&guess, &(Matrix6::identity() * 1e-4), &r).unwrap();
        assert!((half.translation.vector.x - 0.11).abs() < 1e-3, "{half:?}");
        assert!((half.rotation.angle() - 0.06).abs() < 1e-3, "{half:?}");
        // A singular information matrix fuses nothing.
        assert!(
            fuse_correction(
                &guess,
                &Matrix6::zeros(),
                &result(measured, Matrix6::zeros())
            )
            .is_none()
        );
    }
}
