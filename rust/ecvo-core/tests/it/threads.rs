//! ecvo-core's parallel loops (MOTION's chunks, the filter's rows) give the same
//! poses, bit for bit, whatever the number of threads of the rayon pool they run in.

use crate::common;

use ecvo_core::motion::{CHUNK, MIN_CHUNKS_PER_TASK};
use ecvo_core::{Config, FrameOutput, Mode, Odometry, ReferenceLevel};
use ecvo_synth::{DepthNoise, SynthCamera, SynthSequence};

/// A noisy 640x480 stream, rendered once: large enough that the loops are split
/// between threads.
fn stream() -> (SynthSequence, Vec<ecvo_synth::SynthFrame>) {
    let mut s = SynthSequence::phone_320x180(24, 5);
    s.camera = SynthCamera::tum_640x480();
    s.noise = DepthNoise::kinect_like();
    let frames = (0..s.frames).map(|i| s.frame(i)).collect();
    (s, frames)
}

fn run(cfg: &Config, frames: &[ecvo_synth::SynthFrame], threads: usize) -> Vec<FrameOutput> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut odo = Odometry::new(cfg.clone()).unwrap();
    pool.install(|| {
        frames
            .iter()
            .map(|f| {
                odo.push(ecvo_core::FrameView {
                    timestamp: f.timestamp,
                    intensity: &f.intensity,
                    depth: &f.depth,
                })
                .unwrap()
            })
            .collect()
    })
}

fn bits(p: &ecvo_core::Pose) -> Vec<u64> {
    p.to_homogeneous().iter().map(|v| v.to_bits()).collect()
}

#[test]
fn poses_do_not_depend_on_the_thread_count() {
    let (seq, frames) = stream();
    let mut cfg = common::config(&seq, Mode::L2);
    // Tight reference levels, so that a short stream corrects at both levels.
    cfg.reference_levels = vec![
        ReferenceLevel::mm_deg(10.0, 1.0),
        ReferenceLevel::mm_deg(30.0, 3.0),
    ];
    // The finest step's template must be big enough for MOTION to split its loops,
    // or this test would compare the sequential path with itself.
    let (frame, _) = common::prepared(&seq, 0, &cfg);
    let finest = frame.templates.last().unwrap().points.len();
    assert!(
        finest >= 2 * MIN_CHUNKS_PER_TASK * CHUNK,
        "{finest} template points do not split"
    );
    let one = run(&cfg, &frames, 1);
    assert!(
        one.iter().any(|o| o.reference_levels > 1),
        "the stream must exercise both levels of error correction"
    );
    // 3 threads split unevenly, 4 more finely than 2 would.
    for threads in [3, 4] {
        let many = run(&cfg, &frames, threads);
        for (i, (a, b)) in one.iter().zip(&many).enumerate() {
            assert_eq!(bits(&a.pose), bits(&b.pose), "frame {i}, {threads} threads");
            assert_eq!(a.state, b.state);
            assert_eq!(a.motion_estimations, b.motion_estimations);
            assert_eq!(a.reference_levels, b.reference_levels);
        }
    }
}
