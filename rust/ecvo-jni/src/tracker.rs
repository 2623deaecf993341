//! A tracker behind a handle: the registry of live trackers and the push of one frame.

use std::collections::{BTreeMap, VecDeque};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use ecvo_pipeline::{Pipeline, PushStatus};
use jni::sys::{jint, jlong};

use crate::config::InitArgs;
use crate::depth16::Depth16Decoder;
use crate::error::Failure;
#[cfg(feature = "test-hooks")]
use crate::layout::TEST_PANIC_TIMESTAMP_NS;
use crate::layout::{DepthFormat, NO_POSE, ns_to_seconds};

/// One tracker behind a handle.
pub struct NativeTracker {
    pub(crate) pipeline: Pipeline,
    width: usize,
    height: usize,
    format: DepthFormat,
    depth16: Depth16Decoder,
    /// Recent (seconds bits, nanoseconds) pairs, so that `nativeGetPose` returns the
    /// exact nanosecond timestamp that was pushed.
    stamps: Mutex<VecDeque<(u64, jlong)>>,
    /// Its place under [`crate::limits::MAX_LIVE_TRACKERS`], given back when it drops.
    _slot: crate::limits::Slot,
}

/// Pushed timestamps remembered for `nativeGetPose` (far more than the frames the
/// pipeline holds at once).
const STAMPS_KEPT: usize = 64;

pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

pub(crate) static REGISTRY: Mutex<BTreeMap<jlong, Arc<NativeTracker>>> =
    Mutex::new(BTreeMap::new());
static NEXT_HANDLE: AtomicI64 = AtomicI64::new(1);

pub(crate) fn tracker(handle: jlong) -> Result<Arc<NativeTracker>, Failure> {
    if handle == 0 {
        return Err(Failure::IllegalState("tracker handle is 0 (closed)".into()));
    }
    lock(&REGISTRY).get(&handle).cloned().ok_or_else(|| {
        Failure::IllegalState(format!("tracker handle {handle} is released or unknown"))
    })
}

pub(crate) fn init(args: &InitArgs) -> Result<jlong, Failure> {
    let (config, options, format, confidence) = args.build()?;
    let (width, height) = (config.camera.width, config.camera.height);
    let slot = crate::limits::reserve()?;
    let pipeline = Pipeline::new(config, options)?;
    let t = Arc::new(NativeTracker {
        pipeline,
        width,
        height,
        format,
        depth16: Depth16Decoder::new(confidence),
        stamps: Mutex::new(VecDeque::with_capacity(STAMPS_KEPT)),
        _slot: slot,
    });
    let handle = NEXT_HANDLE.fetch_add(1, Ordering::Relaxed);
    lock(&REGISTRY).insert(handle, t);
    log::info!(
        "ecvo-jni: tracker {handle} started ({width}x{height}, {format:?}, {:?})",
        args
    );
    Ok(handle)
}

impl NativeTracker {
    /// Frame width and height in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Pushes one frame; `fill` copies raw depth and intensity into the pooled buffers.
    pub(crate) fn push(
        &self,
        timestamp_ns: jlong,
        fill: impl FnOnce(&mut [u8], &mut [u16]) -> Result<(), Failure>,
    ) -> Result<jint, Failure> {
        #[cfg(feature = "test-hooks")]
        if timestamp_ns == TEST_PANIC_TIMESTAMP_NS {
            panic!("ecvo-jni test hook: injected panic");
        }
        if timestamp_ns == NO_POSE {
            return Err(Failure::IllegalArgument(format!(
                "timestampNs: {timestamp_ns} (Long.MIN_VALUE) is NO_POSE, the \"no pose yet\" of getPose, not a timestamp"
            )));
        }
        let seconds = ns_to_seconds(timestamp_ns);
        let mut result = Ok(());
        let format = self.format;
        // Compared with the previous frame's as integer nanoseconds.
        let status = self.pipeline.push_ns(timestamp_ns, |i, d| {
            result = fill(i, d);
            if result.is_err() {
                // The buffer must be overwritten entirely whatever happens.
                i.fill(0);
                d.fill(0);
            } else if format == DepthFormat::Depth16 {
                self.depth16.decode_in_place(d);
            }
        })?;
        result?;
        {
            let mut s = lock(&self.stamps);
            if s.len() == STAMPS_KEPT {
                s.pop_front();
            }
            s.push_back((seconds.to_bits(), timestamp_ns));
        }
        Ok(match status {
            PushStatus::Accepted => 0,
            PushStatus::DroppedOldest => 1,
            PushStatus::Repeated => 2,
        })
    }

    /// The nanosecond timestamp that was pushed as `seconds`.
    pub(crate) fn stamp_ns(&self, seconds: f64) -> jlong {
        let bits = seconds.to_bits();
        lock(&self.stamps)
            .iter()
            .rev()
            .find(|(b, _)| *b == bits)
            .map_or_else(|| (seconds * 1e9).round() as jlong, |(_, ns)| *ns)
    }
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
unsafe extern "C" {
    /// glibc: returns free memory of every malloc arena to the system.
    fn malloc_trim(pad: usize) -> i32;
}

/// After a tracker's release: hands the memory its threads freed back to the system.
/// glibc keeps freed memory in its arenas (the main heap and one per thread that
/// allocated), so without this the RSS after each round of "10 trackers, one frame each,
/// released" grew from 20 MB to 705 MB over 30 rounds (`--example rounds`); with it,
/// from 9 to 51 MB, the rest in the tops of the per-thread arenas, which `malloc_trim`
/// does not shrink. The large blocks are now mappings of their own ([`crate::blocks`]),
/// so this only concerns the small ones. Other C libraries (Android's bionic) manage
/// their own.
pub(crate) fn give_back_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks glibc's own arenas; it is thread-safe.
    unsafe {
        malloc_trim(0);
    }
}
