//! The state the stages and the caller share: raw-frame pool, queues, progress,
//! timers, the published poses, and the input checks.

use super::*;

/// One raw input frame in the input pool.
pub(crate) struct RawFrame {
    pub(crate) sequence: u64,
    pub(crate) timestamp: f64,
    pub(crate) pushed_at: Instant,
    pub(crate) intensity: Vec<u8>,
    pub(crate) depth: Vec<u16>,
    /// The intrinsics in force when it was pushed ([`crate::Pipeline::set_intrinsics`]).
    pub(crate) camera: Camera,
    /// IMU samples pushed before it ([`crate::Pipeline::push_imu`]).
    pub(crate) imu_upto: u64,
    /// Its depth's time against its intensity's
    /// ([`crate::Pipeline::push_with_depth_time`]).
    pub(crate) depth_time: ecvo_core::imu::DepthTime,
}

pub(crate) struct RawPool {
    pub(crate) free: Vec<RawFrame>,
    /// Buffers allocated beyond the pool's size in live mode (more threads pushing at
    /// once than it has room for); freed as they come back.
    pub(crate) extra: usize,
    /// How many such buffers were ever allocated.
    pub(crate) allocated: u64,
    /// The stream's camera, to allocate one.
    pub(crate) camera: Camera,
}

impl RawPool {
    pub(crate) fn new(count: usize, camera: Camera) -> RawPool {
        RawPool {
            free: (0..count).map(|_| RawFrame::new(camera)).collect(),
            extra: 0,
            allocated: 0,
            camera,
        }
    }
}

impl RawFrame {
    fn new(camera: Camera) -> RawFrame {
        RawFrame {
            sequence: 0,
            timestamp: 0.0,
            pushed_at: Instant::now(),
            intensity: vec![0; camera.pixels()],
            depth: vec![0; camera.pixels()],
            camera,
            imu_upto: 0,
            depth_time: ecvo_core::imu::DepthTime::Same,
        }
    }
}

/// A reference frame on its way to the geometry stage.
pub(crate) struct GeometryItem {
    pub(crate) frame: PooledFrame,
    pub(crate) pose: Pose,
}

#[derive(Clone, Copy, Default)]
pub(crate) struct Progress {
    pub(crate) pushed: u64,
    pub(crate) tracked: u64,
    pub(crate) dropped_at_input: u64,
    pub(crate) dropped_at_tracker: u64,
    pub(crate) failed_preparations: u64,
    pub(crate) geometry_sent: u64,
    pub(crate) geometry_done: u64,
    pub(crate) geometry_skipped: u64,
    pub(crate) outputs_discarded: u64,
    pub(crate) ahead_computed: u64,
    pub(crate) ahead_used: u64,
    pub(crate) timestamps_rejected: u64,
    pub(crate) repeated_frames: u64,
    pub(crate) intrinsics_changes: u64,
    pub(crate) first_push: Option<Instant>,
    pub(crate) last_tracked: Option<Instant>,
}

impl Progress {
    /// Frames that need nothing more from the filter and tracker.
    pub(crate) fn settled(&self) -> u64 {
        self.tracked + self.dropped_at_input + self.dropped_at_tracker + self.failed_preparations
    }
}

#[derive(Default)]
pub(crate) struct Timers {
    pub(crate) filter: Mutex<Histogram>,
    pub(crate) tracker: Mutex<Histogram>,
    pub(crate) work: Mutex<Histogram>,
    pub(crate) work_cpu: Mutex<Histogram>,
    pub(crate) geometry: Mutex<Histogram>,
    pub(crate) latency: Mutex<Histogram>,
}

/// State shared by the caller and the stage threads.
pub(crate) struct Shared {
    pub(crate) camera: Camera,
    pub(crate) levels: usize,
    pub(crate) admission: Admission,
    pub(crate) geometry: Option<GeometryOptions>,
    pub(crate) keep_trajectory: bool,
    #[cfg(any(test, feature = "test-hooks"))]
    pub(crate) hooks: TestHooks,

    pub(crate) abort: AtomicBool,
    pub(crate) input_closed: AtomicBool,
    pub(crate) failure: Mutex<Option<Error>>,
    pub(crate) next_sequence: AtomicU64,
    /// The last frame accepted by `push`: its timestamp and content hash.
    pub(crate) last_input: Mutex<LastInput>,

    pub(crate) raw: Mutex<RawPool>,
    pub(crate) raw_freed: Condvar,
    pub(crate) input: Queue<RawFrame>,
    pub(crate) prepared: Queue<PooledFrame>,
    pub(crate) to_geometry: Queue<GeometryItem>,
    pub(crate) frames: Arc<FramePool>,

    pub(crate) progress: Mutex<Progress>,
    pub(crate) progress_changed: Condvar,
    pub(crate) latest: Mutex<LatestPose>,
    /// The tracker's velocity after its last frame: that frame's sequence and \[A\]
    /// (motion and interval) when it registered frame to frame. The filter stage
    /// restarts its \[A\]-ahead chain from it.
    pub(crate) velocity: Mutex<Published>,
    /// The depth-noise model the tracker uses after its last frame (it changes under
    /// `DepthNoiseModel::Fitted`): \[A\] computed ahead must use it.
    pub(crate) depth_noise: Mutex<ecvo_core::DepthNoiseModel>,
    pub(crate) counters: Mutex<Counters>,
    /// IMU samples pushed and not yet known to be read ([`crate::Pipeline::push_imu`]).
    pub(crate) imu: Mutex<crate::imu::ImuInbox>,
    /// The kept poses and reference records (`keep_trajectory`).
    pub(crate) poses: Mutex<PoseLog>,
    pub(crate) cloud: Option<Mutex<Cloud>>,
    pub(crate) timers: Timers,
}

/// What `push` remembers of the last frame it accepted (queued or repeated).
pub(crate) struct LastInput {
    /// The intrinsics frames pushed from now on carry.
    pub(crate) camera: Camera,
    pub(crate) timestamp: Option<f64>,
    /// The last accepted timestamp in nanoseconds, when it came through `push_ns`.
    pub(crate) timestamp_ns: Option<i64>,
    pub(crate) hash: Option<u64>,
}

/// A 64-bit hash of a frame's intensity and depth, to tell a frame bit-identical to
/// the previous one (two different frames collide with probability about 2^-64). Four
/// independent lanes of multiply-rotate over 8-byte words.
pub fn frame_hash(intensity: &[u8], depth: &[u16]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut lanes = [K, K ^ 1, K ^ 2, K ^ 3];
    let mut mix = |i: usize, w: u64| {
        lanes[i & 3] = (lanes[i & 3] ^ w).wrapping_mul(K).rotate_left(29);
    };
    let words = intensity.chunks_exact(8);
    let tail = words.remainder();
    let mut n = 0;
    for w in words {
        mix(
            n,
            u64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]),
        );
        n += 1;
    }
    for &b in tail {
        mix(n, u64::from(b) | 1 << 63);
        n += 1;
    }
    let words = depth.chunks_exact(4);
    let tail = words.remainder();
    for w in words {
        mix(
            n,
            u64::from(w[0]) | u64::from(w[1]) << 16 | u64::from(w[2]) << 32 | u64::from(w[3]) << 48,
        );
        n += 1;
    }
    for &d in tail {
        mix(n, u64::from(d) | 1 << 62);
        n += 1;
    }
    let h = lanes.iter().fold(
        intensity.len() as u64 ^ (depth.len() as u64) << 32,
        |h, &l| (h ^ l).wrapping_mul(K).rotate_left(31),
    );
    h ^ h >> 32
}

impl Shared {
    /// Fails (and counts) if `timestamp` is not after the last accepted frame's.
    /// Refuses a timestamp not after the last accepted one: in integer nanoseconds
    /// when both came with them (`push_ns`), in seconds otherwise.
    pub(crate) fn check_timestamp(
        &self,
        last: &LastInput,
        timestamp: f64,
        timestamp_ns: Option<i64>,
    ) -> Result<()> {
        if let (Some(previous_ns), Some(ns)) = (last.timestamp_ns, timestamp_ns) {
            if ns <= previous_ns {
                self.update_progress(|p| p.timestamps_rejected += 1);
                return Err(Error::TimestampNsNotIncreasing {
                    previous_ns,
                    timestamp_ns: ns,
                });
            }
            return Ok(());
        }
        match last.timestamp {
            Some(previous) if timestamp <= previous => {
                self.update_progress(|p| p.timestamps_rejected += 1);
                Err(Error::TimestampNotIncreasing {
                    previous,
                    timestamp,
                })
            }
            _ => Ok(()),
        }
    }

    pub(crate) fn aborted(&self) -> bool {
        self.abort.load(Ordering::Acquire)
    }

    /// The error to report once the pipeline no longer takes frames.
    pub(crate) fn stopped_error(&self) -> Error {
        lock(&self.failure).clone().unwrap_or(Error::Closed)
    }

    pub(crate) fn check_failure(&self) -> Result<()> {
        match &*lock(&self.failure) {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }

    pub(crate) fn update_progress(&self, f: impl FnOnce(&mut Progress)) {
        f(&mut lock(&self.progress));
        self.progress_changed.notify_all();
    }

    /// Stops everything: no stage waits for another once this returns.
    pub(crate) fn abort(&self) {
        self.abort.store(true, Ordering::Release);
        self.input.close();
        self.prepared.close();
        self.to_geometry.close();
        self.frames.wake_all();
        {
            let _g = lock(&self.raw);
            self.raw_freed.notify_all();
        }
        self.update_progress(|_| {});
    }

    pub(crate) fn fail(&self, stage: Stage, message: String) {
        log::error!("ecvo-pipeline: the {stage} stage panicked: {message}");
        lock(&self.failure).get_or_insert(Error::StagePanicked { stage, message });
        self.abort();
    }

    /// A free raw frame. Offline, waits for one. Live, never waits: when none is free
    /// (only with more threads pushing at once than the pool has room for: one
    /// pusher needs at most `queue + 2` of its `queue + 3`), it allocates one, freed
    /// when it comes back. A frame is dropped only once the new one is known to be
    /// queued (not repeated), so every drop is reported to the pusher that caused it.
    pub(crate) fn take_raw(&self) -> Result<RawFrame> {
        let mut g = lock(&self.raw);
        loop {
            if self.aborted() || self.input_closed.load(Ordering::Acquire) {
                return Err(self.stopped_error());
            }
            if let Some(r) = g.free.pop() {
                return Ok(r);
            }
            if self.admission == Admission::Live {
                g.extra += 1;
                g.allocated += 1;
                return Ok(RawFrame::new(g.camera));
            }
            g = self
                .raw_freed
                .wait_timeout(g, Duration::from_millis(50))
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    pub(crate) fn give_raw(&self, raw: RawFrame) {
        let mut g = lock(&self.raw);
        if g.extra > 0 {
            g.extra -= 1;
            drop(g);
            drop(raw);
            return;
        }
        g.free.push(raw);
        drop(g);
        self.raw_freed.notify_one();
    }

    #[cfg(any(test, feature = "test-hooks"))]
    pub(crate) fn hook(&self, stage: Stage, sequence: u64) {
        if let Some((s, d)) = self.hooks.delay
            && s == stage
        {
            std::thread::sleep(d);
        }
        if self.hooks.panic_at == Some((stage, sequence)) {
            panic!("injected panic in the {stage} stage at frame {sequence}");
        }
    }

    #[cfg(not(any(test, feature = "test-hooks")))]
    #[inline(always)]
    pub(crate) fn hook(&self, _stage: Stage, _sequence: u64) {}
}

/// Returns raw frames to the pool if `fill` panics.
pub(crate) struct RawGuard<'a> {
    pub(crate) shared: &'a Shared,
    pub(crate) raw: Option<RawFrame>,
}

impl Drop for RawGuard<'_> {
    fn drop(&mut self) {
        if let Some(r) = self.raw.take() {
            self.shared.give_raw(r);
        }
    }
}

/// Counts the rayon workers still alive, so that dropping the pipeline can wait
/// for them (a dropped `rayon::ThreadPool` does not join its threads).
pub(crate) struct WorkerCount {
    pub(crate) alive: Mutex<usize>,
    pub(crate) exited: Condvar,
}
