//! Helpers shared by the tests of the `ecvo` binary.

#![allow(dead_code)]

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
