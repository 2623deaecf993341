//! # ecvo-jni
//!
//! `libecvo_jni.so`: the JNI bridge between the Android tracker
//! (`android-app/tracker`, Kotlin `io.ecvo.NativeBridge`) and [`ecvo_pipeline`].
//! A thin layer: it converts codes and buffers, and turns every error and panic into a
//! Java exception.
//!
//! ## The native methods
//!
//! The 19 `@JvmStatic external fun` of `NativeBridge.kt` are declared once each with
//! jni 0.22's `native_method!` (see [`NATIVE_METHODS`]): the macro checks at compile
//! time that each Rust implementation matches the JNI signature written next to it,
//! and exports it under its short JNI name (`Java_io_ecvo_NativeBridge_nativeInit`,
//! ...), which is what `scripts/android/check-so.sh` looks for. [`declared_signatures`]
//! lists the same names and signatures, and `tests/it/signatures.rs` compares them with
//! the declarations parsed from `NativeBridge.kt`, so Kotlin and Rust cannot drift
//! apart silently.
//!
//! ## Handles and concurrency
//!
//! A tracker lives in a process-wide **registry** (`Mutex<BTreeMap<jlong,
//! Arc<NativeTracker>>>`); its handle is a registry key from a counter that starts at 1
//! and is never reused, so a handle is never 0 and a stale or made-up handle is an
//! `IllegalStateException`, never a dangling pointer. Every call locks the registry
//! only to clone the tracker's `Arc`, then works without it; `nativeRelease` removes
//! the entry and drops its `Arc`. A release racing with a call on another thread is
//! therefore safe: the call keeps the tracker alive until it returns, and the pipeline
//! (whose drop joins its threads) goes away with the last `Arc`. Releasing an unknown
//! or already released handle does nothing (the Kotlin `Tracker` never does it; its
//! read-write lock also makes `close` wait for calls in progress).
//!
//! [`ecvo_pipeline::Pipeline`] is `Send + Sync`: the camera thread pushes while the UI
//! thread reads the pose. `nativeGetPose` copies a small struct under a mutex the
//! tracker holds only to overwrite it, so neither side blocks the other for long.
//!
//! ## Frames
//!
//! Direct `ByteBuffer`s are read from their `position()` to their `limit()` (which must
//! hold the plane; bytes after it are ignored), as planes ([`PlaneLayout`]): `nativePushBuffers` takes packed rows,
//! `nativePushStrided` rows a given number of bytes apart, as `ImageReader` planes with
//! padding are (the last row need not be padded; a stride shorter than a row or a buffer
//! shorter than the plane is an `IllegalArgumentException` naming the buffer). Depth
//! holds 16-bit samples **little-endian** (native order on every Android ABI, and the
//! order of `ImageReader` planes): a depth buffer whose `order()` is not
//! `LITTLE_ENDIAN` is refused (`ByteBuffer.allocateDirect` is big-endian by default);
//! intensity is 8-bit gray. `position()`, `limit()` and `order()` are called through
//! method IDs looked up once. Arrays hold exactly
//! `width * height` values. The data is copied into a pooled frame inside
//! [`ecvo_pipeline::Pipeline::push`]'s fill closure; no pointer is kept after the call.
//! A push returns 0 (queued), 1 (queued, an older waiting frame dropped: live mode) or
//! 2 (bit-identical to the previous frame: not tracked, see
//! [`ecvo_pipeline::PushStatus::Repeated`]).
//! `DEPTH16` samples are decoded while copying ([`Depth16Decoder`], with the
//! [`Confidence`] rule `minConfidence` chose: a level 0..=7, or -1 for auto).
//!
//! ## Modules
//!
//! `natives` (the method table and wrappers), `config` (`nativeInit`'s arguments),
//! `imu` (gyroscope samples: `nativePushImu`, `nativePushImuBatch`),
//! `tracker` (handles and the registry), `frames` (buffers and arrays), `depth16`,
//! `layout` (code tables and array layouts shared with Kotlin), `error` (the one
//! mapping of failures to Java exceptions), `blocks` (the library's allocator: large
//! blocks mapped and unmapped on their own, so that release gives them back).
//!
//! ## Errors
//!
//! `IllegalArgumentException` for bad input (the message names the field; a push
//! whose timestamp is not after the previous accepted frame's is one: the frame is not
//! tracked, later frames are),
//! `IllegalStateException` for a released handle or a closed pipeline,
//! `RuntimeException` for a stage failure or a caught panic (`native_method!` wraps
//! every call in `catch_unwind`; the workspace builds with `panic = "unwind"`).

#[cfg(unix)]
pub mod blocks;
mod config;
mod depth16;
mod error;
mod frames;
#[doc(hidden)]
pub mod handles;
mod imu;
mod layout;
mod limits;
mod natives;
#[cfg(any(target_os = "linux", target_os = "android"))]
mod soname;
mod tracker;

pub use config::{InitArgs, memory_budget, set_memory_budget};
pub use depth16::*;
pub use error::Failure;
pub use frames::{PlaneLayout, copy_plane};
pub use layout::*;
pub use limits::MAX_LIVE_TRACKERS;
pub use natives::*;
pub use tracker::NativeTracker;

use jni::sys::jint;

/// Large blocks as mappings of their own, unmapped when freed, so that a released
/// tracker's frames leave no resident memory in the C library's arenas ([`blocks`]).
#[cfg(unix)]
#[global_allocator]
static ALLOCATOR: blocks::Blocks = blocks::Blocks;

/// Called by the JVM when the library is loaded: initialises logging once (Android's
/// logcat through `android_logger`; elsewhere whatever `log` backend the host set up), and
/// warns there when the library carries no `DT_SONAME`.
///
/// # Safety
///
/// Called by the JVM only.
#[unsafe(no_mangle)]
pub extern "system" fn JNI_OnLoad(
    _vm: *mut jni::sys::JavaVM,
    _reserved: *mut std::ffi::c_void,
) -> jint {
    #[cfg(target_os = "android")]
    android_logger::init_once(
        android_logger::Config::default()
            .with_max_level(log::LevelFilter::Info)
            .with_tag("ecvo"),
    );
    #[cfg(any(target_os = "linux", target_os = "android"))]
    if soname::object_has_soname(JNI_OnLoad as *const std::ffi::c_void) == Some(false) {
        log::warn!(
            "libecvo_jni.so has no DT_SONAME: Android's linker then identifies it by its file name \
             (build it with scripts/build-android.sh, which links with -soname)"
        );
    }
    jni::sys::JNI_VERSION_1_6
}
