//! Property tests (proptest) of the Umeyama/Horn rigid alignment behind the ATE.

use ecvo_io::Pose;
use ecvo_io::eval::align_rigid;
use nalgebra::{Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;

fn rigid() -> impl Strategy<Value = Pose> {
    (
        prop::array::uniform3(-10.0f64..10.0),
        prop::array::uniform3(-1.0f64..1.0),
        0.0f64..std::f64::consts::PI,
    )
        .prop_filter_map("axis", |(t, axis, angle)| {
            let a = Vector3::from(axis);
            (a.norm() > 1e-3).then(|| {
                Pose::from_parts(
                    Translation3::new(t[0], t[1], t[2]),
                    UnitQuaternion::from_scaled_axis(a.normalize() * angle),
                )
            })
        })
}

/// Points spread in all three directions (not collinear), so the alignment is unique.
fn cloud() -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec(prop::array::uniform3(-5.0f64..5.0), 4..60).prop_filter(
        "spread in 3-D",
        |pts| {
            let v: Vec<Vector3<f64>> = pts.iter().map(|p| Vector3::from(*p)).collect();
            let mu = v.iter().sum::<Vector3<f64>>() / v.len() as f64;
            let mut c = nalgebra::Matrix3::zeros();
            for p in &v {
                c += (p - mu) * (p - mu).transpose();
            }
            let s = (c / v.len() as f64).symmetric_eigenvalues();
            s.min() > 0.05
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn recovers_a_rigid_motion(t in rigid(), pts in cloud()) {
        let src: Vec<Vector3<f64>> = pts.iter().map(|p| Vector3::from(*p)).collect();
        let dst: Vec<Vector3<f64>> = src.iter().map(|p| t * nalgebra::Point3::from(*p)).map(|p| p.coords).collect();
        let est = align_rigid(&src, &dst).expect("aligns");
        prop_assert!((est.translation.vector - t.translation.vector).norm() < 1e-8, "{est:?} vs {t:?}");
        prop_assert!(est.rotation.angle_to(&t.rotation) < 1e-8);
        // A rotation, never a reflection.
        prop_assert!((est.rotation.to_rotation_matrix().matrix().determinant() - 1.0).abs() < 1e-9);
        // Aligning back gives the inverse.
        let back = align_rigid(&dst, &src).expect("aligns");
        prop_assert!((back * est).translation.vector.norm() < 1e-7);
    }

    #[test]
    fn noise_does_not_move_it_far(t in rigid(), pts in cloud(), seed in any::<u64>()) {
        // Bounded noise of 1 mm on every coordinate moves the estimate by little.
        let src: Vec<Vector3<f64>> = pts.iter().map(|p| Vector3::from(*p)).collect();
        let mut s = seed | 1;
        let mut noise = || {
            s ^= s << 13; s ^= s >> 7; s ^= s << 17;
            (s % 2001) as f64 / 1000.0 - 1.0
        };
        let dst: Vec<Vector3<f64>> = src
            .iter()
            .map(|p| (t * nalgebra::Point3::from(*p)).coords + Vector3::new(noise(), noise(), noise()) * 1e-3)
            .collect();
        let est = align_rigid(&src, &dst).expect("aligns");
        let rms = (src.iter().zip(&dst).map(|(s, d)| ((est * nalgebra::Point3::from(*s)).coords - d).norm_squared()).sum::<f64>() / src.len() as f64).sqrt();
        // Least squares: no worse than the true motion, whose residual is the noise.
        prop_assert!(rms <= 1.8e-3, "{rms}");
        prop_assert!(est.rotation.angle_to(&t.rotation) < 0.01);
    }

    #[test]
    fn bad_input_is_an_error(n in 0usize..3, m in 3usize..6) {
        let p = vec![Vector3::new(1.0, 2.0, 3.0); n];
        prop_assert!(align_rigid(&p, &p).is_err());
        let a = vec![Vector3::new(1.0, 0.0, 0.0); m];
        prop_assert!(align_rigid(&a, &a[1..]).is_err());
        let mut b = vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 0.0, 1.0)];
        b[1].y = f64::NAN;
        prop_assert!(align_rigid(&b, &b).is_err());
    }
}
