//! The frame pool: prepared frames shared between stages by reference counting
//! (the paper's "Frame Pool", section 4.1).
//!
//! The pool keeps one `Arc` of every slot, all created when the pool is. A slot is free when that
//! is the only `Arc` left: every other holder (a queue, the tracker's previous or
//! reference frame, the geometry stage) holds a [`PooledFrame`], and dropping the last
//! one makes the slot free again without freeing its buffers. Nobody can clone a
//! handle to a slot that no handle points to, so "the pool's `Arc` is the only one" is
//! a stable observation under the pool's lock. A slot is handed to the filter
//! exclusively (removed from the pool while it is being written), so writing needs no
//! `unsafe`. The number of slots is fixed, so nothing is allocated after start-up.

use std::ops::Deref;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use ecvo_core::PreparedFrame;

use crate::queue::lock;
use crate::stats::PoolStats;

/// What the pipeline knows about a frame besides its prepared images.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameMeta {
    /// Position of the frame among the frames pushed (accepted or not), from 0.
    pub sequence: u64,
    /// When `push` was called.
    pub pushed_at: Instant,
    /// \[A\] for this frame, computed by the filter stage while the tracker was behind.
    pub ahead: Option<Ahead>,
    /// The filter stage's time on this frame (\[A\] computed ahead left out).
    pub filtered_in: Duration,
    /// The same as CPU time of the compute thread.
    pub filtered_cpu: Duration,
    /// IMU samples pushed before the frame.
    pub imu_upto: u64,
}

/// `frame_to_frame(this frame, the frame of sequence `against`, prior)`, computed
/// ahead.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ahead {
    /// Sequence of the previous frame it registered against.
    pub against: u64,
    /// The constant-velocity prediction it started from (besides the identity).
    pub prior: Option<ecvo_core::Pose>,
    /// The depth-noise model it used.
    pub depth_noise: ecvo_core::DepthNoiseModel,
    /// The result.
    pub result: ecvo_core::MotionResult,
    /// How long computing it took on the filter stage's thread: booked to the tracker
    /// stage's time, not the filter's (used or discarded, it is the tracker's work).
    pub took: std::time::Duration,
    /// The same as CPU time of the thread that computed it.
    pub took_cpu: std::time::Duration,
}

/// One pooled frame.
#[derive(Debug)]
pub(crate) struct Slot {
    pub frame: PreparedFrame,
    pub meta: FrameMeta,
}

struct Inner {
    /// The pool's own reference to every slot that is not being written.
    slots: Vec<Arc<Slot>>,
    /// Slots in the pool (all created at start-up).
    allocated: usize,
    /// Most slots in use at once (allocated and not free).
    max_in_use: usize,
}

/// A bounded pool of reusable prepared frames.
pub(crate) struct FramePool {
    inner: Mutex<Inner>,
    freed: Condvar,
    capacity: usize,
}

/// A shared handle to a pooled prepared frame: cloning it shares the frame, and the
/// frame returns to the pool (its buffers kept for reuse) when the last handle is
/// dropped. This is the handle type the tracker keeps as previous and reference
/// frame.
pub struct PooledFrame {
    slot: Option<Arc<Slot>>,
    pool: Arc<FramePool>,
}

impl PooledFrame {
    fn slot(&self) -> &Slot {
        self.slot.as_ref().expect("a live handle has its slot")
    }

    /// Position of the frame among the frames pushed, from 0.
    pub fn sequence(&self) -> u64 {
        self.slot().meta.sequence
    }

    pub(crate) fn meta(&self) -> FrameMeta {
        self.slot().meta
    }
}

impl Clone for PooledFrame {
    fn clone(&self) -> Self {
        PooledFrame {
            slot: self.slot.clone(),
            pool: self.pool.clone(),
        }
    }
}

impl Deref for PooledFrame {
    type Target = PreparedFrame;
    fn deref(&self) -> &PreparedFrame {
        &self.slot().frame
    }
}

impl std::fmt::Debug for PooledFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PooledFrame")
            .field("sequence", &self.sequence())
            .field("timestamp", &self.timestamp)
            .finish()
    }
}

impl Drop for PooledFrame {
    fn drop(&mut self) {
        // Let go of the slot first, then wake a filter that may wait for a free one.
        drop(self.slot.take());
        let _g = lock(&self.pool.inner);
        self.pool.freed.notify_one();
    }
}

impl FramePool {
    /// A pool of `capacity` slots (at least 1), all created now with `make`, so that a
    /// running pipeline never allocates a frame: which slots a run needs depends on
    /// thread timing, and a slot first used late would otherwise allocate late.
    pub(crate) fn new(capacity: usize, make: impl Fn() -> PreparedFrame) -> Arc<Self> {
        let capacity = capacity.max(1);
        let slots: Vec<Arc<Slot>> = (0..capacity)
            .map(|_| {
                Arc::new(Slot {
                    frame: make(),
                    meta: FrameMeta {
                        sequence: 0,
                        pushed_at: Instant::now(),
                        ahead: None,
                        filtered_in: Duration::ZERO,
                        filtered_cpu: Duration::ZERO,
                        imu_upto: 0,
                    },
                })
            })
            .collect();
        Arc::new(FramePool {
            inner: Mutex::new(Inner {
                slots,
                allocated: capacity,
                max_in_use: 0,
            }),
            freed: Condvar::new(),
            capacity,
        })
    }

    fn in_use(inner: &Inner) -> usize {
        let free = inner
            .slots
            .iter()
            .filter(|s| Arc::strong_count(s) == 1)
            .count();
        inner.allocated - free
    }

    /// A free slot, exclusively owned by the caller (its `Arc` has no other
    /// reference), waiting while every slot is in use; `None` once `abort` is set.
    pub(crate) fn acquire(&self, abort: &AtomicBool) -> Option<Arc<Slot>> {
        let mut g = lock(&self.inner);
        loop {
            if abort.load(Ordering::Acquire) {
                return None;
            }
            if let Some(i) = g.slots.iter().position(|s| Arc::strong_count(s) == 1) {
                let slot = g.slots.swap_remove(i);
                let in_use = Self::in_use(&g);
                g.max_in_use = g.max_in_use.max(in_use);
                return Some(slot);
            }
            // Handles notify when dropped; the timeout only guards against a missed
            // wake-up racing with `abort`.
            g = self
                .freed
                .wait_timeout(g, Duration::from_millis(50))
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// Puts a written slot back under the pool's management and hands out the first
    /// shared handle to it.
    pub(crate) fn share(self: &Arc<Self>, slot: Arc<Slot>) -> PooledFrame {
        lock(&self.inner).slots.push(slot.clone());
        PooledFrame {
            slot: Some(slot),
            pool: self.clone(),
        }
    }

    /// Puts an unused slot back.
    pub(crate) fn give_back(&self, slot: Arc<Slot>) {
        lock(&self.inner).slots.push(slot);
        self.freed.notify_one();
    }

    /// Wakes every waiter (on abort).
    pub(crate) fn wake_all(&self) {
        let _g = lock(&self.inner);
        self.freed.notify_all();
    }

    /// Occupancy now.
    pub(crate) fn stats(&self) -> PoolStats {
        let g = lock(&self.inner);
        PoolStats {
            capacity: self.capacity,
            allocated: g.allocated,
            in_use: Self::in_use(&g),
            max_in_use: g.max_in_use,
        }
    }
}
