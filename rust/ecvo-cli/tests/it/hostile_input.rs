//! Hostile input through the binary (issue 29): no hang, no unbounded read, no read
//! outside the sequence folder, nothing skipped or lost in silence, no NaN or inf in
//! the output. Every check runs under a deadline (`run_within`).

use crate::common;

use std::fs;
use std::path::Path;
use std::process::Output;

use common::png::with_declared_size;
use common::{entry, fails, mini_sequence, run_within, summary, temp_dir, testdata_stream};

/// Seconds any hostile run may take.
const DEADLINE: u64 = 30;

fn run_seq(seq: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["run", seq.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    run_within(&args, DEADLINE)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

fn mkfifo(path: &Path) {
    let st = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap();
    assert!(st.success(), "mkfifo {}", path.display());
}

#[test]
fn named_pipes_are_refused_not_read() {
    let dir = temp_dir("fifo");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    // A frame PNG.
    let (_, rgb) = entry(&seq.join("rgb.txt"), 1);
    fs::remove_file(seq.join(&rgb)).unwrap();
    mkfifo(&seq.join(&rgb));
    fails(&run_seq(&seq, &out, &[]), &[&rgb, "named pipe"]);
    // rgb.txt.
    let seq2 = mini_sequence(&temp_dir("fifo-list"), 3);
    fs::remove_file(seq2.join("rgb.txt")).unwrap();
    mkfifo(&seq2.join("rgb.txt"));
    fails(&run_seq(&seq2, &out, &[]), &["rgb.txt", "named pipe"]);
    // eval's ground truth.
    let gt = dir.join("gt.txt");
    mkfifo(&gt);
    let est = testdata_stream().join("groundtruth.txt");
    let o = run_within(
        &["eval", gt.to_str().unwrap(), est.to_str().unwrap()],
        DEADLINE,
    );
    fails(&o, &["gt.txt", "named pipe"]);
}

#[test]
fn dev_zero_and_huge_lists_are_refused() {
    let dir = temp_dir("zero");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    fs::remove_file(seq.join("rgb.txt")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", seq.join("rgb.txt")).unwrap();
    fails(&run_seq(&seq, &out, &[]), &["rgb.txt", "character device"]);
    // A regular (sparse) list past the limit.
    fs::remove_file(seq.join("rgb.txt")).unwrap();
    let f = fs::File::create(seq.join("rgb.txt")).unwrap();
    f.set_len(ecvo_io_limit() + 1).unwrap();
    fails(
        &run_seq(&seq, &out, &[]),
        &["rgb.txt", "larger than the limit"],
    );
    // camera.json the same.
    let seq = mini_sequence(&temp_dir("zero-cam"), 3);
    fs::remove_file(seq.join("camera.json")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", seq.join("camera.json")).unwrap();
    fails(
        &run_seq(&seq, &out, &[]),
        &["camera.json", "character device"],
    );
}

/// `ecvo_io::files::MAX_TEXT_BYTES` (16 MiB), written out: the binary's limit.
fn ecvo_io_limit() -> u64 {
    16 << 20
}

#[test]
fn oversized_declared_frame_is_refused_before_decoding() {
    let dir = temp_dir("declared");
    let seq = mini_sequence(&dir, 3);
    let (_, depth) = entry(&seq.join("depth.txt"), 1);
    let png = fs::read(seq.join(&depth)).unwrap();
    fs::write(seq.join(&depth), with_declared_size(&png, 65_535, 65_535)).unwrap();
    fails(
        &run_seq(&seq, &dir.join("out"), &[]),
        &[&depth, "65535x65535", "320x180"],
    );
}

#[test]
fn entries_leading_out_of_the_folder_are_refused() {
    let dir = temp_dir("escape");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    let list = seq.join("rgb.txt");
    let good = fs::read_to_string(&list).unwrap();
    let (_, rgb) = entry(&list, 1);
    // `..` and absolute entries: refused at parse time with the line.
    fs::copy(seq.join(&rgb), dir.join("outside.png")).unwrap();
    for bad in ["../outside.png", "/etc/passwd"] {
        fs::write(&list, good.replace(&rgb, bad)).unwrap();
        fails(
            &run_seq(&seq, &out, &[]),
            &["rgb.txt:5", bad, "--allow-outside"],
        );
    }
    // A symlink leading out: refused when read.
    fs::write(&list, &good).unwrap();
    fs::remove_file(seq.join(&rgb)).unwrap();
    std::os::unix::fs::symlink(dir.join("outside.png"), seq.join(&rgb)).unwrap();
    fails(
        &run_seq(&seq, &out, &[]),
        &[&rgb, "outside the sequence folder"],
    );
    // --allow-outside opts in.
    let o = run_seq(&seq, &out, &["--allow-outside"]);
    assert!(o.status.success(), "{}", stderr(&o));
    fs::write(&list, good.replace(&rgb, "../outside.png")).unwrap();
    let o = run_seq(&seq, &out, &["--allow-outside"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn skipped_frames_are_reported_and_strict_refuses_them() {
    let dir = temp_dir("skips");
    let seq = mini_sequence(&dir, 6);
    let out = dir.join("out");
    // Frame 3's images replaced by frame 2's: a repeated frame.
    for list in ["rgb.txt", "depth.txt"] {
        let (_, a) = entry(&seq.join(list), 2);
        let (_, b) = entry(&seq.join(list), 3);
        fs::copy(seq.join(&a), seq.join(&b)).unwrap();
    }
    let o = run_seq(&seq, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("identical to the previous frame"), "{e}");
    assert!(
        e.contains("warning: frames: listed 6 colour + 6 depth"),
        "{e}"
    );
    assert!(e.contains("skipped 1"), "{e}");
    let s = summary(&out);
    assert_eq!(
        s["frames_account"]["skipped_repeated"],
        serde_json::json!([3])
    );
    assert_eq!(s["frames_account"]["tracked"], 5);
    fails(
        &run_seq(&seq, &out, &["--strict"]),
        &["identical", "--strict"],
    );

    // A depth list with half the entries.
    let seq = mini_sequence(&temp_dir("skips-half"), 6);
    let list = seq.join("depth.txt");
    let text = fs::read_to_string(&list).unwrap();
    let kept: Vec<&str> = text.lines().take(3 + 3).collect();
    fs::write(&list, kept.join("\n") + "\n").unwrap();
    let o = run_seq(&seq, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("rgb.txt: 3 of its 6 entries have no depth image"),
        "{e}"
    );
    assert!(e.contains("skipped unpaired: 3 colour, 0 depth"), "{e}");
    assert_eq!(summary(&out)["frames_account"]["unpaired_rgb_skipped"], 3);
    fails(
        &run_seq(&seq, &out, &["--strict"]),
        &["no partner", "--strict"],
    );
}

#[test]
fn depth_without_valid_pixels_warns_at_once() {
    let dir = temp_dir("nodepth");
    let seq = mini_sequence(&dir, 4);
    // Saturated depth (65535 raw, 65.5 m: beyond the filter's 8 m) in every frame.
    for n in 0..4 {
        let (_, f) = entry(&seq.join("depth.txt"), n);
        ecvo_io::png::write_depth_png(seq.join(&f), &vec![u16::MAX; 320 * 180], 320, 180).unwrap();
    }
    let o = run_seq(&seq, &dir.join("out"), &[]);
    let e = stderr(&o);
    assert!(
        e.contains("frame 0 (timestamp 1700000000)") && e.contains("no valid depth pixel"),
        "{e}"
    );
    assert!(e.contains("4 without a valid depth pixel"), "{e}");
    // Implausible intrinsics are refused before any frame is read.
    let cam = seq.join("camera.json");
    let good = fs::read_to_string(&cam).unwrap();
    for (from, to) in [
        ("\"fx\": 250.0", "\"fx\": 1e-5"),
        ("\"fx\": 250.0", "\"fx\": 1e300"),
        ("\"cx\": 159.5", "\"cx\": 1e12"),
        ("\"depth_scale\": 1000.0", "\"depth_scale\": 1e-300"),
    ] {
        fs::write(&cam, good.replace(from, to)).unwrap();
        let field = from.split('"').nth(1).unwrap();
        fails(
            &run_seq(&seq, &dir.join("out"), &[]),
            &["camera.json", field],
        );
    }
}

#[test]
fn non_finite_values_are_refused_with_the_line() {
    let dir = temp_dir("nonfinite");
    let out = dir.join("out");
    // A list timestamp.
    let seq = mini_sequence(&dir, 3);
    let list = seq.join("rgb.txt");
    let text = fs::read_to_string(&list).unwrap();
    let (t, _) = entry(&list, 1);
    fs::write(&list, text.replacen(&t, "nan", 1)).unwrap();
    fails(&run_seq(&seq, &out, &[]), &["rgb.txt:5", "not finite"]);
    // Ground truth: inf, and a finite value too large to score.
    let seq = mini_sequence(&temp_dir("nonfinite-gt"), 3);
    let gt = seq.join("groundtruth.txt");
    let good = fs::read_to_string(&gt).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    let tx = lines[2].split_whitespace().nth(1).unwrap().to_string();
    for (bad, needle) in [("inf", "not finite"), ("1e300", "out of range")] {
        fs::write(&gt, good.replacen(&tx, bad, 1)).unwrap();
        fails(&run_seq(&seq, &out, &[]), &["groundtruth.txt:3", needle]);
        let o = run_within(
            &["eval", gt.to_str().unwrap(), gt.to_str().unwrap()],
            DEADLINE,
        );
        fails(&o, &["groundtruth.txt:3", needle]);
    }
    // camera.json: NaN (not JSON), and an array read by position.
    let cam = seq.join("camera.json");
    let good = fs::read_to_string(&cam).unwrap();
    fs::write(&gt, lines.join("\n")).unwrap();
    fs::write(&cam, good.replace("250.0", "NaN")).unwrap();
    fails(&run_seq(&seq, &out, &[]), &["camera.json"]);
    fs::write(&cam, "[320, 180, 250.0, 250.0, 159.5, 89.5, 1000.0]").unwrap();
    fails(&run_seq(&seq, &out, &[]), &["camera.json", "JSON object"]);
}

#[test]
fn ground_truth_means_an_ate_was_computed() {
    let dir = temp_dir("gt-flag");
    let seq = mini_sequence(&dir, 4);
    let out = dir.join("out");
    // Ground truth at other times: no ATE, and the summary says so.
    let gt = seq.join("groundtruth.txt");
    fs::write(&gt, "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n").unwrap();
    let o = run_seq(&seq, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("ATE RMSE: n/a (only 0 pose pairs"), "{text}");
    let s = summary(&out);
    assert_eq!(s["ground_truth"], false, "{s}");
    assert_eq!(s["ground_truth_file"], true, "{s}");
    assert!(s["ate_rmse_m"].is_null());
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    // An empty ground-truth file: eval refuses it.
    fs::write(&gt, "").unwrap();
    let est = out.join("trajectory.txt");
    let o = run_within(
        &["eval", gt.to_str().unwrap(), est.to_str().unwrap()],
        DEADLINE,
    );
    fails(&o, &["pose pairs"]);
}

#[test]
fn inconsistencies_are_consistent() {
    let dir = temp_dir("consistent");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    // Both frame-step flags refuse 0.
    let o = run_within(
        &["table", seq.to_str().unwrap(), "--frame-steps", "0"],
        DEADLINE,
    );
    fails(&o, &["--frame-steps"]);
    assert_eq!(o.status.code(), Some(2));
    fails(
        &run_seq(&seq, &out, &["--frame-step", "0"]),
        &["--frame-step"],
    );
    // A byte-order mark at the start of rgb.txt is accepted.
    let list = seq.join("rgb.txt");
    let good = fs::read_to_string(&list).unwrap();
    fs::write(&list, format!("\u{feff}{good}")).unwrap();
    let o = run_seq(&seq, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A NUL byte in a file name is escaped; a 1 MB one is shortened.
    let (_, rgb) = entry(&list, 1);
    fs::write(&list, good.replace(&rgb, "rgb/a\u{1}b.png")).unwrap();
    let e = fails(&run_seq(&seq, &out, &[]), &["rgb/a\\u{1}b.png"]);
    assert!(!e.contains('\u{1}'), "{e}");
    let long = format!("rgb/{}.png", "x".repeat(1 << 20));
    fs::write(&list, good.replace(&rgb, &long)).unwrap();
    let e = fails(&run_seq(&seq, &out, &[]), &["characters]"]);
    assert!(e.len() < 2000, "{} bytes of stderr", e.len());
}

#[test]
fn a_frame_too_large_for_the_budget_is_refused_before_allocating() {
    let dir = temp_dir("budget");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    // 8192x8192 frames (the header says so; the data is never decoded).
    let cam = seq.join("camera.json");
    let text = fs::read_to_string(&cam)
        .unwrap()
        .replace("\"width\": 320", "\"width\": 8192")
        .replace("\"height\": 180", "\"height\": 8192")
        .replace("\"fx\": 250.0", "\"fx\": 6400.0")
        .replace("\"fy\": 250.0", "\"fy\": 6400.0")
        .replace("\"cx\": 159.5", "\"cx\": 4095.5")
        .replace("\"cy\": 89.5", "\"cy\": 4095.5");
    fs::write(&cam, text).unwrap();
    for list in ["rgb.txt", "depth.txt"] {
        for n in 0..3 {
            let (_, f) = entry(&seq.join(list), n);
            let png = fs::read(seq.join(&f)).unwrap();
            fs::write(seq.join(&f), with_declared_size(&png, 8192, 8192)).unwrap();
        }
    }
    let e = fails(
        &run_seq(&seq, &out, &[]),
        &["8192x8192", "memory budget of 512 MiB"],
    );
    assert!(e.contains("need"), "{e}");
    // A smaller budget refuses the small stream too, naming both figures.
    let seq = mini_sequence(&temp_dir("budget-small"), 3);
    fails(
        &run_seq(&seq, &out, &["--max-memory", "8M"]),
        &["320x180 frames need", "memory budget of 8 MiB"],
    );
    fails(
        &run_seq(&seq, &out, &["--max-memory", "lots"]),
        &["--max-memory"],
    );
}
