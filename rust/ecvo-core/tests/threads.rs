//! ecvo-core's parallel loops (MOTION's chunks, the filter's rows) give the same
//! poses, bit for bit, whatever the number of threads of the rayon pool they run in.

mod common;

use ecvo_core::motion::{CHUNK, MIN_CHUNKS_PER_TASK};
use ecvo_core::{FrameOutput, Mode, Odometry};
use ecvo_synth::{DepthNoise, SynthCamera, SynthSequence};

/// A noisy 640x480 stream: large enough that the loops are split between threads.
fn stream() -> SynthSequence {
    let mut s = SynthSequence::phone_320x180(40, 5);
    s.camera = SynthCamera::tum_640x480();
    s.noise = DepthNoise::kinect_like();
    s
}

fn run(seq: &SynthSequence, threads: usize) -> Vec<FrameOutput> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut odo = Odometry::new(common::config(seq, Mode::L2)).unwrap();
    pool.install(|| {
        (0..seq.frames)
            .map(|i| {
                let f = seq.frame(i);
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
    let seq = stream();
    let cfg = common::config(&seq, Mode::L2);
    // The finest step's template must be big enough for MOTION to split its loops,
    // or this test would compare the sequential path with itself.
    let (frame, _) = common::prepared(&seq, 0, &cfg);
    let finest = frame.templates.last().unwrap().points.len();
    assert!(
        finest >= 2 * MIN_CHUNKS_PER_TASK * CHUNK,
        "{finest} template points do not split"
    );
    let one = run(&seq, 1);
    assert!(
        one.iter().any(|o| o.reference_levels > 0),
        "the stream must exercise error correction"
    );
    for threads in [2, 3, 4] {
        let many = run(&seq, threads);
        for (i, (a, b)) in one.iter().zip(&many).enumerate() {
            assert_eq!(bits(&a.pose), bits(&b.pose), "frame {i}, {threads} threads");
            assert_eq!(a.state, b.state);
            assert_eq!(a.motion_estimations, b.motion_estimations);
            assert_eq!(a.reference_levels, b.reference_levels);
        }
    }
}
