//! Memory soak: pushes many synthetic 320x180 frames through a live pipeline (no
//! point cloud, no trajectory kept) and samples the process's resident set size
//! (`VmRSS` in `/proc/self/status`) every `--every` frames.
//!
//! It prints the RSS curve and checks that, after `--warmup` frames, RSS stays
//! within 1 MB of its first post-warm-up sample and below 32 MB (exit status 1 if
//! not). Linux only (it reads `/proc`). Not part of the test run: 100,000 frames take
//! several minutes.
//!
//! ```text
//! cargo run --release -p ecvo-pipeline --example soak
//! cargo run --release -p ecvo-pipeline --example soak -- --frames 20000 --every 1000
//! ```
//!
//! The frames: 16 frames of ecvo-synth's phone sequence, rendered once (2.8 MB, part
//! of the RSS measured), played forwards then backwards so that the motion stays
//! continuous, with timestamps 1/30 s apart. Frames are pushed as soon as the
//! tracker has nearly caught up (live admission never waits, so pushing without a
//! pause would only measure the drop path).

use std::process::ExitCode;
use std::time::{Duration, Instant};

use ecvo_core::{Camera, Config, Mode, Preset};
use ecvo_pipeline::{Admission, Pipeline, PipelineOptions};
use ecvo_synth::{SynthFrame, SynthSequence};

/// Frames rendered once and replayed.
const RENDERED: usize = 16;
/// Flatness allowed after warm-up, and the ceiling, in kB.
const FLAT_KB: u64 = 1024;
const MAX_KB: u64 = 32 * 1024;

fn rss_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse().expect("a number"))
        .unwrap_or(default)
}

fn main() -> ExitCode {
    let frames = arg("--frames", 100_000);
    let every = arg("--every", 2_000).max(1);
    let warmup = arg("--warmup", 10_000);
    let threads = arg("--threads", 2);

    let seq = SynthSequence::phone_320x180(RENDERED, 11);
    let c = seq.camera;
    let camera = Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    };
    let rendered: Vec<SynthFrame> = seq.iter().collect();
    let config = Config::new(camera, Preset::Phone, Mode::L2);
    let options = PipelineOptions {
        threads,
        admission: Admission::Live,
        geometry: None,
        keep_trajectory: false,
        output_queue: None,
        ..PipelineOptions::default()
    };
    let pipeline = Pipeline::new(config, options).expect("a valid configuration");
    println!(
        "soak: {frames} frames of 320x180, live, no point cloud, {threads} threads; RSS at start {} kB",
        rss_kb()
    );
    println!(
        "{:>8} {:>9} {:>9} {:>8} {:>6} {:>8}",
        "frame", "RSS kB", "tracked", "dropped", "lost", "s"
    );

    let start = Instant::now();
    let mut curve: Vec<(usize, u64)> = Vec::new();
    for k in 0..frames {
        // 0, 1, .., 15, 14, .., 1, 0, 1, ...: continuous motion.
        let period = 2 * (RENDERED - 1);
        let i = k % period;
        let f = &rendered[if i < RENDERED { i } else { period - i }];
        pipeline
            .push(k as f64 / 30.0, |int, depth| {
                int.copy_from_slice(&f.intensity);
                depth.copy_from_slice(&f.depth);
            })
            .expect("push");
        // Let the tracker nearly catch up (a bounded wait: live admission may drop).
        let waited = Instant::now();
        while pipeline.latest().tracked + pipeline_dropped(&pipeline) + 2 < k as u64 + 1
            && waited.elapsed() < Duration::from_millis(200)
        {
            std::thread::sleep(Duration::from_micros(200));
        }
        if (k + 1) % every == 0 {
            let s = pipeline.stats();
            let rss = rss_kb();
            curve.push((k + 1, rss));
            println!(
                "{:>8} {:>9} {:>9} {:>8} {:>6} {:>8.1}",
                k + 1,
                rss,
                s.tracked,
                s.dropped,
                s.counters.lost_frames,
                start.elapsed().as_secs_f64()
            );
        }
    }
    let summary = pipeline.finish().expect("the pipeline finishes");
    let s = &summary.stats;
    println!(
        "done: {} pushed, {} tracked, {} dropped, {} lost, filter {:.2} ms, tracker {:.2} ms (medians), {:.0} s",
        s.pushed,
        s.tracked,
        s.dropped,
        s.counters.lost_frames,
        s.filter.median_ms,
        s.tracker.median_ms,
        start.elapsed().as_secs_f64()
    );

    let after: Vec<u64> = curve
        .iter()
        .filter(|(k, _)| *k > warmup)
        .map(|&(_, r)| r)
        .collect();
    let Some(&first) = after.first() else {
        println!("no sample after the warm-up of {warmup} frames");
        return ExitCode::FAILURE;
    };
    let (lo, hi) = (
        *after.iter().min().expect("samples"),
        *after.iter().max().expect("samples"),
    );
    let spread = hi - lo;
    println!(
        "after {warmup} frames: RSS {first} kB first, {lo}..{hi} kB, spread {spread} kB \
         (allowed {FLAT_KB}), max {hi} kB (allowed {MAX_KB})"
    );
    if spread <= FLAT_KB && hi < MAX_KB {
        println!("PASS");
        ExitCode::SUCCESS
    } else {
        println!("FAIL");
        ExitCode::FAILURE
    }
}

fn pipeline_dropped(p: &Pipeline) -> u64 {
    p.stats().dropped
}
