//! `memory::estimate` is an upper bound of what the sequential engine really
//! allocates: a counting global allocator records the peak of the bytes outstanding
//! while `Odometry` is created and tracks a moving procedural scene, at several sizes
//! from the documented minimum (8x8) to 1280x720, and the estimate must cover it (and
//! not be more than about twice it, so that a budget check means something). Also:
//! the budget refuses before allocating, and every size from the minimum runs without
//! a configuration error. The gyroscope's ring is part of the estimate: the frames
//! are tracked with a 400 Hz IMU stream, and what the first `push_imu` allocates is
//! checked against [`memory::imu_bytes`].

use std::sync::atomic::Ordering;

use ecvo_core::imu::GyroSample;
use ecvo_core::memory::{self, MB};
use ecvo_core::{Camera, Config, Error, FrameView, Mode, Odometry, Preset};

#[path = "support/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::{CURRENT, Counting, PEAK};

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The tests measure one process-wide counter: one at a time.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

fn camera(width: usize, height: usize) -> Camera {
    let f = 0.8 * width.max(height) as f64;
    Camera {
        width,
        height,
        fx: f,
        fy: f,
        cx: (width as f64 - 1.0) / 2.0,
        cy: (height as f64 - 1.0) / 2.0,
        depth_scale: 1000.0,
    }
}

/// A textured, curved wall seen by a camera sliding sideways: frame `k` shifts the
/// pattern by `k` pixels, so the tracker registers, corrects and replaces references.
fn frame(c: &Camera, k: usize) -> (Vec<u8>, Vec<u16>) {
    let (w, h) = (c.width, c.height);
    let s = 64.0 / w.max(h) as f64;
    let mut gray = Vec::with_capacity(w * h);
    let mut depth = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let u = (x + k) as f64 * s;
            let v = y as f64 * s;
            let g = 128.0
                + 50.0 * (u * 0.9).sin() * (v * 0.7).cos()
                + 30.0 * (u * 0.23 + v * 0.31).sin();
            gray.push(g.clamp(0.0, 255.0) as u8);
            depth.push((1500.0 + 200.0 * (u * 0.05).sin() + 100.0 * (v * 0.07).cos()) as u16);
        }
    }
    (gray, depth)
}

/// Peak bytes outstanding above the baseline while `run` runs.
fn peak_of(run: impl FnOnce()) -> usize {
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    run();
    PEAK.load(Ordering::Relaxed) - base
}

/// Gyro samples at 400 Hz from `t0` (inclusive) to `t1` (exclusive), turning slowly.
fn gyro(t0: f64, t1: f64) -> Vec<GyroSample> {
    let first = (t0 * 400.0).ceil() as usize;
    let last = (t1 * 400.0).ceil() as usize;
    (first..last)
        .map(|i| GyroSample {
            t: i as f64 / 400.0,
            w: [0.0, 0.01, 0.0],
        })
        .collect()
}

fn track(config: &Config, frames: &[(Vec<u8>, Vec<u16>)]) {
    let mut odo = Odometry::new(config.clone()).expect("a valid configuration");
    for (k, (g, d)) in frames.iter().enumerate() {
        // The gyro's samples up to the frame, as a sensor callback would give them.
        let t = k as f64 / 30.0;
        odo.push_imu(&gyro(t - 1.0 / 30.0, t + 0.001))
            .expect("finite samples");
        odo.push(FrameView {
            timestamp: k as f64 / 30.0,
            intensity: g,
            depth: d,
        })
        .expect("frames of the right size");
    }
    assert!(odo.frames_allocated() <= memory::max_prepared_frames(config));
}

#[test]
fn the_estimate_bounds_what_odometry_allocates() {
    let _serial = serial();
    // Warm rayon's global pool (its threads and queues are not the engine's).
    track(
        &Config::new(camera(64, 48), Preset::Phone, Mode::L2),
        &[frame(&camera(64, 48), 0)],
    );
    for (w, h) in [
        (8, 8),
        (64, 48),
        (8192, 8),
        (8, 2048),
        (320, 180),
        (640, 480),
        (1280, 720),
    ] {
        for (mode, lookup) in [
            (Mode::Naive, None),
            (Mode::L2, None),
            (Mode::L2, Some(ecvo_core::LookupDepth::Raw)),
        ] {
            let c = camera(w, h);
            let mut config = Config::new(c, Preset::Phone, mode);
            if let Some(d) = lookup {
                config.keyframes = true;
                config.lookup_depth = d;
            }
            let est = memory::estimate(&config);
            let frames: Vec<_> = (0..12).map(|k| frame(&c, k)).collect();
            let peak = peak_of(|| track(&config, &frames));
            println!(
                "{w}x{h} {mode:?}: estimate {} (frame {} x {}), peak {}",
                memory::format_mb(est.bytes),
                memory::format_mb(est.frame_bytes),
                est.frames,
                memory::format_mb(peak)
            );
            assert!(
                peak <= est.bytes,
                "{w}x{h} {mode:?}: peak {peak} above the estimate {est:?}"
            );
            // Tight enough to mean something where the image dominates.
            if w * h >= 320 * 180 {
                assert!(
                    est.bytes <= 2 * peak + memory::FIXED_BYTES,
                    "{w}x{h} {mode:?}: estimate {est:?} far above the peak {peak}"
                );
            }
        }
    }
}

#[test]
fn the_gyro_ring_is_counted_and_allocated_once() {
    let _serial = serial();
    let config = Config::new(camera(64, 48), Preset::Phone, Mode::L2);
    let est = memory::estimate(&config);
    assert_eq!(est.imu_bytes, memory::imu_bytes());
    assert_eq!(
        est.bytes,
        memory::with_margin(
            est.frames * est.frame_bytes + est.preparer_bytes + est.estimator_bytes + est.imu_bytes
        ),
        "the ring is in the total: {est:?}"
    );
    let mut odo = Odometry::new(config).expect("valid");
    let samples = gyro(0.0, 10.0);
    let base = CURRENT.load(Ordering::Relaxed);
    odo.push_imu(&samples[..10]).unwrap();
    let ring = CURRENT.load(Ordering::Relaxed) - base;
    // 4000 more samples wrap the ring several times: nothing more is allocated.
    odo.push_imu(&samples[10..]).unwrap();
    let all = CURRENT.load(Ordering::Relaxed) - base;
    println!(
        "gyro ring: {ring} bytes at the first push, {all} after {} samples; counted {}",
        samples.len(),
        est.imu_bytes
    );
    assert!(ring > 0, "the first push allocates the ring");
    assert_eq!(all, ring, "allocated once");
    assert!(
        ring <= est.imu_bytes && 2 * ring > est.imu_bytes,
        "ring {ring} bytes against {} counted",
        est.imu_bytes
    );
}

#[test]
fn odometry_refuses_above_its_budget_with_need_and_budget() {
    let _serial = serial();
    let mut config = Config::new(camera(4096, 4096), Preset::Phone, Mode::L2);
    let need = memory::estimate(&config).bytes;
    assert!(
        need > memory::DEFAULT_MEMORY_BUDGET,
        "4096x4096 needs {need}"
    );
    let before = CURRENT.load(Ordering::Relaxed);
    let err = Odometry::new(config.clone()).err().expect("refused");
    assert_eq!(
        err,
        Error::MemoryBudget {
            need,
            budget: memory::DEFAULT_MEMORY_BUDGET
        }
    );
    let msg = err.to_string();
    assert!(
        msg.contains("512.0 MB") && msg.contains(&memory::format_mb(need)),
        "{msg}"
    );
    // Nothing of the image's size was allocated to find that out.
    assert!(
        CURRENT.load(Ordering::Relaxed) < before + MB,
        "allocated before refusing"
    );
    config.memory_budget = need;
    assert!(Odometry::new(config).is_ok());
}

#[test]
fn every_size_from_the_minimum_configures() {
    for (w, h) in [
        (8, 8),
        (9, 8),
        (15, 15),
        (16, 16),
        (64, 48),
        (96, 72),
        (8192, 8),
        (8, 8192),
        (17, 8191),
    ] {
        let c = camera(w, h);
        for config in [
            Config::new(c, Preset::Phone, Mode::L2),
            Config::paper(c, Preset::Pc, Mode::L2),
        ] {
            config.validate().unwrap_or_else(|e| panic!("{w}x{h}: {e}"));
            let levels = &config.motion.levels;
            let deepest = levels.iter().map(|l| l.pyramid_level).max().unwrap();
            assert!(
                w >> deepest >= 8 && h >> deepest >= 8,
                "{w}x{h}: {levels:?}"
            );
        }
    }
    let c = camera(7, 8);
    match Odometry::new(Config::new(c, Preset::Phone, Mode::L2)) {
        Err(Error::InvalidConfig { field, why }) => {
            assert_eq!(field, "width/height");
            assert!(why.contains("7x8") && why.contains("8x8"), "{why}");
        }
        other => panic!("7x8 gave {:?}", other.err()),
    }
}
