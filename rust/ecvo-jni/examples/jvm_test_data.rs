//! Writes the stream and the expected poses that the JVM tests of
//! `rust/ecvo-jni/tests/kotlin` (NativeBridgeTest.kt) compare against, into the folder
//! given as the only argument: `meta.txt`, `frames.bin` and `expected.txt`, from
//! `testdata/synth_phone_320x180` replayed through `ecvo-pipeline` with the
//! configuration the Kotlin test asks for. Run by `scripts/jni-jvm-tests.sh`.

use std::io::Write;
use std::path::{Path, PathBuf};

use ecvo_core::{Config, Mode, Preset};
use ecvo_pipeline::{Admission, GeometryOptions, Pipeline, PipelineOptions};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
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

fn main() {
    let out = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .expect("usage: jvm_test_data OUT_DIR");
    let frames = write_stream(&out);
    assert!(frames > 10);
    println!(
        "wrote {frames} frames and their expected poses to {}",
        out.display()
    );
}
