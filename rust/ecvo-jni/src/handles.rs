//! The natives' handle operations without a JVM: what `nativeInit`, `nativePushArrays`,
//! `nativeFlush` and `nativeRelease` do once their arguments are converted, for the
//! Rust tests that count allocations (`tests/memory.rs`: a counting global allocator
//! cannot be installed in the JVM's process for the library alone).

use jni::sys::{jint, jlong};

use crate::config::InitArgs;
use crate::error::{Failure, bad};
use crate::tracker::{REGISTRY, init, lock, tracker};

/// `nativeInit`: a new tracker's handle.
pub fn open(args: &InitArgs) -> Result<jlong, Failure> {
    init(args)
}

/// `nativePushArrays` with Rust slices: depth in the tracker's depth format, gray
/// intensity, each `width * height`.
pub fn push(
    handle: jlong,
    timestamp_ns: jlong,
    depth: &[u16],
    gray: &[u8],
) -> Result<jint, Failure> {
    let t = tracker(handle)?;
    let (w, h) = t.size();
    if depth.len() != w * h || gray.len() != w * h {
        return Err(bad(format!(
            "depth/intensity: {} and {} values for a {w}x{h} frame",
            depth.len(),
            gray.len()
        )));
    }
    t.push(timestamp_ns, |i, d| {
        i.copy_from_slice(gray);
        d.copy_from_slice(depth);
        Ok(())
    })
}

/// `nativeFlush`.
pub fn flush(handle: jlong) -> Result<(), Failure> {
    Ok(tracker(handle)?.pipeline.flush()?)
}

/// `nativeRelease` (the Kotlin `Tracker.close` and its `Cleaner` both end here).
pub fn release(handle: jlong) {
    let removed = lock(&REGISTRY).remove(&handle);
    let released = removed
        .as_ref()
        .is_some_and(|t| std::sync::Arc::strong_count(t) == 1);
    drop(removed);
    if released {
        crate::tracker::give_back_memory();
    }
}

/// Trackers in the registry.
pub fn live_trackers() -> usize {
    lock(&REGISTRY).len()
}
