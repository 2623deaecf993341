//! Property tests (proptest) of SE(3) `exp`/`log`/`compose` and of `comp()`.

use ecvo_core::nalgebra::{Translation3, UnitQuaternion, Vector3};
use ecvo_core::se3::{self, Twist};
use ecvo_core::{Pose, ReferenceLevel, comp};
use proptest::prelude::*;

/// A twist whose rotation angle is below `max_angle` (radians).
fn twist(max_t: f64, max_angle: f64) -> impl Strategy<Value = Twist> {
    (
        prop::array::uniform3(-max_t..max_t),
        prop::array::uniform3(-1.0f64..1.0),
        0.0..max_angle,
    )
        .prop_map(|(v, axis, angle)| {
            let a = Vector3::from(axis);
            let w = if a.norm() < 1e-9 {
                Vector3::zeros()
            } else {
                a.normalize() * angle
            };
            Twist::new(v[0], v[1], v[2], w.x, w.y, w.z)
        })
}

fn pose(max_t: f64) -> impl Strategy<Value = Pose> {
    twist(max_t, 3.0).prop_map(|xi| se3::exp(&xi))
}

fn close(a: &Pose, b: &Pose, tol: f64) -> bool {
    (a.translation.vector - b.translation.vector).norm() <= tol
        && a.rotation.angle_to(&b.rotation) <= tol
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn log_inverts_exp(xi in twist(10.0, 3.1)) {
        let back = se3::log(&se3::exp(&xi));
        prop_assert!((back - xi).norm() <= 1e-9 * (1.0 + xi.norm()), "{xi:?} -> {back:?}");
    }

    #[test]
    fn exp_inverts_log(t in pose(10.0)) {
        let back = se3::exp(&se3::log(&t));
        prop_assert!(close(&back, &t, 1e-9), "{t:?} -> {back:?}");
    }

    #[test]
    fn small_twists_are_exact(xi in twist(1e-3, 1e-6)) {
        // The Taylor branches near zero must join the closed form smoothly.
        let back = se3::log(&se3::exp(&xi));
        prop_assert!((back - xi).norm() <= 1e-15 + 1e-9 * xi.norm());
        prop_assert!((se3::angle(&se3::exp(&xi)) - xi.fixed_rows::<3>(3).norm()).abs() <= 1e-7);
    }

    #[test]
    fn angle_is_the_twist_angle(xi in twist(1.0, 3.1)) {
        let w = xi.fixed_rows::<3>(3).norm();
        prop_assert!((se3::angle(&se3::exp(&xi)) - w).abs() <= 1e-6, "{w}");
    }

    #[test]
    fn exp_of_opposite_is_inverse(xi in twist(5.0, 3.1)) {
        let t = se3::compose(&se3::exp(&xi), &se3::exp(&-xi));
        prop_assert!(close(&t, &Pose::identity(), 1e-9));
    }

    #[test]
    fn compose_matches_the_product_and_is_associative(a in pose(5.0), b in pose(5.0), c in pose(5.0)) {
        prop_assert!(close(&se3::compose(&a, &b), &(a * b), 1e-12));
        let left = se3::compose(&se3::compose(&a, &b), &c);
        let right = se3::compose(&a, &se3::compose(&b, &c));
        prop_assert!(close(&left, &right, 1e-9));
        prop_assert!(close(&se3::compose(&a, &a.inverse()), &Pose::identity(), 1e-9));
        // Translation of a composition = a's rotation applied to b's, plus a's.
        let ab = se3::compose(&a, &b);
        let t = a.rotation * b.translation.vector + a.translation.vector;
        prop_assert!((ab.translation.vector - t).norm() <= 1e-9);
    }

    #[test]
    fn long_chains_stay_unit(steps in prop::collection::vec(twist(0.05, 0.2), 200..400)) {
        // A reference chain: pose = pose * inverse(prev) * next, many times over.
        let mut p = Pose::identity();
        for xi in &steps {
            let s = se3::exp(xi);
            p = se3::compose(&se3::compose(&p, &s.inverse()), &se3::compose(&s, &s));
            prop_assert!((p.rotation.quaternion().norm() - 1.0).abs() <= 1e-12);
            prop_assert!(se3::is_finite(&p));
        }
    }

    #[test]
    fn comp_is_the_paper_rule(
        t in prop::array::uniform3(-0.3f64..0.3),
        axis in prop::array::uniform3(-1.0f64..1.0),
        angle_deg in 0.0f64..60.0,
        d_mm in 0.0f64..300.0,
        a_deg in 0.1f64..60.0,
    ) {
        let a = Vector3::from(axis);
        prop_assume!(a.norm() > 1e-3);
        let rot = UnitQuaternion::from_scaled_axis(a.normalize() * angle_deg.to_radians());
        let pose = Pose::from_parts(Translation3::new(t[0], t[1], t[2]), rot);
        let level = ReferenceLevel::mm_deg(d_mm, a_deg);
        let dist = Vector3::from(t).norm();
        // Away from the boundaries (rounding in the trace), comp is exactly
        // "translation above εd or rotation above εa".
        prop_assume!((dist - d_mm / 1000.0).abs() > 1e-9 && (angle_deg - a_deg).abs() > 1e-6);
        let expected = dist > d_mm / 1000.0 || angle_deg > a_deg;
        prop_assert_eq!(comp(&pose, &level), expected);
        // The same for the inverse motion (same distance, same angle).
        prop_assert_eq!(comp(&pose.inverse(), &level), expected);
        // Monotone in the thresholds: looser thresholds never fire where tighter don't.
        let looser = ReferenceLevel::mm_deg(d_mm * 2.0, (a_deg * 2.0).min(179.0));
        prop_assert!(!comp(&pose, &looser) || expected);
        // The identity never needs a correction; a motion past both always does.
        prop_assert!(!comp(&Pose::identity(), &level));
    }
}
