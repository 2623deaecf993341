//! Drives libecvo_jni from a real JVM started with `-Xcheck:jni`.
//!
//! 1. Builds the cdylib with the `test-hooks` feature into a target dir of its own
//!    (`<target>/ecvo-jni-hooks`: a nested cargo on the outer target dir would wait
//!    for the outer cargo's lock forever).
//! 2. Replays `testdata/synth_phone_320x180` through `ecvo-pipeline` here and writes
//!    the frames and the expected poses for the Kotlin side.
//! 3. Runs `scripts/kotlin/test-kotlin.sh --native-lib ... --extra-tests
//!    rust/ecvo-jni/tests/kotlin` (the Kotlin tests live there) and requires
//!    `N passed, 0 failed` and no JNI warning.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use ecvo_core::{Config, Mode, Preset};
use ecvo_pipeline::{Admission, GeometryOptions, Pipeline, PipelineOptions};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// The target dir this test was built in (`<target>/release/deps/jvm-...`).
fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    exe.ancestors().nth(3).unwrap().to_path_buf()
}

fn build_hooks_library(target: &Path) -> PathBuf {
    let cargo = option_env!("CARGO").unwrap_or("cargo");
    let status = Command::new(cargo)
        .current_dir(repo())
        .args([
            "build",
            "-p",
            "ecvo-jni",
            "--lib",
            "--release",
            "--features",
            "test-hooks",
        ])
        .env("CARGO_TARGET_DIR", target)
        .status()
        .expect("cargo runs");
    assert!(status.success(), "building the test-hooks library failed");
    let dir = target.join("release");
    assert!(dir.join("libecvo_jni.so").exists() || dir.join("libecvo_jni.dylib").exists());
    dir
}

/// Writes meta.txt, frames.bin and expected.txt (see NativeBridgeTest.kt).
fn write_stream(out: &Path) -> usize {
    let seq = ecvo_io::Sequence::open(repo().join("testdata/synth_phone_320x180"), None)
        .expect("sample stream");
    let cam = *seq.camera();
    std::fs::create_dir_all(out).unwrap();
    std::fs::write(
        out.join("meta.txt"),
        format!(
            "{} {} {:?} {:?} {:?} {:?} {}\n",
            cam.width,
            cam.height,
            cam.fx,
            cam.fy,
            cam.cx,
            cam.cy,
            seq.len()
        ),
    )
    .unwrap();
    assert_eq!(cam.depth_scale, 1000.0, "the Kotlin test sends millimetres");

    // The same configuration the Kotlin test asks for: phone preset, L2, offline, 2 threads.
    let pipeline = Pipeline::new(
        Config::new(cam, Preset::Phone, Mode::L2),
        PipelineOptions {
            threads: 2,
            admission: Admission::Offline,
            geometry: Some(GeometryOptions::default()),
            keep_trajectory: true,
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    let mut frames =
        std::io::BufWriter::new(std::fs::File::create(out.join("frames.bin")).unwrap());
    let mut stamps = Vec::new();
    for i in 0..seq.len() {
        let f = seq.load_frame(i).unwrap();
        let ns = (f.timestamp * 1e9).round() as i64;
        stamps.push(ns);
        frames.write_all(&ns.to_le_bytes()).unwrap();
        for d in &f.depth {
            frames.write_all(&d.to_le_bytes()).unwrap();
        }
        frames.write_all(&f.intensity).unwrap();
        pipeline
            .push(ecvo_jni::ns_to_seconds(ns), |g, d| {
                g.copy_from_slice(&f.intensity);
                d.copy_from_slice(&f.depth);
            })
            .unwrap();
    }
    frames.flush().unwrap();
    let summary = pipeline.finish().unwrap();
    assert_eq!(summary.trajectory.len(), seq.len());
    let mut expected = String::new();
    for (r, ns) in summary.trajectory.iter().zip(&stamps) {
        expected += &ns.to_string();
        for v in ecvo_jni::pose_matrix(&r.pose) {
            expected += &format!(" {}", v.to_bits() as i32);
        }
        for v in ecvo_jni::pose_doubles(r) {
            expected += &format!(" {}", v.to_bits() as i64);
        }
        expected += "\n";
    }
    std::fs::write(out.join("expected.txt"), expected).unwrap();
    seq.len()
}

#[test]
fn kotlin_tests_pass_under_xcheck_jni() {
    let target = target_dir();
    let lib_dir = build_hooks_library(&target.join("ecvo-jni-hooks"));
    let data = target.join("ecvo-jni-jvm-data");
    let frames = write_stream(&data);
    assert!(frames > 10);

    let repo = repo();
    let output = Command::new("bash")
        .current_dir(&repo)
        .arg(repo.join("scripts/kotlin/test-kotlin.sh"))
        .arg("--native-lib")
        .arg(&lib_dir)
        .arg("--extra-tests")
        .arg(repo.join("rust/ecvo-jni/tests/kotlin"))
        .arg("--out")
        .arg(target.join("ecvo-jni-kotlin"))
        .env("ECVO_JNI_TEST_DATA", &data)
        .env("ECVO_JNI_TEST_HOOKS", "1")
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("{stdout}");
    eprintln!("{stderr}");
    let last = stdout
        .lines()
        .rev()
        .find(|l| l.ends_with(" failed") && l.contains(" passed, "))
        .unwrap_or_else(|| panic!("no `N passed, N failed` line; exit {:?}", output.status));
    assert!(
        !stdout.contains("WARNING in native method")
            && !stderr.contains("WARNING in native method"),
        "-Xcheck:jni warned"
    );
    assert!(last.ends_with(" 0 failed"), "{last}");
    let passed: usize = last.split(' ').next().unwrap().parse().unwrap();
    // The Kotlin API tests plus the 29 of NativeBridgeTest.
    assert!(passed >= 29, "{last}");
    assert!(
        !stdout.contains("SKIP io.ecvo.NativeBridgeTest")
            && !stdout.contains("NativeBridgeTest) (assumption"),
        "a NativeBridgeTest was skipped"
    );
    assert!(output.status.success(), "exit {:?}", output.status);
}
