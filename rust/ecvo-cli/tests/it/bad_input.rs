//! Bad input through the binary: every error is one clear message naming the file
//! (and line), with a non-zero exit status and no panic.

use crate::common;

use std::fs;

use common::{entry, fails, mini_sequence, run, run_seq, temp_dir, testdata_stream};

#[test]
fn missing_sequence_folder() {
    let dir = temp_dir("missing");
    let missing = dir.join("no-such-sequence");
    let o = run_seq(&missing, &dir.join("out"), &[]);
    fails(&o, &["no-such-sequence"]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn malformed_list_line_names_file_and_line() {
    let dir = temp_dir("malformed");
    let seq = mini_sequence(&dir, 3);
    let list = seq.join("rgb.txt");
    let mut text = fs::read_to_string(&list).unwrap();
    text.push_str("1700000001.5\n"); // line 7: a timestamp without a file
    fs::write(&list, text).unwrap();
    fails(&run_seq(&seq, &dir.join("out"), &[]), &["rgb.txt:7"]);
}

#[test]
fn non_monotonic_stamps_name_file_and_line() {
    let dir = temp_dir("monotonic");
    let seq = mini_sequence(&dir, 3);
    let list = seq.join("depth.txt");
    let text = fs::read_to_string(&list).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.swap(4, 5); // data lines 2 and 3 (file lines 5 and 6)
    fs::write(&list, lines.join("\n") + "\n").unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &[]),
        &["depth.txt:6", "strictly increasing"],
    );
}

#[test]
fn wrong_png_mid_stream_names_the_file() {
    let dir = temp_dir("png");
    let seq = mini_sequence(&dir, 4);
    // Frame 2's depth image replaced by an 8-bit intensity image.
    let (_, rgb) = entry(&seq.join("rgb.txt"), 2);
    let (_, depth) = entry(&seq.join("depth.txt"), 2);
    fs::copy(seq.join(&rgb), seq.join(&depth)).unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &[]),
        &[&depth, "16-bit gray"],
    );
}

#[test]
fn garbage_png_names_the_file() {
    let dir = temp_dir("garbage");
    let seq = mini_sequence(&dir, 3);
    let (_, rgb) = entry(&seq.join("rgb.txt"), 0);
    fs::write(seq.join(&rgb), b"not a png at all").unwrap();
    fails(&run_seq(&seq, &dir.join("out"), &[]), &[&rgb]);
}

#[test]
fn image_size_mismatch_names_the_file() {
    let dir = temp_dir("size");
    let seq = mini_sequence(&dir, 3);
    let cam = seq.join("camera.json");
    let text = fs::read_to_string(&cam).unwrap().replace("320", "640");
    fs::write(&cam, text).unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &[]),
        &["320x180", "640x180"],
    );
}

#[test]
fn bad_camera_json_names_file_and_field() {
    let dir = temp_dir("camera");
    let seq = mini_sequence(&dir, 3);
    // In the sequence folder: a missing field.
    let cam = seq.join("camera.json");
    let good = fs::read_to_string(&cam).unwrap();
    let no_fx: String = good
        .lines()
        .filter(|l| !l.contains("\"fx\""))
        .collect::<Vec<_>>()
        .join("\n");
    fs::write(&cam, &no_fx).unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &[]),
        &["camera.json", "fx"],
    );
    fs::write(&cam, &good).unwrap();

    // Given with --camera: a zero focal length, then not JSON, then a missing file.
    let other = dir.join("other-camera.json");
    fs::write(&other, good.replace("\"fy\": 250.0", "\"fy\": 0.0")).unwrap();
    let arg = other.to_str().unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &["--camera", arg]),
        &["--camera", "other-camera.json", "fy"],
    );
    fs::write(&other, "{ this is not json").unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &["--camera", arg]),
        &["other-camera.json"],
    );
    fails(
        &run_seq(
            &seq,
            &dir.join("out"),
            &["--camera", "/no/such/camera.json"],
        ),
        &["/no/such/camera.json"],
    );

    // No camera at all.
    fs::remove_file(&cam).unwrap();
    fails(&run_seq(&seq, &dir.join("out"), &[]), &["no camera.json"]);
}

#[test]
fn bad_levels_are_explained() {
    let dir = temp_dir("levels");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    for (levels, needle) in [
        ("30:7", "needs a unit"),
        ("30mm:7", "deg"),
        ("-3mm:7deg", "out of range"),
        ("30mm", "DISTANCE:ANGLE"),
    ] {
        let stderr = fails(&run_seq(&seq, &out, &["--levels", levels]), &[needle]);
        assert!(stderr.contains(&format!("--levels `{levels}`")), "{stderr}");
    }
    // L2 needs two levels.
    fails(
        &run_seq(&seq, &out, &["--levels", "30mm:7deg"]),
        &["--mode l2", "2 reference level"],
    );
}

#[test]
fn bad_flags_exit_with_usage_errors() {
    let dir = temp_dir("flags");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    for (flags, needle) in [
        (&["--mode", "l3"][..], "--mode"),
        (&["--preset", "tablet"][..], "--preset"),
        (&["--max-frames", "many"][..], "--max-frames"),
        (&["--threads", "0"][..], "--threads"),
        (&["--no-such-flag"][..], "--no-such-flag"),
    ] {
        let o = run_seq(&seq, &out, flags);
        fails(&o, &[needle]);
        assert_eq!(o.status.code(), Some(2), "{flags:?}");
    }
    // --out is required.
    let o = run(&["run", seq.to_str().unwrap()]);
    fails(&o, &["--out"]);
    // An output folder that cannot be created.
    let file = dir.join("a-file");
    fs::write(&file, "x").unwrap();
    fails(
        &run_seq(&seq, &file.join("out"), &[]),
        &["a-file", "output folder"],
    );
}

#[test]
fn eval_errors_name_file_and_line() {
    let dir = temp_dir("eval");
    let gt = testdata_stream().join("groundtruth.txt");
    let bad = dir.join("est.txt");
    fs::write(
        &bad,
        "# t x y z qx qy qz qw\n1 0 0 0 0 0 0 1\n2 0 0 zero 0 0 0 1\n",
    )
    .unwrap();
    fails(
        &run(&["eval", gt.to_str().unwrap(), bad.to_str().unwrap()]),
        &["est.txt:3", "tz"],
    );
    fails(
        &run(&["eval", gt.to_str().unwrap(), "/no/such/est.txt"]),
        &["/no/such/est.txt"],
    );
    // Well-formed but at other times: nothing to compare.
    let far = dir.join("far.txt");
    fs::write(&far, "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n").unwrap();
    fails(
        &run(&["eval", gt.to_str().unwrap(), far.to_str().unwrap()]),
        &["far.txt", "pose pairs"],
    );
}

#[test]
fn synth_refuses_to_overwrite_and_checks_flags() {
    let dir = temp_dir("synth");
    let out = dir.join("s");
    let o = run(&["synth", "--out", out.to_str().unwrap(), "--frames", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&["synth", "--out", out.to_str().unwrap(), "--frames", "2"]);
    fails(&o, &["rgb.txt", "refusing to overwrite"]);
    let o = run(&[
        "synth",
        "--out",
        dir.join("t").to_str().unwrap(),
        "--noise",
        "loud",
    ]);
    fails(&o, &["--noise"]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&[
        "synth",
        "--out",
        dir.join("u").to_str().unwrap(),
        "--size",
        "100x100",
    ]);
    fails(&o, &["--size"]);
    assert_eq!(o.status.code(), Some(2));
}
