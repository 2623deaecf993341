//! `ecvo synth --motion orbit --noise tof`: the stream holds the poses of
//! `SynthSequence::orbit_320x180`, millimetre depth at both sizes, and `ecvo run`
//! tracks it.

use crate::common;

use common::{data_lines, run_ok, summary, temp_dir};
use ecvo_synth::SynthSequence;

fn camera(seq: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(seq.join("camera.json")).unwrap()).unwrap()
}

#[test]
fn a_tof_orbit_is_written_and_tracked() {
    // Measured (seed 3, 2.5 m, 45 deg/s, 90 frames): 0.7 mm ATE, 0 lost; bounded
    // loosely at 1 cm and 2 lost frames.
    let dir = temp_dir("synth-orbit-tof");
    let seq = dir.join("seq");
    let s = seq.to_str().unwrap();
    let stdout = run_ok(&[
        "synth",
        "--out",
        s,
        "--frames",
        "90",
        "--seed",
        "3",
        "--noise",
        "tof",
        "--motion",
        "orbit",
        "--depth",
        "2.5",
        "--max-rot-speed",
        "45",
    ])
    .stdout;
    assert!(String::from_utf8_lossy(&stdout).contains("noise Tof, motion Orbit"));
    assert_eq!(camera(&seq)["depth_scale"].as_f64(), Some(1000.0));
    let expected = SynthSequence::orbit_320x180(90, 3, 2.5, 45f64.to_radians());
    let gt = data_lines(&seq.join("groundtruth.txt"));
    assert_eq!(gt.len(), 90);
    for (i, line) in gt.iter().enumerate() {
        let f: Vec<f64> = line
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let t = expected.pose(i).translation.vector;
        let d = ((f[1] - t.x).powi(2) + (f[2] - t.y).powi(2) + (f[3] - t.z).powi(2)).sqrt();
        assert!(d < 1e-6, "frame {i}: {d} m from the orbit");
    }
    let out = dir.join("out");
    run_ok(&["run", s, "--out", out.to_str().unwrap(), "--threads", "1"]);
    let summary = summary(&out);
    let lost = summary["lost_frames"].as_u64().unwrap();
    let ate = summary["ate_rmse_m"].as_f64().unwrap();
    assert!(lost <= 2, "{lost} lost: {summary}");
    assert!(ate < 0.01, "ATE {ate} m on the ToF orbit");
}

#[test]
fn tof_depth_is_in_millimetres_at_640x480_too() {
    let dir = temp_dir("synth-orbit-640");
    let seq = dir.join("seq");
    let s = seq.to_str().unwrap();
    run_ok(&[
        "synth", "--out", s, "--frames", "2", "--noise", "tof", "--motion", "orbit", "--size",
        "640x480",
    ]);
    let c = camera(&seq);
    assert_eq!(c["width"].as_u64(), Some(640), "{c}");
    assert_eq!(c["depth_scale"].as_f64(), Some(1000.0), "{c}");
    // The Kinect model keeps the Kinect's 1/5000 m.
    let kinect = dir.join("kinect");
    run_ok(&[
        "synth",
        "--out",
        kinect.to_str().unwrap(),
        "--frames",
        "2",
        "--noise",
        "kinect",
        "--motion",
        "orbit",
        "--size",
        "640x480",
    ]);
    assert_eq!(camera(&kinect)["depth_scale"].as_f64(), Some(5000.0));
}
