//! # ecvo-jni
//!
//! `libecvo_jni.so`: the JNI bridge between the Android tracker
//! (`android-app/tracker`, Kotlin `io.ecvo.NativeBridge`) and [`ecvo_pipeline`].
//! A thin layer: it converts codes and buffers, and turns every error and panic into a
//! Java exception.
//!
//! ## The native methods
//!
//! The 11 `@JvmStatic external fun` of `NativeBridge.kt` are declared once each with
//! jni 0.22's `native_method!` (see [`NATIVE_METHODS`]): the macro checks at compile
//! time that each Rust implementation matches the JNI signature written next to it,
//! and exports it under its short JNI name (`Java_io_ecvo_NativeBridge_nativeInit`,
//! ...), which is what `scripts/android/check-so.sh` looks for. [`declared_signatures`]
//! lists the same names and signatures, and `tests/signatures.rs` compares them with
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
//! Direct `ByteBuffer`s are read from their base address (position 0), `capacity`
//! bytes long: depth holds `width * height` 16-bit samples in **native byte order**,
//! which is little-endian on every Android ABI (as `ImageReader` planes are) and is
//! decoded as little-endian here; intensity `width * height` bytes. Arrays hold exactly
//! `width * height` values. The data is copied into a pooled frame inside
//! [`ecvo_pipeline::Pipeline::push`]'s fill closure; no pointer is kept after the call.
//! `DEPTH16` samples are decoded while copying (see [`decode_depth16`]).
//!
//! ## Errors
//!
//! `IllegalArgumentException` for bad input (the message names the field),
//! `IllegalStateException` for a released handle or a closed pipeline,
//! `RuntimeException` for a stage failure or a caught panic (`native_method!` wraps
//! every call in `catch_unwind`; the workspace builds with `panic = "unwind"`).

use std::collections::{BTreeMap, VecDeque};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use ecvo_core::{Camera, Config, Mode, Pose, Preset, TrackingState};
use ecvo_pipeline::{
    Admission, CloudPoint, GeometryOptions, Pipeline, PipelineOptions, PipelineStats, PoseRecord,
    PushStatus,
};
use jni::objects::{JByteArray, JByteBuffer, JClass, JDoubleArray, JFloatArray, JShortArray};
use jni::strings::JNIString;
use jni::sys::{jboolean, jdouble, jint, jlong};
use jni::{Env, NativeMethod, jni_str};

/// What `nativeGetPose` returns when there is no pose yet (`Tracker.NO_POSE`).
pub const NO_POSE: jlong = jlong::MIN;

/// Doubles per pose in `nativeTrajectory` (`TimedPose.STRIDE`).
pub const POSE_STRIDE: usize = 8;

/// Doubles per reference in `nativeReferences` (`ReferenceFrame.STRIDE`).
pub const REFERENCE_STRIDE: usize = 9;

/// Doubles in `nativeStats` (`TrackerStats.SIZE`).
pub const STATS_SIZE: usize = 14;

/// With the `test-hooks` feature only: a push with this timestamp panics inside the
/// native call (the misuse suite checks it becomes a `RuntimeException`).
#[cfg(feature = "test-hooks")]
pub const TEST_PANIC_TIMESTAMP_NS: jlong = -0x0EC0_DEAD;

/// How the 16-bit depth samples encode distance (`io.ecvo.DepthFormat` codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthFormat {
    /// Code 0: millimetres, 0 = no measurement.
    Millimetres,
    /// Code 1: Android `DEPTH16` (13-bit millimetres, 3-bit confidence).
    Depth16,
    /// Code 2: `depthScale` units per metre.
    CustomScale,
}

impl DepthFormat {
    /// The format with this code.
    pub fn from_code(code: jint) -> Option<DepthFormat> {
        match code {
            0 => Some(DepthFormat::Millimetres),
            1 => Some(DepthFormat::Depth16),
            2 => Some(DepthFormat::CustomScale),
            _ => None,
        }
    }
}

/// Decodes one Android `DEPTH16` sample: range in millimetres in the low 13 bits, a
/// 3-bit confidence on top (raw 0 = 100 %, 1 = 0 %, `c` = `(c - 1) / 7`), mapped to a
/// level 0..=7 (7 best: raw 0 -> 7, raw c -> c - 1, as `Depth16.kt` does). Samples
/// whose level is below `min_confidence` become 0 (no measurement).
pub fn decode_depth16(raw: u16, min_confidence: u8) -> u16 {
    let c = raw >> 13;
    let level = if c == 0 { 7 } else { c - 1 };
    if level < u16::from(min_confidence) {
        0
    } else {
        raw & 0x1FFF
    }
}

/// Capture time: nanoseconds (Kotlin) to the pipeline's seconds.
pub fn ns_to_seconds(ns: jlong) -> f64 {
    ns as f64 / 1e9
}

/// A pose as the 16 floats `nativeGetPose` writes: 4x4 camera-to-world, column-major.
pub fn pose_matrix(pose: &Pose) -> [f32; 16] {
    let m = pose.to_homogeneous();
    let mut out = [0f32; 16];
    // nalgebra stores matrices column-major.
    for (o, v) in out.iter_mut().zip(m.as_slice()) {
        *o = *v as f32;
    }
    out
}

/// A pose record as the 8 doubles of `nativeTrajectory`: t, tx, ty, tz, qx, qy, qz, qw.
pub fn pose_doubles(r: &PoseRecord) -> [f64; POSE_STRIDE] {
    let t = r.pose.translation.vector;
    let q = r.pose.rotation.quaternion();
    [r.timestamp, t.x, t.y, t.z, q.i, q.j, q.k, q.w]
}

/// The 14 doubles of `nativeStats` (layout in `TrackerStats.kt`).
pub fn stats_doubles(s: &PipelineStats) -> [f64; STATS_SIZE] {
    let c = &s.counters;
    let level = |i: usize| c.references.get(i).copied().unwrap_or(0) as f64;
    [
        s.pushed as f64,
        s.dropped as f64,
        s.tracked as f64,
        c.motion_estimations as f64,
        level(0),
        level(1),
        c.lost_frames as f64,
        c.failed_corrections as f64,
        c.reanchors as f64,
        s.filter.mean_ms,
        s.tracker.mean_ms,
        s.geometry.mean_ms,
        s.latency.mean_ms,
        s.wall_ms_per_frame,
    ]
}

/// The 4 floats per point of `nativePointCloud` (x, y, z, intensity 0..1), at most
/// `max_points` points taken evenly from the whole cloud.
pub fn cloud_floats(points: &[CloudPoint], max_points: usize) -> Vec<f32> {
    let n = points.len();
    let take = n.min(max_points);
    let mut out = Vec::with_capacity(take * 4);
    for i in 0..take {
        let p = &points[if take == n { i } else { i * n / take }];
        out.extend_from_slice(&[
            p.position[0],
            p.position[1],
            p.position[2],
            f32::from(p.intensity) / 255.0,
        ]);
    }
    out
}

/// What a native call failed with; becomes the Java exception of the same name.
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// `java.lang.IllegalArgumentException`.
    IllegalArgument(String),
    /// `java.lang.IllegalStateException`.
    IllegalState(String),
    /// `java.lang.RuntimeException`.
    Runtime(String),
    /// A Java exception is already pending.
    Pending,
}

impl From<ecvo_pipeline::Error> for Failure {
    fn from(e: ecvo_pipeline::Error) -> Self {
        use ecvo_pipeline::Error as E;
        match &e {
            E::Core(_) | E::InvalidOptions { .. } => Failure::IllegalArgument(e.to_string()),
            E::Closed => Failure::IllegalState(e.to_string()),
            E::StagePanicked { .. } | E::Spawn(_) => Failure::Runtime(e.to_string()),
        }
    }
}

impl From<jni::errors::Error> for Failure {
    fn from(e: jni::errors::Error) -> Self {
        match e {
            jni::errors::Error::JavaException => Failure::Pending,
            e => Failure::Runtime(format!("JNI error: {e}")),
        }
    }
}

fn bad(msg: impl Into<String>) -> Failure {
    Failure::IllegalArgument(msg.into())
}

/// Runs a native method's body; a [`Failure`] is thrown as its Java exception and
/// reported to `native_method!`'s policy as a pending exception (so nothing else is
/// thrown). Panics are caught by the `native_method!` wrapper (`RuntimeException`).
fn run<'local, T>(
    env: &mut Env<'local>,
    body: impl FnOnce(&mut Env<'local>) -> Result<T, Failure>,
) -> jni::errors::Result<T> {
    let failure = match body(env) {
        Ok(v) => return Ok(v),
        Err(f) => f,
    };
    if !env.exception_check() {
        let (class, msg) = match failure {
            Failure::IllegalArgument(m) => (jni_str!("java/lang/IllegalArgumentException"), m),
            Failure::IllegalState(m) => (jni_str!("java/lang/IllegalStateException"), m),
            Failure::Runtime(m) => (jni_str!("java/lang/RuntimeException"), m),
            Failure::Pending => (
                jni_str!("java/lang/RuntimeException"),
                "JNI call failed".into(),
            ),
        };
        log::debug!("ecvo-jni: throwing {class:?}: {msg}");
        let _ = env.throw_new(class, JNIString::from(msg));
    }
    Err(jni::errors::Error::JavaException)
}

/// One tracker behind a handle.
pub struct NativeTracker {
    pipeline: Pipeline,
    width: usize,
    height: usize,
    format: DepthFormat,
    min_confidence: u8,
    /// Recent (seconds bits, nanoseconds) pairs, so that `nativeGetPose` returns the
    /// exact nanosecond timestamp that was pushed.
    stamps: Mutex<VecDeque<(u64, jlong)>>,
}

/// Pushed timestamps remembered for `nativeGetPose` (far more than the frames the
/// pipeline holds at once).
const STAMPS_KEPT: usize = 64;

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

static REGISTRY: Mutex<BTreeMap<jlong, Arc<NativeTracker>>> = Mutex::new(BTreeMap::new());
static NEXT_HANDLE: AtomicI64 = AtomicI64::new(1);

fn tracker(handle: jlong) -> Result<Arc<NativeTracker>, Failure> {
    if handle == 0 {
        return Err(Failure::IllegalState("tracker handle is 0 (closed)".into()));
    }
    lock(&REGISTRY).get(&handle).cloned().ok_or_else(|| {
        Failure::IllegalState(format!("tracker handle {handle} is released or unknown"))
    })
}

/// The settings of `nativeInit`, checked; the error names the bad field.
#[derive(Clone, Debug)]
pub struct InitArgs {
    /// Frame width in pixels.
    pub width: jint,
    /// Frame height in pixels.
    pub height: jint,
    /// Focal length x.
    pub fx: f64,
    /// Focal length y.
    pub fy: f64,
    /// Principal point x.
    pub cx: f64,
    /// Principal point y.
    pub cy: f64,
    /// `DepthFormat` code.
    pub depth_format: jint,
    /// Units per metre for `CUSTOM_SCALE`.
    pub depth_scale: f64,
    /// 0..=7, `DEPTH16` only.
    pub min_confidence: jint,
    /// `Preset` code.
    pub preset: jint,
    /// `Mode` code.
    pub mode: jint,
    /// Live (drop when busy) or offline.
    pub live: bool,
    /// Compute threads.
    pub threads: jint,
}

impl InitArgs {
    /// The tracker configuration, pipeline options and depth decoding these settings
    /// describe, or `IllegalArgument` naming the bad field.
    pub fn build(&self) -> Result<(Config, PipelineOptions, DepthFormat, u8), Failure> {
        let size = |v: jint, name: &str| {
            usize::try_from(v).map_err(|_| bad(format!("{name}: {v} is negative")))
        };
        let width = size(self.width, "width")?;
        let height = size(self.height, "height")?;
        let format = DepthFormat::from_code(self.depth_format).ok_or_else(|| {
            bad(format!(
                "depthFormat: unknown code {} (0 MILLIMETRES, 1 DEPTH16, 2 CUSTOM_SCALE)",
                self.depth_format
            ))
        })?;
        let depth_scale = match format {
            DepthFormat::Millimetres | DepthFormat::Depth16 => 1000.0,
            DepthFormat::CustomScale => {
                if !(self.depth_scale.is_finite() && self.depth_scale > 0.0) {
                    return Err(bad(format!(
                        "depthScale: {} is not a positive number",
                        self.depth_scale
                    )));
                }
                self.depth_scale
            }
        };
        let min_confidence = match format {
            DepthFormat::Depth16 => u8::try_from(self.min_confidence)
                .ok()
                .filter(|c| *c <= 7)
                .ok_or_else(|| {
                    bad(format!(
                        "minConfidence: {} is not in 0..7",
                        self.min_confidence
                    ))
                })?,
            _ => 0,
        };
        let preset = match self.preset {
            0 => Preset::Pc,
            1 => Preset::Phone,
            c => return Err(bad(format!("preset: unknown code {c} (0 PC, 1 PHONE)"))),
        };
        let mode = match self.mode {
            0 => Mode::Naive,
            1 => Mode::L1,
            2 => Mode::L2,
            c => return Err(bad(format!("mode: unknown code {c} (0 NAIVE, 1 L1, 2 L2)"))),
        };
        let threads = size(self.threads, "threads")?;
        if !(1..=256).contains(&threads) {
            return Err(bad(format!("threads: {threads} is not in 1..256")));
        }
        for (name, v) in [
            ("fx", self.fx),
            ("fy", self.fy),
            ("cx", self.cx),
            ("cy", self.cy),
        ] {
            if !v.is_finite() {
                return Err(bad(format!("{name}: {v} is not finite")));
            }
        }
        let camera = Camera {
            width,
            height,
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            depth_scale,
        };
        let config = Config::new(camera, preset, mode);
        config.validate().map_err(|e| bad(e.to_string()))?;
        let options = PipelineOptions {
            threads,
            admission: if self.live {
                Admission::Live
            } else {
                Admission::Offline
            },
            geometry: Some(GeometryOptions::default()),
            keep_trajectory: true,
            ..PipelineOptions::default()
        };
        Ok((config, options, format, min_confidence))
    }
}

fn init(args: &InitArgs) -> Result<jlong, Failure> {
    let (config, options, format, min_confidence) = args.build()?;
    let (width, height) = (config.camera.width, config.camera.height);
    let pipeline = Pipeline::new(config, options)?;
    let t = Arc::new(NativeTracker {
        pipeline,
        width,
        height,
        format,
        min_confidence,
        stamps: Mutex::new(VecDeque::with_capacity(STAMPS_KEPT)),
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
    fn pixels(&self) -> usize {
        self.width * self.height
    }

    /// Pushes one frame; `fill` copies raw depth and intensity into the pooled buffers.
    fn push(
        &self,
        timestamp_ns: jlong,
        fill: impl FnOnce(&mut [u8], &mut [u16]) -> Result<(), Failure>,
    ) -> Result<jint, Failure> {
        #[cfg(feature = "test-hooks")]
        if timestamp_ns == TEST_PANIC_TIMESTAMP_NS {
            panic!("ecvo-jni test hook: injected panic");
        }
        let seconds = ns_to_seconds(timestamp_ns);
        let mut result = Ok(());
        let (format, min_conf) = (self.format, self.min_confidence);
        let status = self.pipeline.push(seconds, |i, d| {
            result = fill(i, d);
            if result.is_err() {
                // The buffer must be overwritten entirely whatever happens.
                i.fill(0);
                d.fill(0);
            } else if format == DepthFormat::Depth16 {
                for v in d.iter_mut() {
                    *v = decode_depth16(*v, min_conf);
                }
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
        })
    }

    /// The nanosecond timestamp that was pushed as `seconds`.
    fn stamp_ns(&self, seconds: f64) -> jlong {
        let bits = seconds.to_bits();
        lock(&self.stamps)
            .iter()
            .rev()
            .find(|(b, _)| *b == bits)
            .map_or_else(|| (seconds * 1e9).round() as jlong, |(_, ns)| *ns)
    }
}

// --- the native methods ------------------------------------------------------------------

/// Declares the native methods once: each entry becomes a `native_method!` constant
/// (compile-time checked against its Rust function, exported under its short JNI
/// name) and a row of [`declared_signatures`].
macro_rules! bridge {
    ($( $konst:ident = $export:literal, fn $name:ident $args:tt $(-> $ret:tt)?; )*) => {
        $(
            #[doc = concat!("The native method exported as `", $export, "`.")]
            pub const $konst: NativeMethod<'static> = jni::native_method! {
                java_type = "io.ecvo.NativeBridge",
                export = $export,
                static fn $name $args $(-> $ret)?,
            };
        )*

        /// Every native method, e.g. for `Env::register_native_methods`.
        pub const NATIVE_METHODS: &[NativeMethod<'static>] = &[$($konst),*];

        /// `(exported symbol, JNI signature)` of every native method, from the same
        /// declarations as [`NATIVE_METHODS`]; `tests/signatures.rs` compares them with
        /// `NativeBridge.kt`.
        pub fn declared_signatures() -> Vec<(&'static str, String)> {
            vec![$(
                ($export, jni::jni_sig!($args $(-> $ret)?).sig().to_str().into_owned()),
            )*]
        }
    };
}

bridge! {
    NATIVE_INIT = "Java_io_ecvo_NativeBridge_nativeInit",
        fn native_init(width: jint, height: jint, fx: jdouble, fy: jdouble, cx: jdouble, cy: jdouble,
            depth_format: jint, depth_scale: jdouble, min_confidence: jint,
            preset: jint, mode: jint, live: jboolean, threads: jint) -> jlong;
    NATIVE_PUSH_BUFFERS = "Java_io_ecvo_NativeBridge_nativePushBuffers",
        fn native_push_buffers(handle: jlong, timestamp_ns: jlong, depth: JByteBuffer, intensity: JByteBuffer) -> jint;
    NATIVE_PUSH_ARRAYS = "Java_io_ecvo_NativeBridge_nativePushArrays",
        fn native_push_arrays(handle: jlong, timestamp_ns: jlong, depth: [jshort], intensity: [jbyte]) -> jint;
    NATIVE_GET_POSE = "Java_io_ecvo_NativeBridge_nativeGetPose",
        fn native_get_pose(handle: jlong, out: [jfloat]) -> jlong;
    NATIVE_STATE = "Java_io_ecvo_NativeBridge_nativeState",
        fn native_state(handle: jlong) -> jint;
    NATIVE_FLUSH = "Java_io_ecvo_NativeBridge_nativeFlush",
        fn native_flush(handle: jlong);
    NATIVE_TRAJECTORY = "Java_io_ecvo_NativeBridge_nativeTrajectory",
        fn native_trajectory(handle: jlong) -> [jdouble];
    NATIVE_REFERENCES = "Java_io_ecvo_NativeBridge_nativeReferences",
        fn native_references(handle: jlong) -> [jdouble];
    NATIVE_STATS = "Java_io_ecvo_NativeBridge_nativeStats",
        fn native_stats(handle: jlong) -> [jdouble];
    NATIVE_POINT_CLOUD = "Java_io_ecvo_NativeBridge_nativePointCloud",
        fn native_point_cloud(handle: jlong, max_points: jint) -> [jfloat];
    NATIVE_RELEASE = "Java_io_ecvo_NativeBridge_nativeRelease",
        fn native_release(handle: jlong);
}

fn native_init<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    width: jint,
    height: jint,
    fx: jdouble,
    fy: jdouble,
    cx: jdouble,
    cy: jdouble,
    depth_format: jint,
    depth_scale: jdouble,
    min_confidence: jint,
    preset: jint,
    mode: jint,
    live: jboolean,
    threads: jint,
) -> jni::errors::Result<jlong> {
    let args = InitArgs {
        width,
        height,
        fx,
        fy,
        cx,
        cy,
        depth_format,
        depth_scale,
        min_confidence,
        preset,
        mode,
        live,
        threads,
    };
    run(env, |_| init(&args))
}

/// The address and capacity of a direct buffer of at least `need` bytes.
fn direct(
    env: &Env<'_>,
    buf: &JByteBuffer<'_>,
    name: &str,
    need: usize,
) -> Result<(*const u8, usize), Failure> {
    if buf.is_null() {
        return Err(bad(format!("{name}: buffer is null")));
    }
    let cap = env
        .get_direct_buffer_capacity(buf)
        .map_err(|_| bad(format!("{name}: buffer is not direct")))?;
    let ptr = env
        .get_direct_buffer_address(buf)
        .map_err(|_| bad(format!("{name}: buffer is not direct")))?;
    if ptr.is_null() {
        return Err(bad(format!("{name}: buffer is not direct")));
    }
    if cap < need {
        return Err(bad(format!(
            "{name}: buffer holds {cap} bytes, the frame needs {need}"
        )));
    }
    Ok((ptr, cap))
}

fn native_push_buffers<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    timestamp_ns: jlong,
    depth: JByteBuffer<'local>,
    intensity: JByteBuffer<'local>,
) -> jni::errors::Result<jint> {
    run(env, |env| {
        let t = tracker(handle)?;
        let n = t.pixels();
        let (dp, _) = direct(env, &depth, "depth", 2 * n)?;
        let (ip, _) = direct(env, &intensity, "intensity", n)?;
        // SAFETY: both buffers are direct, at least this long (checked above), and
        // stay alive (referenced by the local references `depth` and `intensity`)
        // for this call; the slices do not outlive it.
        let (d, i) = unsafe {
            (
                std::slice::from_raw_parts(dp, 2 * n),
                std::slice::from_raw_parts(ip, n),
            )
        };
        t.push(timestamp_ns, |ib, db| {
            ib.copy_from_slice(i);
            for (v, b) in db.iter_mut().zip(d.chunks_exact(2)) {
                *v = u16::from_le_bytes([b[0], b[1]]);
            }
            Ok(())
        })
    })
}

fn array_len(len: jni::errors::Result<usize>, name: &str, need: usize) -> Result<(), Failure> {
    let len = len.map_err(|_| bad(format!("{name}: array is null")))?;
    if len != need {
        return Err(bad(format!(
            "{name}: array has {len} values, the frame needs {need}"
        )));
    }
    Ok(())
}

fn native_push_arrays<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    timestamp_ns: jlong,
    depth: JShortArray<'local>,
    intensity: JByteArray<'local>,
) -> jni::errors::Result<jint> {
    run(env, |env| {
        let t = tracker(handle)?;
        let n = t.pixels();
        if depth.is_null() {
            return Err(bad("depth: array is null"));
        }
        if intensity.is_null() {
            return Err(bad("intensity: array is null"));
        }
        array_len(depth.len(env), "depth", n)?;
        array_len(intensity.len(env), "intensity", n)?;
        let env = &*env;
        t.push(timestamp_ns, |ib, db| {
            // SAFETY: u16/i16 and u8/i8 have the same size and alignment; the
            // reinterpreted slices are only written by the JNI copy.
            let (d, i) = unsafe {
                (
                    std::slice::from_raw_parts_mut(db.as_mut_ptr().cast::<i16>(), db.len()),
                    std::slice::from_raw_parts_mut(ib.as_mut_ptr().cast::<i8>(), ib.len()),
                )
            };
            depth.get_region(env, 0, d)?;
            intensity.get_region(env, 0, i)?;
            Ok(())
        })
    })
}

fn native_get_pose<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    out: JFloatArray<'local>,
) -> jni::errors::Result<jlong> {
    run(env, |env| {
        let t = tracker(handle)?;
        if out.is_null() {
            return Err(bad("out: array is null"));
        }
        let len = out.len(env)?;
        if len < 16 {
            return Err(bad(format!("out: array has {len} values, a pose needs 16")));
        }
        let latest = t.pipeline.latest();
        if latest.tracked == 0 {
            return Ok(NO_POSE);
        }
        out.set_region(env, 0, &pose_matrix(&latest.pose))?;
        Ok(t.stamp_ns(latest.timestamp))
    })
}

fn native_state<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<jint> {
    run(env, |_| {
        let t = tracker(handle)?;
        let latest = t.pipeline.latest();
        Ok(match latest.state {
            _ if latest.tracked == 0 => 0,
            TrackingState::Initialising => 0,
            TrackingState::Tracking => 1,
            TrackingState::Lost => 2,
        })
    })
}

fn native_flush<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<()> {
    run(env, |_| Ok(tracker(handle)?.pipeline.flush()?))
}

fn doubles<'local>(env: &mut Env<'local>, v: &[f64]) -> Result<JDoubleArray<'local>, Failure> {
    let a = env.new_double_array(v.len())?;
    a.set_region(env, 0, v)?;
    Ok(a)
}

fn native_trajectory<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<JDoubleArray<'local>> {
    run(env, |env| {
        let t = tracker(handle)?;
        let v: Vec<f64> = t
            .pipeline
            .trajectory()
            .iter()
            .flat_map(pose_doubles)
            .collect();
        doubles(env, &v)
    })
}

fn native_references<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<JDoubleArray<'local>> {
    run(env, |env| {
        let t = tracker(handle)?;
        let refs = t.pipeline.references();
        let mut v = Vec::with_capacity(refs.len() * REFERENCE_STRIDE);
        for r in &refs {
            v.extend_from_slice(&pose_doubles(r));
            v.push(f64::from(r.reference_levels));
        }
        doubles(env, &v)
    })
}

fn native_stats<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<JDoubleArray<'local>> {
    run(env, |env| {
        let t = tracker(handle)?;
        doubles(env, &stats_doubles(&t.pipeline.stats()))
    })
}

fn native_point_cloud<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    max_points: jint,
) -> jni::errors::Result<JFloatArray<'local>> {
    run(env, |env| {
        let t = tracker(handle)?;
        let max = usize::try_from(max_points)
            .map_err(|_| bad(format!("maxPoints: {max_points} is negative")))?;
        let v = cloud_floats(&t.pipeline.cloud_snapshot(), max);
        let a = env.new_float_array(v.len())?;
        a.set_region(env, 0, &v)?;
        Ok(a)
    })
}

fn native_release<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<()> {
    run(env, |_| {
        let removed = lock(&REGISTRY).remove(&handle);
        if removed.is_some() {
            log::info!("ecvo-jni: tracker {handle} released");
        }
        // The pipeline stops and joins its threads when the last `Arc` goes: here,
        // or at the end of a call still running on another thread.
        drop(removed);
        Ok(())
    })
}

/// Called by the JVM when the library is loaded: initialises logging once (Android's
/// logcat through `android_logger`; elsewhere whatever `log` backend the host set up).
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
    jni::sys::JNI_VERSION_1_6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth16_confidence_levels() {
        // Raw confidence 0 is 100 % (level 7), 1 is 0 % (level 0).
        assert_eq!(decode_depth16(1234, 7), 1234);
        assert_eq!(decode_depth16((1 << 13) | 1234, 0), 1234);
        assert_eq!(decode_depth16((1 << 13) | 1234, 1), 0);
        // Raw 5 is level 4.
        assert_eq!(decode_depth16((5 << 13) | 0x1FFF, 4), 0x1FFF);
        assert_eq!(decode_depth16((5 << 13) | 0x1FFF, 5), 0);
    }

    #[test]
    fn pose_matrix_is_column_major() {
        let pose = Pose::new(
            ecvo_core::nalgebra::Vector3::new(1.0, 2.0, 3.0),
            ecvo_core::nalgebra::Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let m = pose_matrix(&pose);
        assert_eq!(&m[12..16], &[1.0, 2.0, 3.0, 1.0]);
        // Camera x axis (first column) points along world y after a 90 degree turn about z.
        assert!((m[1] - 1.0).abs() < 1e-6 && m[0].abs() < 1e-6);
        assert_eq!(m[3], 0.0);
    }

    #[test]
    fn cloud_is_subsampled_evenly() {
        let pts: Vec<CloudPoint> = (0..10)
            .map(|i| CloudPoint {
                position: [i as f32, 0.0, 0.0],
                normal: [0.0; 3],
                intensity: 255,
            })
            .collect();
        let v = cloud_floats(&pts, 5);
        assert_eq!(v.len(), 20);
        assert_eq!(
            v.chunks(4).map(|c| c[0]).collect::<Vec<_>>(),
            [0.0, 2.0, 4.0, 6.0, 8.0]
        );
        assert_eq!(v[3], 1.0);
        assert_eq!(cloud_floats(&pts, 100).len(), 40);
    }

    #[test]
    fn init_names_bad_fields() {
        let good = InitArgs {
            width: 320,
            height: 180,
            fx: 250.0,
            fy: 250.0,
            cx: 159.5,
            cy: 89.5,
            depth_format: 0,
            depth_scale: 1000.0,
            min_confidence: 0,
            preset: 1,
            mode: 2,
            live: true,
            threads: 2,
        };
        assert!(good.build().is_ok());
        let msg = |a: InitArgs| match a.build() {
            Err(Failure::IllegalArgument(m)) => m,
            other => panic!("expected IllegalArgument, got {other:?}"),
        };
        assert!(
            msg(InitArgs {
                fx: f64::NAN,
                ..good.clone()
            })
            .contains("fx")
        );
        assert!(
            msg(InitArgs {
                width: 0,
                ..good.clone()
            })
            .contains("width")
        );
        assert!(
            msg(InitArgs {
                mode: 3,
                ..good.clone()
            })
            .contains("mode")
        );
        assert!(
            msg(InitArgs {
                preset: -1,
                ..good.clone()
            })
            .contains("preset")
        );
        assert!(
            msg(InitArgs {
                depth_format: 9,
                ..good.clone()
            })
            .contains("depthFormat")
        );
        assert!(
            msg(InitArgs {
                depth_format: 2,
                depth_scale: 0.0,
                ..good.clone()
            })
            .contains("depthScale")
        );
        assert!(
            msg(InitArgs {
                depth_format: 1,
                min_confidence: 8,
                ..good.clone()
            })
            .contains("minConfidence")
        );
        assert!(
            msg(InitArgs {
                threads: 0,
                ..good.clone()
            })
            .contains("threads")
        );
        assert!(
            msg(InitArgs {
                threads: -3,
                ..good
            })
            .contains("threads")
        );
    }
}
