//! Helpers shared by the tests of the `ecvo` binary.

#![allow(dead_code)]

pub mod png;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `ecvo` binary built for these tests.
pub fn ecvo() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ecvo"))
}

/// Runs `ecvo` with `args`; returns its output.
pub fn run(args: &[&str]) -> Output {
    ecvo().args(args).output().expect("the ecvo binary runs")
}

/// Runs `ecvo` with `args` and panics with its stderr unless it succeeded.
pub fn run_ok(args: &[&str]) -> Output {
    let out = run(args);
    assert!(
        out.status.success(),
        "ecvo {args:?} failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The repository root.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .expect("rust/ecvo-cli is two levels below the root")
        .to_path_buf()
}

/// The synthetic test stream in `testdata/`.
pub fn testdata_stream() -> PathBuf {
    repo_root().join("testdata").join("synth_phone_320x180")
}

/// A fresh, empty temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ecvo-cli-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary folder");
    dir
}

/// Parses `DIR/summary.json`.
pub fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json exists");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// Data lines (not empty, not `#` comments) of a text file.
pub fn data_lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map(str::to_string)
        .collect()
}

/// Checks the counters of a summary: no loss, and every frame after the first costs
/// one motion estimation plus one per reference it became by a correction, one per
/// correction that failed or was rejected, and one per refinement against the
/// level-1 reference; refused refinements are some of those.
pub fn check_counters(s: &serde_json::Value, frames: u64, levels: usize) {
    assert_eq!(s["frames"].as_u64(), Some(frames), "{s}");
    assert_eq!(s["lost_frames"].as_u64(), Some(0), "{s}");
    let refs: Vec<u64> = s["references"]
        .as_array()
        .expect("references is an array")
        .iter()
        .map(|v| v.as_u64().expect("reference count"))
        .collect();
    assert_eq!(refs.len(), levels, "{s}");
    // A level-k reference was first a level-(k-1) reference.
    assert!(refs.windows(2).all(|w| w[0] >= w[1]), "{refs:?}");
    let count = |k: &str| s[k].as_u64().unwrap_or_else(|| panic!("{k} in {s}"));
    assert_eq!(
        s["motion_estimations"].as_u64(),
        Some(
            frames - 1 + refs.iter().sum::<u64>() - count("stale_references")
                + count("failed_corrections")
                + count("rejected_corrections")
                + count("refinements")
        ),
        "{s}"
    );
    assert!(count("refused_refinements") <= count("refinements"), "{s}");
}

/// A copy of the first `frames` frames of the test stream in `dir` (lists, images,
/// camera.json, ground truth).
pub fn mini_sequence(dir: &Path, frames: usize) -> PathBuf {
    let src = testdata_stream();
    let seq = dir.join("seq");
    fs::create_dir_all(seq.join("rgb")).unwrap();
    fs::create_dir_all(seq.join("depth")).unwrap();
    fs::copy(src.join("camera.json"), seq.join("camera.json")).unwrap();
    for list in ["rgb.txt", "depth.txt", "groundtruth.txt"] {
        let text = fs::read_to_string(src.join(list)).unwrap();
        let mut kept = Vec::new();
        let mut n = 0;
        for line in text.lines() {
            if line.starts_with('#') {
                kept.push(line.to_string());
            } else if n < frames {
                n += 1;
                kept.push(line.to_string());
                if list != "groundtruth.txt" {
                    let file = line.split_whitespace().nth(1).unwrap();
                    fs::copy(src.join(file), seq.join(file)).unwrap();
                }
            }
        }
        fs::write(seq.join(list), kept.join("\n") + "\n").unwrap();
    }
    seq
}

/// The n-th (0-based) data line of a list file: `(timestamp, file)`.
pub fn entry(list: &Path, n: usize) -> (String, String) {
    let text = fs::read_to_string(list).unwrap();
    let line = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .nth(n)
        .unwrap()
        .to_string();
    let mut f = line.split_whitespace();
    (f.next().unwrap().into(), f.next().unwrap().into())
}

/// Checks a failed run: non-zero status, no panic, and stderr containing every one
/// of `needles`. Returns stderr.
pub fn fails(out: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "succeeded unexpectedly: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "stderr lacks `{n}`:\n{stderr}");
    }
    stderr
}

pub fn run_seq(seq: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["run", seq.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    run(&args)
}

/// Runs `ecvo` with `args`, killing it and failing the test if it takes more than
/// `secs` seconds (a hang on hostile input is a failure, not a stuck test run).
pub fn run_within(args: &[&str], secs: u64) -> Output {
    use std::io::Read as _;
    let mut child = ecvo()
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the ecvo binary runs");
    let start = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("waiting for ecvo") {
            let (mut stdout, mut stderr) = (Vec::new(), Vec::new());
            child
                .stdout
                .take()
                .unwrap()
                .read_to_end(&mut stdout)
                .unwrap();
            child
                .stderr
                .take()
                .unwrap()
                .read_to_end(&mut stderr)
                .unwrap();
            return Output {
                status,
                stdout,
                stderr,
            };
        }
        if start.elapsed().as_secs() >= secs {
            let _ = child.kill();
            let _ = child.wait();
            panic!("ecvo {args:?} did not finish within {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}
