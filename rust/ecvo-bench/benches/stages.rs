//! Criterion benches of the two per-frame stages on one thread: the filter stage
//! (`Preparer::prepare_into`; `prepare/` with the normals a point cloud reads,
//! `prepare-tracking/` without them, as the pipeline prepares without a geometry
//! stage) and frame-to-frame MOTION (`frame_to_frame`, the call
//! the tracker makes for [A], from the identity) at 320x180, 320x240 and 640x480.
//!
//! The frames are rendered by ecvo-synth (the standard room, a hand-held path, the
//! phone-like noise), so the benches run anywhere:
//!
//! ```text
//! cargo bench -p ecvo-bench --bench stages
//! cargo bench -p ecvo-bench --bench stages -- prepare/320x240
//! ```
//!
//! Everything runs inside a one-thread rayon pool: the figures are the cost of a
//! frame on one core, which is what the stages' loops split when they run wider.
//!
//! `ECVO_BENCH_SCHEDULE` (as `--schedule`) and `ECVO_BENCH_POINT_BUDGET` (as
//! `--point-budget`, e.g. `1=4096,0=4096`) change the config from the default, to
//! compare schedules with one bench binary.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use ecvo_core::{
    Camera, Config, FrameView, Mode, MotionEstimator, PreparedFrame, Preparer, Preset,
    frame_to_frame, tracker::working_motion,
};
use ecvo_synth::{SynthCamera, SynthFrame, SynthSequence};

/// The benched sizes: name and camera (the phone's, TUM's at half and full size).
fn cameras() -> Vec<(&'static str, SynthCamera)> {
    let tum = SynthCamera::tum_640x480();
    let half = SynthCamera {
        width: 320,
        height: 240,
        fx: tum.fx / 2.0,
        fy: tum.fy / 2.0,
        cx: (tum.cx + 0.5) / 2.0 - 0.5,
        cy: (tum.cy + 0.5) / 2.0 - 0.5,
        depth_scale: tum.depth_scale,
    };
    vec![
        ("320x180", SynthCamera::phone_320x180()),
        ("320x240", half),
        ("640x480", tum),
    ]
}

fn camera_of(c: &SynthCamera) -> Camera {
    Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    }
}

fn view(f: &SynthFrame) -> FrameView<'_> {
    FrameView {
        timestamp: f.timestamp,
        intensity: &f.intensity,
        depth: &f.depth,
    }
}

/// Two consecutive frames of a hand-held sequence with camera `cam`, and its config.
fn frames(cam: SynthCamera) -> (Config, SynthFrame, SynthFrame) {
    let mut seq = SynthSequence::phone_320x180(40, 7);
    seq.camera = cam;
    let mut config = Config::new(camera_of(&cam), Preset::Pc, Mode::L2);
    if let Ok(s) = std::env::var("ECVO_BENCH_SCHEDULE") {
        config.motion.levels =
            ecvo_core::parse_schedule(&s, &config.camera).expect("ECVO_BENCH_SCHEDULE");
    }
    if let Ok(s) = std::env::var("ECVO_BENCH_POINT_BUDGET") {
        for (level, points) in ecvo_core::parse_point_budget(&s).expect("ECVO_BENCH_POINT_BUDGET") {
            config.motion.set_point_budget(level, points);
        }
    }
    config.validate().expect("a valid bench config");
    (config, seq.frame(20), seq.frame(21))
}

fn benches(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    for (name, cam) in cameras() {
        let (config, prev, cur) = frames(cam);
        let mut preparer = Preparer::new(&config);
        let mut fp = PreparedFrame::for_config(&config);
        let mut fc = PreparedFrame::for_config(&config);
        pool.install(|| {
            preparer.prepare_into(view(&prev), &mut fp).unwrap();
            preparer.prepare_into(view(&cur), &mut fc).unwrap();
        });

        let mut group = c.benchmark_group("prepare");
        group.bench_function(name, |b| {
            let mut out = PreparedFrame::for_config(&config);
            pool.install(|| {
                b.iter(|| {
                    preparer.prepare_into(view(&cur), &mut out).unwrap();
                    black_box(out.valid_depth)
                })
            })
        });
        group.finish();

        // The tracking path: no normals (what the pipeline prepares without a
        // geometry stage: `ecvo run`, Python, JNI without a point cloud).
        let mut tracking = preparer.clone();
        tracking.set_normals(false);
        let mut group = c.benchmark_group("prepare-tracking");
        group.bench_function(name, |b| {
            let mut out = PreparedFrame::for_config(&config);
            pool.install(|| {
                b.iter(|| {
                    tracking.prepare_into(view(&cur), &mut out).unwrap();
                    black_box(out.valid_depth)
                })
            })
        });
        group.finish();

        let mut group = c.benchmark_group("motion");
        // The tracker's settings: with the fitted depth-noise model, its starting model
        // and the depth spread measured.
        let motion = working_motion(&config.motion);
        group.bench_function(name, |b| {
            let mut estimator = MotionEstimator::new();
            pool.install(|| {
                b.iter(|| {
                    let r = frame_to_frame(&mut estimator, &fc, &fp, None, &motion);
                    black_box(r.pose)
                })
            })
        });
        group.finish();
    }
}

criterion_group!(stages, benches);
criterion_main!(stages);
