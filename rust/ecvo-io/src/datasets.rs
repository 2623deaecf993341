//! Finding the shared RGB-D datasets (`shared/datasets` beside the repository) from
//! tests, benchmarks and tools.

use std::path::{Path, PathBuf};

/// Environment variable naming the datasets folder; checked first.
pub const DATASETS_ENV: &str = "ECVO_DATASETS";

/// Environment variable that, set to `1`, turns a missing dataset in tests into a
/// failure instead of a skip.
pub const REQUIRE_DATASETS_ENV: &str = "ECVO_REQUIRE_DATASETS";

fn search_up(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .map(|a| a.join("shared").join("datasets"))
        .find(|p| p.is_dir())
}

/// The datasets folder: `$ECVO_DATASETS` if set (and `None` if that is not a folder),
/// else the first `shared/datasets` found walking up from `$CARGO_MANIFEST_DIR` (at
/// run time, then this crate's at build time) and from the current directory.
pub fn datasets_dir() -> Option<PathBuf> {
    if let Some(v) = std::env::var_os(DATASETS_ENV).filter(|v| !v.is_empty()) {
        let p = PathBuf::from(v);
        if p.is_dir() {
            return Some(p);
        }
        log::warn!("{DATASETS_ENV}={} is not a folder", p.display());
        return None;
    }
    let mut starts: Vec<PathBuf> = Vec::new();
    if let Some(m) = std::env::var_os("CARGO_MANIFEST_DIR") {
        starts.push(m.into());
    }
    starts.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    if let Ok(cwd) = std::env::current_dir() {
        starts.push(cwd);
    }
    starts.iter().find_map(|s| search_up(s))
}

/// The dataset folder `name` (e.g. `tum_fr1_xyz_half`) inside [`datasets_dir`], if it
/// exists.
pub fn dataset(name: &str) -> Option<PathBuf> {
    datasets_dir().map(|d| d.join(name)).filter(|p| p.is_dir())
}

/// For tests: the dataset folder `name`, or `None` after telling the user that the
/// test did not run. Panics instead if `ECVO_REQUIRE_DATASETS=1`, so that CI cannot
/// pass by skipping.
///
/// The notice goes straight to the process's stderr, not through `eprintln!`, which
/// the test harness captures (and shows only for failed tests): `cargo test` prints
/// `NOT RUN (no data): <test>: ...` among its results, where a user sees it.
pub fn dataset_for_test(name: &str) -> Option<PathBuf> {
    if let Some(p) = dataset(name) {
        return Some(p);
    }
    let required = std::env::var(REQUIRE_DATASETS_ENV).is_ok_and(|v| v.trim() == "1");
    let msg = format!(
        "dataset `{name}` not found (set {DATASETS_ENV} or put it in shared/datasets beside \
         the repository)"
    );
    if required {
        panic!("{msg}, and {REQUIRE_DATASETS_ENV}=1");
    }
    let test = std::thread::current()
        .name()
        .filter(|n| *n != "main")
        .map(|n| format!("{n}: "))
        .unwrap_or_default();
    let line =
        format!("\nNOT RUN (no data): {test}{msg}; the test passes without checking anything\n");
    // An uncaptured write: libtest's capture only redirects the print macros.
    let _ = std::io::Write::write_all(&mut std::io::stderr().lock(), line.as_bytes());
    None
}
