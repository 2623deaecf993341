//! The gyroscope through the command line (issue 47): `ecvo synth` writes a simulated
//! `imu.txt` and its calibration, `ecvo run` uses it (or not, `--no-imu`) and says
//! so, and `ecvo imu-from-groundtruth` writes one for a sequence with ground truth,
//! never inside it.

use crate::common;

use common::{run, run_ok, summary, temp_dir};

#[test]
fn a_pan_with_a_gyro_is_written_tracked_and_reported() {
    let dir = temp_dir("synth-imu");
    let seq = dir.join("pan");
    let s = seq.to_str().unwrap();
    run_ok(&[
        "synth", "--out", s, "--frames", "12", "--seed", "2", "--motion", "pan",
    ]);
    let text = std::fs::read_to_string(seq.join("imu.txt")).unwrap();
    assert!(text.starts_with("# SIMULATED IMU"), "{}", &text[..80]);
    let cam: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(seq.join("camera.json")).unwrap()).unwrap();
    let offset = cam["imu"]["time_offset"].as_f64().unwrap();
    assert!((0.005..=0.020).contains(&offset.abs()), "{offset}");

    let with = dir.join("with");
    let out = run_ok(&["run", s, "--out", with.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("11 frames with a gyro prior"));
    let imu = &summary(&with)["imu"];
    assert_eq!(imu["priors"].as_u64(), Some(11), "{imu}");
    assert_eq!(imu["late"].as_u64(), Some(0));
    let without = dir.join("without");
    run_ok(&["run", s, "--no-imu", "--out", without.to_str().unwrap()]);
    assert!(summary(&without).get("imu").is_none());

    // The ground truth's IMU, written beside, never inside, the sequence.
    let inside = seq.join("imu-here");
    let e = run(&["imu-from-groundtruth", s, "--out", inside.to_str().unwrap()]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("inside the sequence folder"));
    assert!(!inside.exists());
    let gt_imu = dir.join("gt-imu");
    run_ok(&["imu-from-groundtruth", s, "--out", gt_imu.to_str().unwrap()]);
    let by_gt = dir.join("by-gt");
    let imu_txt = gt_imu.join("imu.txt");
    run_ok(&[
        "run",
        s,
        "--imu",
        imu_txt.to_str().unwrap(),
        "--out",
        by_gt.to_str().unwrap(),
    ]);
    let imu = &summary(&by_gt)["imu"];
    assert_eq!(imu["priors"].as_u64(), Some(11), "{imu}");
    assert!(
        imu["calibration_from"].as_str().unwrap().contains("gt-imu"),
        "{imu}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `ecvo synth --depth-delay-ms` stamps each depth image that much after its
/// intensity (a delay the readers cannot pair, 20 ms or more, is refused); `ecvo
/// run` turns every frame's depth to its intensity's time with the gyro, counts it,
/// and tracks closer to the ground truth than with `--imu-depth-time false`.
#[test]
fn depth_taken_after_the_intensity_is_turned_with_the_gyro() {
    let dir = temp_dir("synth-depth-delay");
    let seq = dir.join("pan");
    let s = seq.to_str().unwrap();
    let e = run(&["synth", "--out", s, "--depth-delay-ms", "20"]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("--depth-delay-ms"));
    run_ok(&[
        "synth",
        "--out",
        s,
        "--frames",
        "40",
        "--seed",
        "3",
        "--motion",
        "pan",
        "--max-rot-speed",
        "200",
        "--depth-delay-ms",
        "15",
    ]);
    let list = |f: &str| -> Vec<f64> {
        std::fs::read_to_string(seq.join(f))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| l.split_whitespace().next().unwrap().parse().unwrap())
            .collect()
    };
    let (rgb, depth) = (list("rgb.txt"), list("depth.txt"));
    assert_eq!(rgb.len(), 40);
    for (r, d) in rgb.iter().zip(&depth) {
        assert!((d - r - 0.015).abs() < 2e-6, "{r} {d}");
    }
    let ate = |flags: &[&str]| {
        let out = dir.join("out");
        let mut args = vec!["run", s, "--out", out.to_str().unwrap()];
        args.extend_from_slice(flags);
        run_ok(&args);
        let sm = summary(&out);
        (
            sm["ate_rmse_m"].as_f64().unwrap(),
            sm["imu"]["depth_turned"].as_u64().unwrap(),
        )
    };
    let (turned, n) = ate(&[]);
    let (as_is, m) = ate(&["--imu-depth-time", "false"]);
    eprintln!("ATE {turned:.5} m turned ({n} frames), {as_is:.5} m as is");
    assert_eq!((n, m), (40, 0));
    assert!(turned < as_is, "ATE {turned} m turned, {as_is} m as is");
    let _ = std::fs::remove_dir_all(&dir);
}
