//! Throughput of the pipeline against the sequential engine on a TUM stream.
//!
//! Decodes the frames into memory first, then times tracking all of them with
//! `ecvo_core::Odometry` (sequential) in a one-thread rayon pool (the one-core
//! baseline), with `Odometry` in a `--threads` pool (ecvo-core's parallel loops
//! alone), and with the offline `Pipeline` of `--threads` threads, alternating them
//! `--repeat` times. It prints frames per second (median over the repeats), the
//! ratios to the one-core baseline, the pipeline's stage times, and checks that all
//! give the same poses bit for bit (exit status 1 if not).
//!
//! ```text
//! cargo run --release -p ecvo-pipeline --example throughput -- tum_fr1_xyz_half
//! cargo run --release -p ecvo-pipeline --example throughput -- tum_fr1_xyz_full300 --threads 2 --repeat 3
//! # one engine only (to time whole processes from outside):
//! cargo run --release -p ecvo-pipeline --example throughput -- tum_fr1_xyz_half --only pipeline
//! # decode the frames and track nothing (the baseline to subtract from a whole-process
//! # count, scripts/profile/insn-aarch64.sh):
//! cargo run --release -p ecvo-pipeline --example throughput -- tum_fr1_xyz_half --only decode
//! ```
//!
//! The dataset is a folder name under the shared datasets folder (see
//! `ecvo_io::datasets_dir`) or a path.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use ecvo_core::{Config, Mode, Odometry, Pose, Preset};
use ecvo_pipeline::{Pipeline, PipelineOptions, PipelineStats};

struct Args {
    dataset: String,
    frames: Option<usize>,
    threads: usize,
    repeat: usize,
    only: Option<String>,
    mode: Mode,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        dataset: String::new(),
        frames: None,
        threads: 2,
        repeat: 1,
        only: None,
        mode: Mode::L2,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--frames" => a.frames = Some(value("--frames")?.parse().map_err(|e| format!("{e}"))?),
            "--threads" => a.threads = value("--threads")?.parse().map_err(|e| format!("{e}"))?,
            "--repeat" => a.repeat = value("--repeat")?.parse().map_err(|e| format!("{e}"))?,
            "--only" => a.only = Some(value("--only")?),
            "--mode" => a.mode = value("--mode")?.parse().map_err(|e| format!("{e}"))?,
            "-h" | "--help" => {
                return Err(
                    "usage: throughput DATASET [--frames N] [--threads T] [--repeat R] \
                            [--only pipeline|sequential|decode] [--mode naive|l1|l2]"
                        .into(),
                );
            }
            s if a.dataset.is_empty() && !s.starts_with('-') => a.dataset = s.to_string(),
            s => return Err(format!("unknown argument `{s}`")),
        }
    }
    if a.dataset.is_empty() {
        return Err("give a dataset (e.g. tum_fr1_xyz_half)".into());
    }
    if let Some(o) = &a.only
        && o != "pipeline"
        && o != "sequential"
        && o != "decode"
    {
        return Err(format!(
            "--only {o}: expected pipeline, sequential or decode"
        ));
    }
    a.repeat = a.repeat.max(1);
    Ok(a)
}

/// The sequential engine inside a rayon pool of `threads` threads: with one, the
/// baseline of one core; with more, ecvo-core's own parallel loops.
fn sequential(config: &Config, frames: &[ecvo_io::Frame], threads: usize) -> (f64, Vec<Pose>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let mut odo = Odometry::new(config.clone()).expect("valid config");
    pool.install(|| {
        let t0 = Instant::now();
        let poses = frames
            .iter()
            .map(|f| odo.push(f.view()).expect("frame matches camera").pose)
            .collect();
        (t0.elapsed().as_secs_f64(), poses)
    })
}

fn pipeline(
    config: &Config,
    frames: &[ecvo_io::Frame],
    threads: usize,
) -> (f64, Vec<Pose>, PipelineStats) {
    let p = Pipeline::new(
        config.clone(),
        PipelineOptions {
            threads,
            keep_trajectory: true,
            ..PipelineOptions::default()
        },
    )
    .expect("valid config");
    let t0 = Instant::now();
    for f in frames {
        p.push_view(f.view()).expect("frame accepted");
    }
    p.flush().expect("pipeline ran");
    let secs = t0.elapsed().as_secs_f64();
    let summary = p.finish().expect("pipeline ran");
    let poses = summary.trajectory.iter().map(|r| r.pose).collect();
    (secs, poses, summary.stats)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn same(a: &[Pose], b: &[Pose]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.to_homogeneous()
                .iter()
                .zip(y.to_homogeneous().iter())
                .all(|(p, q)| p.to_bits() == q.to_bits())
        })
}

fn main() -> ExitCode {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let dir = ecvo_io::dataset(&args.dataset).unwrap_or_else(|| PathBuf::from(&args.dataset));
    let seq = match ecvo_io::Sequence::open(&dir, None) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{}: {e}", dir.display());
            return ExitCode::from(2);
        }
    };
    let n = args.frames.unwrap_or(seq.len()).min(seq.len());
    let t0 = Instant::now();
    let frames: Vec<ecvo_io::Frame> = (0..n)
        .map(|i| seq.load_frame(i).expect("frame decodes"))
        .collect();
    let cam = seq.camera();
    println!(
        "{}: {n} frames {}x{} decoded in {:.1} s; mode {:?}, {} compute threads, {} cores",
        args.dataset,
        cam.width,
        cam.height,
        t0.elapsed().as_secs_f64(),
        args.mode,
        args.threads,
        std::thread::available_parallelism().map_or(0, |c| c.get()),
    );
    if args.only.as_deref() == Some("decode") {
        return ExitCode::SUCCESS;
    }
    let config = Config::new(*cam, Preset::Pc, args.mode);

    let (mut seq_fps, mut par_fps, mut pipe_fps) = (Vec::new(), Vec::new(), Vec::new());
    let (mut seq_poses, mut par_poses, mut pipe_poses, mut stats) = (None, None, None, None);
    for _ in 0..args.repeat {
        if args.only.as_deref() != Some("pipeline") {
            let (secs, poses) = sequential(&config, &frames, 1);
            seq_fps.push(n as f64 / secs);
            seq_poses = Some(poses);
            if args.threads > 1 && args.only.is_none() {
                let (secs, poses) = sequential(&config, &frames, args.threads);
                par_fps.push(n as f64 / secs);
                par_poses = Some(poses);
            }
        }
        if args.only.as_deref() != Some("sequential") {
            let (secs, poses, st) = pipeline(&config, &frames, args.threads);
            pipe_fps.push(n as f64 / secs);
            pipe_poses = Some(poses);
            stats = Some(st);
        }
    }
    if !seq_fps.is_empty() {
        println!(
            "sequential Odometry, 1 thread: {:7.2} frames/s (median of {})",
            median(seq_fps.clone()),
            seq_fps.len()
        );
    }
    if !par_fps.is_empty() {
        println!(
            "sequential Odometry, {} threads (ecvo-core's parallel loops only): {:7.2} frames/s (median of {})",
            args.threads,
            median(par_fps.clone()),
            par_fps.len()
        );
    }
    if let Some(st) = &stats {
        println!(
            "pipeline (offline), {} threads: {:7.2} frames/s (median of {})",
            args.threads,
            median(pipe_fps.clone()),
            pipe_fps.len()
        );
        println!(
            "  per frame: filter {:.2} ms (median {:.2}), tracker {:.2} ms (median {:.2}), \
             total {:.2} ms; queues max input {} tracker {}; motion estimations {}, references {:?}; \
             [A] computed ahead by the filter stage for {} frames, used for {}",
            st.filter.mean_ms,
            st.filter.median_ms,
            st.tracker.mean_ms,
            st.tracker.median_ms,
            st.wall_ms_per_frame,
            st.input_queue.max_depth,
            st.tracker_queue.max_depth,
            st.counters.motion_estimations,
            st.counters.references,
            st.ahead_computed,
            st.ahead_used,
        );
    }
    if !seq_fps.is_empty() && !pipe_fps.is_empty() {
        let seq = median(seq_fps);
        println!(
            "ratio pipeline/sequential (1 thread): {:.2}x",
            median(pipe_fps) / seq
        );
        if !par_fps.is_empty() {
            println!(
                "ratio sequential {} threads/sequential 1 thread: {:.2}x",
                args.threads,
                median(par_fps) / seq
            );
        }
        let seq_poses = seq_poses.as_deref().unwrap_or_default();
        let identical = same(seq_poses, pipe_poses.as_deref().unwrap_or_default())
            && par_poses.as_deref().is_none_or(|p| same(seq_poses, p));
        println!("poses identical bit for bit: {identical}");
        if !identical {
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}
