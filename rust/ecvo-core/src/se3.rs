//! SE(3) exponential and logarithm with the proper left Jacobian `V`.
//!
//! Twists are `[v; ω]`: translation part first, rotation part (axis times angle)
//! last. `exp(ξ)` maps a twist to a rigid motion; `log` is its inverse for rotation
//! angles below π. nalgebra provides `Isometry3` but not these maps.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6};

/// A twist `[v; ω]` in se(3).
pub type Twist = Vector6<f64>;

/// The skew-symmetric matrix `[w]×` with `[w]× x = w × x`.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// The left Jacobian of SO(3), `V(ω) = I + (1-cos θ)/θ² W + (θ-sin θ)/θ³ W²`.
fn left_jacobian(w: &Vector3<f64>) -> Matrix3<f64> {
    let theta2 = w.norm_squared();
    let wx = hat(w);
    let (a, b) = if theta2 < 1e-10 {
        // Taylor expansions: (1-cos θ)/θ² ≈ 1/2 - θ²/24, (θ-sin θ)/θ³ ≈ 1/6 - θ²/120.
        (0.5 - theta2 / 24.0, 1.0 / 6.0 - theta2 / 120.0)
    } else {
        let theta = theta2.sqrt();
        (
            (1.0 - theta.cos()) / theta2,
            (theta - theta.sin()) / (theta2 * theta),
        )
    };
    Matrix3::identity() + wx * a + wx * wx * b
}

/// The inverse of [`left_jacobian`], `V⁻¹ = I - W/2 + (1/θ²)(1 - θ sin θ / (2(1 - cos θ))) W²`.
fn left_jacobian_inverse(w: &Vector3<f64>) -> Matrix3<f64> {
    let theta2 = w.norm_squared();
    let wx = hat(w);
    // c = (1 − (θ/2) cot(θ/2)) / θ² (= (1 − θ sinθ / (2(1 − cosθ))) / θ², written
    // without 1 − cosθ, which loses digits as θ → 0); its series below 1e-3 rad.
    let c = if theta2 < 1e-6 {
        1.0 / 12.0 + theta2 / 720.0 + theta2 * theta2 / 30240.0
    } else {
        let half = 0.5 * theta2.sqrt();
        (1.0 - half * half.cos() / half.sin()) / theta2
    };
    Matrix3::identity() - wx * 0.5 + wx * wx * c
}

/// The exponential map se(3) → SE(3).
pub fn exp(xi: &Twist) -> Isometry3<f64> {
    let v = Vector3::new(xi[0], xi[1], xi[2]);
    let w = Vector3::new(xi[3], xi[4], xi[5]);
    let rotation = UnitQuaternion::from_scaled_axis(w);
    let t = left_jacobian(&w) * v;
    Isometry3::from_parts(Translation3::from(t), rotation)
}

/// The logarithm SE(3) → se(3); exact inverse of [`exp`] for rotation angles below π.
pub fn log(pose: &Isometry3<f64>) -> Twist {
    let w = pose.rotation.scaled_axis();
    let v = left_jacobian_inverse(&w) * pose.translation.vector;
    Twist::new(v.x, v.y, v.z, w.x, w.y, w.z)
}

/// The rotation angle of a pose in radians, from the trace of its rotation matrix
/// (clamped so that rounding never produces NaN).
pub fn angle(pose: &Isometry3<f64>) -> f64 {
    let r: Rotation3<f64> = pose.rotation.to_rotation_matrix();
    ((r.matrix().trace() - 1.0) * 0.5).clamp(-1.0, 1.0).acos()
}

/// `a * b` with the rotation renormalised: nalgebra's `UnitQuaternion` product
/// does not renormalise, and the inverse is a conjugate, so rounding in long
/// chains of `inverse() * pose` would otherwise grow exponentially.
pub fn compose(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Isometry3<f64> {
    let mut p = a * b;
    p.rotation.renormalize();
    p
}

/// True when every component of the pose is finite.
pub fn is_finite(pose: &Isometry3<f64>) -> bool {
    pose.translation.vector.iter().all(|x| x.is_finite())
        && pose.rotation.coords.iter().all(|x| x.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn log_keeps_its_digits_at_small_angles_and_long_translations() {
        // Found by the property test: 1 − cos θ lost digits at θ ≈ 1e-4.
        let xi = Twist::new(
            0.0,
            0.0,
            -6.606275882236122,
            0.0,
            -9.374992926100006e-5,
            0.0,
        );
        let back = log(&exp(&xi));
        assert!((back - xi).norm() <= 1e-12 * (1.0 + xi.norm()), "{back:?}");
    }

    fn twists() -> Vec<Twist> {
        vec![
            Twist::zeros(),
            Twist::new(0.1, -0.2, 0.3, 0.0, 0.0, 0.0),
            Twist::new(0.1, -0.2, 0.3, 0.01, -0.02, 0.03),
            Twist::new(-1.0, 0.5, 2.0, 0.7, -0.4, 1.1),
            Twist::new(0.0, 0.0, 0.0, 1e-9, 2e-9, -1e-9),
            Twist::new(0.3, 0.2, 0.1, 0.0, 3.0, 0.0),
        ]
    }

    #[test]
    fn log_inverts_exp() {
        for xi in twists() {
            let back = log(&exp(&xi));
            assert_relative_eq!(back, xi, epsilon = 1e-9);
        }
    }

    #[test]
    fn exp_inverts_log() {
        for xi in twists() {
            let t = exp(&xi);
            let t2 = exp(&log(&t));
            assert_relative_eq!(t.to_homogeneous(), t2.to_homogeneous(), epsilon = 1e-9);
        }
    }

    #[test]
    fn exp_matches_the_matrix_exponential_series() {
        // Sum the series of the 4x4 twist matrix directly.
        for xi in twists() {
            let mut m = nalgebra::Matrix4::<f64>::zeros();
            let w = Vector3::new(xi[3], xi[4], xi[5]);
            m.fixed_view_mut::<3, 3>(0, 0).copy_from(&hat(&w));
            m[(0, 3)] = xi[0];
            m[(1, 3)] = xi[1];
            m[(2, 3)] = xi[2];
            let mut term = nalgebra::Matrix4::<f64>::identity();
            let mut sum = term;
            for k in 1..60 {
                term = term * m / k as f64;
                sum += term;
            }
            assert_relative_eq!(exp(&xi).to_homogeneous(), sum, epsilon = 1e-9);
        }
    }

    #[test]
    fn derivative_of_exp_at_zero_is_the_generator() {
        // d/dε exp(ε ξ) p |ε=0 = v + ω × p.
        let p = Vector3::new(0.3, -0.7, 1.9);
        let xi = Twist::new(0.2, -0.1, 0.4, 0.3, 0.5, -0.2);
        let h = 1e-6;
        let fd = (exp(&(xi * h)).transform_vector(&p) + exp(&(xi * h)).translation.vector
            - (exp(&(xi * -h)).transform_vector(&p) + exp(&(xi * -h)).translation.vector))
            / (2.0 * h);
        let v = Vector3::new(xi[0], xi[1], xi[2]);
        let w = Vector3::new(xi[3], xi[4], xi[5]);
        assert_relative_eq!(fd, v + w.cross(&p), epsilon = 1e-8);
    }

    #[test]
    fn compose_keeps_rotations_unit_through_long_chains() {
        let step = exp(&Twist::new(0.01, -0.02, 0.005, 0.013, -0.007, 0.021));
        let mut reference = Isometry3::identity();
        let mut pose = Isometry3::identity();
        for i in 0..5000 {
            pose = compose(&pose, &step);
            if i % 7 == 0 {
                let accumulated = compose(&reference.inverse(), &pose);
                pose = compose(&reference, &accumulated);
                reference = pose;
            }
        }
        assert!((pose.rotation.quaternion().norm() - 1.0).abs() < 1e-12);
        let r = pose.rotation.to_rotation_matrix();
        assert_relative_eq!(
            r.matrix() * r.matrix().transpose(),
            Matrix3::identity(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn angle_from_trace() {
        let t = exp(&Twist::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.25));
        assert_relative_eq!(angle(&t), 0.25, epsilon = 1e-12);
        assert_eq!(angle(&Isometry3::identity()), 0.0);
    }
}
