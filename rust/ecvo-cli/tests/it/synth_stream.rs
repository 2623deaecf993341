//! `ecvo run` on the synthetic stream in `testdata/` (60 frames, 320x180, phone-like
//! noise, exact ground truth), and the files it writes.

use crate::common;

use std::path::Path;

use common::{check_counters, data_lines, run_ok, summary, temp_dir, testdata_stream};

const FRAMES: u64 = 60;

/// Runs `ecvo run` on the test stream with `extra` flags into a fresh folder.
fn track(name: &str, extra: &[&str]) -> (std::path::PathBuf, serde_json::Value, String) {
    let out = temp_dir(name);
    let seq = testdata_stream();
    let mut args = vec!["run", seq.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = run_ok(&args);
    let stdout = String::from_utf8(o.stdout).unwrap();
    let s = summary(&out);
    (out, s, stdout)
}

// Measured on the testdata stream (engine of 2025-11, pc preset): naive 0.0012 m,
// L1 0.0004 m, L2 0.0004 m. The bounds leave room for engine changes.
const NAIVE_ATE_BOUND_M: f64 = 0.005;
const L2_ATE_BOUND_M: f64 = 0.002;

#[test]
fn naive_tracks_the_stream() {
    let (out, s, stdout) = track("naive", &["--mode", "naive"]);
    let ate = s["ate_rmse_m"].as_f64().expect("ATE with ground truth");
    assert!(ate < NAIVE_ATE_BOUND_M, "naive ATE {ate} m");
    assert!(stdout.contains("ATE RMSE"), "{stdout}");
    check_counters(&s, FRAMES, 0);
    assert_eq!(s["motion_estimations"].as_u64(), Some(FRAMES - 1));
    assert_eq!(s["mode"], "naive");
    // Naive: no reference frames, the cloud takes every 15th frame (0, 15, 30, 45).
    assert!(data_lines(&out.join("references.txt")).is_empty());
    assert_eq!(s["cloud"]["frames"].as_u64(), Some(4), "{s}");
    assert_eq!(s["cloud"]["every_nth_frame"].as_u64(), Some(15), "{s}");
    check_files(&out, &s);
}

#[test]
fn l2_tracks_the_stream_and_writes_every_file() {
    let (out, s, stdout) = track("l2", &[]);
    let ate = s["ate_rmse_m"].as_f64().expect("ATE with ground truth");
    assert!(ate < L2_ATE_BOUND_M, "L2 ATE {ate} m");
    assert!(stdout.contains("ATE RMSE"), "{stdout}");
    check_counters(&s, FRAMES, 2);
    let refs = s["references"].as_array().unwrap();
    assert!(
        refs[0].as_u64().unwrap() > 0,
        "the stream moves enough for L1: {s}"
    );
    assert_eq!(s["mode"], "l2");
    assert_eq!(s["preset"], "pc");
    assert_eq!(s["levels_text"], "30mm:7deg,120mm:12deg");
    check_files(&out, &s);
}

#[test]
fn l1_levels_override_and_filter_flags() {
    let (out, s, _) = track(
        "l1",
        &[
            "--mode",
            "l1",
            "--levels",
            "20mm:5deg",
            "--no-bilateral",
            "--no-contour-filter",
            "--max-frames",
            "45",
            "--threads",
            "3",
        ],
    );
    check_counters(&s, 45, 1);
    assert_eq!(s["levels"][0]["max_distance_m"].as_f64(), Some(0.02));
    assert_eq!(s["levels"][0]["max_angle_deg"].as_f64(), Some(5.0));
    assert_eq!(s["filters"]["bilateral"], false);
    assert!(s["filters"]["contour_angle_deg"].is_null());
    assert_eq!(s["filters"]["normal_max_angle_deg"].as_f64(), Some(28.0));
    assert_eq!(s["threads"].as_u64(), Some(3));
    let simd = s["simd"].as_str().unwrap_or_default();
    let paths: &[&str] = if cfg!(target_arch = "x86_64") {
        &["sse2", "avx2", "avx512"]
    } else if cfg!(target_arch = "aarch64") {
        &["neon"]
    } else {
        &["portable"]
    };
    assert!(paths.contains(&simd), "simd {simd:?}: {s}");
    assert!(s["ate_rmse_m"].as_f64().unwrap() < L2_ATE_BOUND_M, "{s}");
    check_files(&out, &s);
}

#[test]
fn no_bilateral_with_the_phone_contour_filter_warns_and_loses_the_stream() {
    // Documented pitfall: with the phone preset (contour angle 20°) the contour test,
    // fed raw phone-noise depth, removes nearly every pixel, so every frame after the
    // first is lost; the CLI says so before tracking. The pc preset's 7° tracks
    // without the bilateral filter (the test above, and `--no-bilateral` alone).
    let out = temp_dir("no-bilateral");
    let seq = testdata_stream();
    let o = run_ok(&[
        "run",
        seq.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-bilateral",
        "--preset",
        "phone",
        "--max-frames",
        "10",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("--no-contour-filter"), "{stderr}");
    let s = summary(&out);
    assert_eq!(s["lost_frames"].as_u64(), Some(9), "{s}");
}

/// The pipeline is deterministic: one and two compute threads give the same bytes
/// in every output but the timings (and the same as the default, two).
#[test]
fn one_and_two_threads_give_identical_outputs() {
    let (one, s1, _) = track("threads-1", &["--threads", "1"]);
    let (two, s2, _) = track("threads-2", &["--threads", "2"]);
    assert_eq!(s1["threads"].as_u64(), Some(1), "{s1}");
    assert_eq!(s2["threads"].as_u64(), Some(2), "{s2}");
    for file in ["trajectory.txt", "references.txt", "cloud.ply"] {
        let a = std::fs::read(one.join(file)).unwrap();
        let b = std::fs::read(two.join(file)).unwrap();
        assert!(!a.is_empty(), "{file} is empty");
        assert!(a == b, "{file} differs between --threads 1 and --threads 2");
    }
    for key in [
        "frames",
        "motion_estimations",
        "references",
        "ate_rmse_m",
        "cloud",
    ] {
        assert_eq!(s1[key], s2[key], "{key}");
    }
    for s in [&s1, &s2] {
        assert_eq!(s["dropped_frames"].as_u64(), Some(0), "{s}");
    }
}

#[test]
fn phone_preset_and_camera_override() {
    // The stream's own camera.json given with --camera gives the same result.
    let cam = testdata_stream().join("camera.json");
    let (_, s, _) = track(
        "phone",
        &[
            "--preset",
            "phone",
            "--camera",
            cam.to_str().unwrap(),
            "--max-frames",
            "30",
        ],
    );
    check_counters(&s, 30, 2);
    assert_eq!(s["preset"], "phone");
    assert_eq!(s["levels_text"], "30mm:3deg,70mm:7deg");
    assert_eq!(s["camera"]["fx"].as_f64(), Some(250.0));
    assert!(s["camera_file"].as_str().unwrap().ends_with("camera.json"));
    assert!(s["ate_rmse_m"].as_f64().unwrap() < L2_ATE_BOUND_M, "{s}");
}

#[test]
fn eval_of_the_written_trajectory_agrees_with_the_summary() {
    let (out, s, _) = track("eval", &["--max-frames", "40"]);
    let gt = testdata_stream().join("groundtruth.txt");
    let est = out.join("trajectory.txt");
    let o = run_ok(&[
        "eval",
        gt.to_str().unwrap(),
        est.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("eval --json is JSON");
    let a = v["ate_rmse_m"].as_f64().unwrap();
    let b = s["ate_rmse_m"].as_f64().unwrap();
    // The trajectory is written with round-trip precision.
    assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    assert!(v["rpe"]["per_frame"]["trans_m"].as_f64().is_some(), "{v}");
    assert!(v["rpe"]["trans_m_per_s"].as_f64().is_some(), "{v}");
    let o = run_ok(&["eval", gt.to_str().unwrap(), est.to_str().unwrap()]);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("ATE RMSE") && text.contains("RPE"), "{text}");
    // The ground truth against itself: zero error.
    let o = run_ok(&["eval", gt.to_str().unwrap(), gt.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["ate_rmse_m"].as_f64().unwrap() < 1e-9, "{v}");
}

#[test]
fn table_prints_the_three_rows_per_frame_step() {
    let seq = testdata_stream();
    let json = temp_dir("table_rows").join("rows.jsonl");
    let o = run_ok(&[
        "table",
        seq.to_str().unwrap(),
        "--max-frames",
        "20",
        "--frame-steps",
        "1,2",
        "--json",
        json.to_str().unwrap(),
    ]);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains(
            "| frame step | frames | method | ATE RMSE (m) | motion estimations | references L1/L2 | keyframe fusions/fallbacks | ms per frame |"
        ),
        "{text}"
    );
    for step in [1, 2] {
        for m in ["naive", "L1", "L2"] {
            // --max-frames counts tracked frames: 20 at either step.
            let row = format!("| {step} | 20 | {m} |");
            assert_eq!(
                text.lines().filter(|l| l.starts_with(&row)).count(),
                1,
                "{row} in {text}"
            );
        }
    }
    // Naive tracking of 20 frames: 19 MOTION calls, no references.
    let naive = text
        .lines()
        .find(|l| l.starts_with("| 1 | 20 | naive |"))
        .unwrap();
    assert!(naive.contains("| 19 | - | - |"), "{naive}");
    // One JSON object per row.
    let rows: Vec<serde_json::Value> = std::fs::read_to_string(&json)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 6);
    // Keyframe tracking (the default) in the L1 and L2 rows: every frame after the
    // first is registered once, each new keyframe (a level-1 reference, after the
    // first frame) is fused once with the chain through the previous frame, and the
    // table's column says so; the naive rows register against the previous frame.
    for r in &rows {
        let naive = r["mode"] == "naive";
        assert_eq!(r["keyframes"], !naive, "{r}");
        let fusions = r["keyframe_fusions"].as_u64().unwrap();
        let fallbacks = r["keyframe_fallbacks"].as_u64().unwrap();
        let frames = r["frames"].as_u64().unwrap();
        let calls = r["motion_estimations"].as_u64().unwrap();
        if naive {
            assert_eq!((fusions, fallbacks), (0, 0), "{r}");
            assert_eq!(calls, frames - 1, "{r}");
        } else {
            let keyframes = r["references"][0].as_u64().unwrap();
            assert!(fusions <= keyframes, "{r}");
            assert!(calls >= frames - 1 + fusions + fallbacks, "{r}");
            let cell = format!("| {fusions}/{fallbacks} |");
            let line = text
                .lines()
                .find(|l| {
                    l.starts_with(&format!(
                        "| {} | 20 | {} |",
                        r["frame_step"],
                        r["mode"].as_str().unwrap()
                    ))
                })
                .unwrap();
            assert!(line.contains(&cell), "{cell} in {line}");
        }
    }
    assert_eq!(rows[3]["frame_step"], 2);
    assert_eq!(rows[3]["frames"], 20);
    assert!(
        rows.iter()
            .all(|r| r["ate_rmse_m"].as_f64().is_some_and(|a| a < 0.05))
    );
}

/// Checks the files of an `ecvo run` output folder against its summary.
fn check_files(out: &Path, s: &serde_json::Value) {
    for key in [
        "frames",
        "motion_estimations",
        "references",
        "lost_frames",
        "ate_rmse_m",
        "rpe",
        "ms_per_frame",
        "mode",
        "preset",
        "levels",
        "camera",
        "sequence",
        "ecvo_version",
        "threads",
        "wall_ms_per_frame",
        "wall_time_s",
        "dropped_frames",
        "pipeline",
    ] {
        assert!(s.get(key).is_some(), "summary.json lacks {key}: {s}");
    }
    let wall = s["wall_ms_per_frame"].as_f64().unwrap();
    assert!(wall > 0.0, "{s}");
    assert!(wall * s["frames"].as_f64().unwrap() <= s["wall_time_s"].as_f64().unwrap() * 1e3);
    assert_eq!(
        s["dropped_frames"].as_u64(),
        Some(0),
        "offline drops nothing: {s}"
    );
    assert_eq!(s["pipeline"]["tracked"], s["frames"], "{s}");
    for q in ["input", "tracker"] {
        let q = &s["pipeline"]["queues"][q];
        assert!(
            q["max_depth"].as_u64().unwrap() <= q["capacity"].as_u64().unwrap(),
            "{s}"
        );
    }
    // Every run here writes a cloud, so the CLI's geometry stage has times too.
    for stat in ["median", "mean"] {
        assert!(
            s["ms_per_frame"]["geometry"][stat]
                .as_f64()
                .is_some_and(|v| v > 0.0),
            "{s}"
        );
    }
    for stage in ["filter", "tracker", "total"] {
        for stat in ["median", "mean"] {
            let v = s["ms_per_frame"][stage][stat].as_f64();
            assert!(
                v.is_some_and(|v| v > 0.0),
                "ms_per_frame.{stage}.{stat}: {s}"
            );
        }
    }
    // RPE over 1 s needs more than a second of frames (every run here has 1.5 s).
    assert!(s["rpe"]["trans_m_per_s"].as_f64().is_some(), "{s}");
    assert!(s["rpe"]["rot_deg_per_s"].as_f64().is_some(), "{s}");
    assert!(s["rpe"]["per_frame"]["trans_m"].as_f64().is_some(), "{s}");
    let frames = s["frames"].as_u64().unwrap() as usize;

    // trajectory.txt: one TUM line per frame, increasing stamps.
    let traj = data_lines(&out.join("trajectory.txt"));
    assert_eq!(traj.len(), frames);
    let mut prev = f64::NEG_INFINITY;
    for l in &traj {
        let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), 8, "{l}");
        assert!(v[0] > prev, "{l}");
        prev = v[0];
    }

    // references.txt: one line per level-1 reference, level column matching the counts.
    let refs: Vec<u64> = s["references"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    let lines = data_lines(&out.join("references.txt"));
    assert_eq!(lines.len() as u64, refs.first().copied().unwrap_or(0));
    for (k, &count) in refs.iter().enumerate() {
        let at_least = lines
            .iter()
            .filter(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                assert_eq!(f.len(), 10, "{l}");
                f[8].parse::<usize>().unwrap() > k
            })
            .count();
        assert_eq!(at_least as u64, count, "level {}", k + 1);
    }
    for l in &lines {
        // The reference's pose is its pose in trajectory.txt.
        let f: Vec<&str> = l.split_whitespace().collect();
        let index: usize = f[9].parse().unwrap();
        let t: Vec<&str> = traj[index].split_whitespace().collect();
        assert_eq!(&f[..8], &t[..8], "{l}");
    }

    // cloud.ply: a valid binary header whose vertex count matches the file size.
    let ply = std::fs::read(out.join("cloud.ply")).unwrap();
    let end = b"end_header\n";
    let pos = ply
        .windows(end.len())
        .position(|w| w == end)
        .expect("PLY header ends");
    let header = std::str::from_utf8(&ply[..pos]).unwrap();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    let n: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .expect("vertex count")
        .parse()
        .unwrap();
    for p in ["x", "y", "z", "nx", "ny", "nz"] {
        assert!(
            header.contains(&format!("property float {p}\n")),
            "{header}"
        );
    }
    assert!(header.contains("property uchar red\n"), "{header}");
    assert!(n > 1000, "{n} points");
    assert_eq!(n as u64, s["cloud"]["points"].as_u64().unwrap());
    assert_eq!(ply.len() - pos - end.len(), n * (6 * 4 + 3));

    // trajectory.svg: an SVG with both panels.
    let svg = std::fs::read_to_string(out.join("trajectory.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("ATE error over time") && svg.contains("ground truth"));
}
