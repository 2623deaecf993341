//! ATE and RPE: hand-checked cases and a cross-check against evo.

use std::path::PathBuf;

use ecvo_io::eval::{align_rigid, associate, ate, rpe, rpe_per_frame};
use ecvo_io::{Error, Pose, Trajectory};
use nalgebra::{Translation3, UnitQuaternion, Vector3};

fn corners() -> Vec<Vector3<f64>> {
    let mut v = Vec::new();
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                v.push(Vector3::new(sx * 1.0, sy * 2.0, sz * 3.0));
            }
        }
    }
    v
}

fn traj(stamps: &[f64], pos: &[Vector3<f64>]) -> Trajectory {
    let mut t = Trajectory::new();
    for (s, p) in stamps.iter().zip(pos) {
        t.push(
            *s,
            Pose::from_parts(Translation3::from(*p), UnitQuaternion::identity()),
        );
    }
    t
}

#[test]
fn ate_hand_checked() {
    // Ground truth: the corners (±1, ±2, ±3) of a box. Estimate: each corner moved by
    // o = (0.03 p + 0.01 q) along x, with p = sx*sy*sz and q = sx*sy, then expressed
    // in a frame rotated and shifted by T. Both p and q sum to zero and are
    // uncorrelated with every coordinate, so the best alignment is exactly T^-1 and the
    // errors are |o| = 0.04 (p = q) or 0.02 (p = -q), four of each:
    // RMSE = sqrt((0.04^2 + 0.02^2) / 2) = sqrt(0.001), mean = median = 0.03.
    let g = corners();
    let t = Pose::new(Vector3::new(0.4, -2.0, 1.5), Vector3::new(0.3, -0.5, 0.8));
    let est_pos: Vec<Vector3<f64>> = g
        .iter()
        .map(|c| {
            let (p, q) = (
                c.x.signum() * c.y.signum() * c.z.signum(),
                c.x.signum() * c.y.signum(),
            );
            let moved = c + Vector3::new(0.03 * p + 0.01 * q, 0.0, 0.0);
            t.inverse_transform_vector(&(moved - t.translation.vector))
        })
        .collect();
    let stamps: Vec<f64> = (0..8).map(|k| 100.0 + 0.1 * k as f64).collect();
    let r = ate(&traj(&stamps, &g), &traj(&stamps, &est_pos)).unwrap();
    assert_eq!(r.count, 8);
    assert!((r.rmse - 0.001f64.sqrt()).abs() < 1e-12, "{}", r.rmse);
    assert!((r.mean - 0.03).abs() < 1e-12);
    assert!((r.median - 0.03).abs() < 1e-12);
    assert!((r.max - 0.04).abs() < 1e-12 && (r.min - 0.02).abs() < 1e-12);
    assert!((r.std - 0.01).abs() < 1e-12);
    assert!(r.alignment.rotation.angle_to(&t.rotation) < 1e-12);
    assert!((r.alignment.translation.vector - t.translation.vector).norm() < 1e-12);
    assert_eq!(r.errors.len(), 8);
    assert_eq!(r.pairs, (0..8).map(|k| (k, k)).collect::<Vec<_>>());
    // The aligned estimate lies on the moved corners.
    let est = traj(&stamps, &est_pos);
    let aligned = r.aligned(&est);
    assert!((aligned.poses[0].translation.vector - g[0]).norm() < 0.05);
}

#[test]
fn ate_never_aligns_with_a_reflection() {
    // The estimate is the ground truth mirrored in z. A reflection would fit it
    // exactly; the best rotation (180 deg about y, flipping the axis with the smallest
    // spread, x) leaves every corner 2|x| = 2 m away.
    let g = corners();
    let mirrored: Vec<Vector3<f64>> = g.iter().map(|c| Vector3::new(c.x, c.y, -c.z)).collect();
    let stamps: Vec<f64> = (0..8).map(|k| k as f64).collect();
    let r = ate(&traj(&stamps, &g), &traj(&stamps, &mirrored)).unwrap();
    assert!((r.rmse - 2.0).abs() < 1e-9, "{}", r.rmse);
    assert!(r.errors.iter().all(|e| (e - 2.0).abs() < 1e-9));
    let want = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
    assert!(r.alignment.rotation.angle_to(&want) < 1e-9);
    assert!(
        r.alignment
            .rotation
            .to_rotation_matrix()
            .matrix()
            .determinant()
            > 0.999
    );

    // align_rigid directly: identity for identical point sets.
    let a = align_rigid(&g, &g).unwrap();
    assert!(a.rotation.angle() < 1e-12 && a.translation.vector.norm() < 1e-12);
}

#[test]
fn too_few_pairs_is_an_error() {
    let g = corners();
    let gt = traj(&[0.0, 1.0, 2.0, 3.0], &g[..4]);
    // Only 2 stamps within 0.02 s.
    let est = traj(&[0.005, 1.5, 2.01, 3.5], &g[..4]);
    let e = ate(&gt, &est).unwrap_err();
    assert!(
        matches!(
            e,
            Error::TooFewPairs {
                found: 2,
                needed: 3
            }
        ),
        "{e}"
    );
    assert!(matches!(
        ate(&gt, &Trajectory::new()),
        Err(Error::TooFewPairs { found: 0, .. })
    ));
    assert!(matches!(
        rpe(&gt, &Trajectory::new(), 1.0),
        Err(Error::TooFewPairs { .. })
    ));
    assert!(matches!(
        rpe_per_frame(&gt, &est),
        Err(Error::TooFewPairs { .. })
    ));
}

/// Smooth test motion: position and orientation at time `t`.
fn motion(t: f64) -> Pose {
    Pose::new(
        Vector3::new(t.sin(), 0.5 * t, (0.7 * t).cos()),
        Vector3::new(0.1 * t, 0.2 * (0.5 * t).sin(), 0.05),
    )
}

#[test]
fn ate_with_inexact_timestamps() {
    // Ground truth at 100 Hz, estimate at 30 Hz 4 ms late, plus frames outside the
    // ground truth's time span and one beyond 0.02 s of any ground truth stamp.
    let mut gt = Trajectory::new();
    for k in 0..=500 {
        let t = 50.0 + k as f64 * 0.01;
        gt.push(t, motion(t));
    }
    let mut est = Trajectory::new();
    let offset = Pose::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.0, 0.4, 0.0));
    est.push(49.0, Pose::identity()); // before the ground truth: unmatched
    for k in 0..50 {
        let gk = 3 * k;
        let t_gt = gt.stamps[gk];
        est.push(t_gt + 0.004, offset * gt.poses[gk]);
    }
    est.push(60.0, Pose::identity()); // after: unmatched
    let pairs = associate(&gt, &est, 0.02);
    assert_eq!(pairs.len(), 50);
    assert!(
        pairs
            .iter()
            .enumerate()
            .all(|(k, &(g, e))| g == 3 * k && e == k + 1)
    );
    let r = ate(&gt, &est).unwrap();
    assert_eq!(r.count, 50);
    assert!(r.rmse < 1e-9 && r.max < 1e-9, "{}", r.rmse);
    assert!((r.alignment * offset).translation.vector.norm() < 1e-9);
}

#[test]
fn rpe_hand_checked() {
    // Ground truth: 1 m/s along x, at 100 Hz for 5 s. Estimate at 50 Hz (stamps on
    // the ground-truth grid): 1.1 m/s along x while turning about x at 10 deg/s.
    // For pairs 1 s apart the error is (R_x(10°) | 1.1 m)^-1 (I | 1 m): 0.1 m, 10°.
    let w = 10f64.to_radians();
    let mut gt = Trajectory::new();
    for k in 0..=500 {
        let t = 1000.0 + k as f64 * 0.01;
        gt.push(t, Pose::translation(k as f64 * 0.01, 0.0, 0.0));
    }
    let mut est = Trajectory::new();
    for k in 0..=250 {
        let dt = k as f64 * 0.02;
        est.push(
            1000.0 + dt,
            Pose::new(
                Vector3::new(1.1 * dt, 0.0, 0.0),
                Vector3::new(w * dt, 0.0, 0.0),
            ),
        );
    }
    let r = rpe(&gt, &est, 1.0).unwrap();
    // Pairs (i, i + 50) for i = 0..200; i = 200 reaches the last pose and is skipped
    // (as TUM's evaluate_rpe does), later ones map to it too.
    assert_eq!(r.trans.count, 200);
    assert_eq!(r.pairs[0], (0, 50));
    assert!((r.trans.rmse - 0.1).abs() < 1e-9, "{}", r.trans.rmse);
    assert!((r.rot_deg.rmse - 10.0).abs() < 1e-9, "{}", r.rot_deg.rmse);
    assert!((r.trans.max - 0.1).abs() < 1e-9);

    let f = rpe_per_frame(&gt, &est).unwrap();
    assert_eq!(f.trans.count, 250);
    assert!((f.trans.rmse - 0.002).abs() < 1e-9, "{}", f.trans.rmse);
    assert!((f.rot_deg.rmse - 0.2).abs() < 1e-9, "{}", f.rot_deg.rmse);

    // A perfect estimate, in another world frame, has no relative error.
    let offset = Pose::new(Vector3::new(1.0, -1.0, 0.5), Vector3::new(0.3, 0.2, 0.1));
    let same = Trajectory {
        stamps: gt.stamps.iter().map(|t| t + 0.003).collect(),
        poses: gt.poses.iter().map(|p| offset * p).collect(),
    };
    let r = rpe(&gt, &same, 1.0).unwrap();
    assert!(r.trans.max < 1e-9 && r.rot_deg.max < 1e-6);
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

#[test]
fn ate_agrees_with_evo() {
    // `evo_ape tum fr1_xyz_gt_25hz.txt fr1_xyz_est_perturbed.txt -a --t_max_diff 0.02`
    // (evo 1.38.1), see tests/data/README.md.
    let gt = Trajectory::read_tum(data("fr1_xyz_gt_25hz.txt")).unwrap();
    let est = Trajectory::read_tum(data("fr1_xyz_est_perturbed.txt")).unwrap();
    assert_eq!((gt.len(), est.len()), (298, 128));
    let r = ate(&gt, &est).unwrap();
    assert_eq!(r.count, 127);
    let evo = [
        ("rmse", r.rmse, 0.01558863203962041),
        ("mean", r.mean, 0.014036797568337847),
        ("median", r.median, 0.012811975070597064),
        ("std", r.std, 0.0067803954819895765),
        ("min", r.min, 0.00280125172243647),
        ("max", r.max, 0.03235412257402522),
    ];
    for (name, ours, theirs) in evo {
        assert!(
            (ours - theirs).abs() < 1e-9,
            "{name}: ours {ours}, evo {theirs}"
        );
    }
}

#[test]
fn tum_files_round_trip() {
    let gt = Trajectory::read_tum(data("fr1_xyz_gt_25hz.txt")).unwrap();
    let p = std::env::temp_dir().join(format!("ecvo-io-traj-{}.txt", std::process::id()));
    gt.write_tum(&p).unwrap();
    let back = Trajectory::read_tum(&p).unwrap();
    let _ = std::fs::remove_file(&p);
    assert_eq!(back, gt);
    let e = Trajectory::read_tum(data("no_such_file.txt")).unwrap_err();
    assert!(e.to_string().contains("no_such_file.txt"), "{e}");
}
