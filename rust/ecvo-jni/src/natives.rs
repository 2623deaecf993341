//! The native methods: declared once in [`bridge!`], each a thin wrapper that finds the
//! tracker, converts its arguments and calls the engine.

use jni::objects::{JByteArray, JByteBuffer, JClass, JDoubleArray, JFloatArray, JShortArray};
use jni::sys::{jboolean, jdouble, jint, jlong};
use jni::{Env, NativeMethod};

use crate::config::InitArgs;
use crate::error::{Failure, bad, run};
use crate::frames::{PlaneLayout, array_len, copy_plane, direct};
use crate::imu::{native_push_imu, native_push_imu_batch};
use crate::layout::{
    NO_POSE, QUALITY_SIZE, REFERENCE_STRIDE, cloud_floats, pose_doubles, pose_matrix,
    quality_doubles, state_code, stats_doubles,
};
use crate::layout::{POSE_STRIDE, TRAJECTORY_WINDOW};
use crate::tracker::{REGISTRY, init, lock, tracker};

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
        /// declarations as [`NATIVE_METHODS`]; `tests/it/signatures.rs` compares them with
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
            preset: jint, mode: jint, live: jboolean, threads: jint, point_cloud: jboolean) -> jlong;
    NATIVE_PUSH_BUFFERS = "Java_io_ecvo_NativeBridge_nativePushBuffers",
        fn native_push_buffers(handle: jlong, timestamp_ns: jlong, depth: JByteBuffer, intensity: JByteBuffer) -> jint;
    NATIVE_PUSH_STRIDED = "Java_io_ecvo_NativeBridge_nativePushStrided",
        fn native_push_strided(handle: jlong, timestamp_ns: jlong, depth: JByteBuffer, depth_row_stride: jint,
            intensity: JByteBuffer, intensity_row_stride: jint) -> jint;
    NATIVE_PUSH_ARRAYS = "Java_io_ecvo_NativeBridge_nativePushArrays",
        fn native_push_arrays(handle: jlong, timestamp_ns: jlong, depth: [jshort], intensity: [jbyte]) -> jint;
    NATIVE_GET_POSE = "Java_io_ecvo_NativeBridge_nativeGetPose",
        fn native_get_pose(handle: jlong, out: [jfloat]) -> jlong;
    NATIVE_PUSH_IMU = "Java_io_ecvo_NativeBridge_nativePushImu",
        fn native_push_imu(handle: jlong, timestamp_ns: jlong, wx: jdouble, wy: jdouble, wz: jdouble);
    NATIVE_PUSH_IMU_BATCH = "Java_io_ecvo_NativeBridge_nativePushImuBatch",
        fn native_push_imu_batch(handle: jlong, timestamps_ns: [jlong], rates: [jfloat], count: jint);
    NATIVE_FRAME_QUALITY = "Java_io_ecvo_NativeBridge_nativeFrameQuality",
        fn native_frame_quality(handle: jlong, out: [jdouble]) -> jlong;
    NATIVE_STATE = "Java_io_ecvo_NativeBridge_nativeState",
        fn native_state(handle: jlong) -> jint;
    NATIVE_FLUSH = "Java_io_ecvo_NativeBridge_nativeFlush",
        fn native_flush(handle: jlong);
    NATIVE_SET_INTRINSICS = "Java_io_ecvo_NativeBridge_nativeSetIntrinsics",
        fn native_set_intrinsics(handle: jlong, fx: jdouble, fy: jdouble, cx: jdouble, cy: jdouble);
    NATIVE_TRAJECTORY = "Java_io_ecvo_NativeBridge_nativeTrajectory",
        fn native_trajectory(handle: jlong) -> [jdouble];
    NATIVE_TRAJECTORY_SINCE = "Java_io_ecvo_NativeBridge_nativeTrajectorySince",
        fn native_trajectory_since(handle: jlong, from: jint) -> [jdouble];
    NATIVE_REFERENCES = "Java_io_ecvo_NativeBridge_nativeReferences",
        fn native_references(handle: jlong) -> [jdouble];
    NATIVE_STATS = "Java_io_ecvo_NativeBridge_nativeStats",
        fn native_stats(handle: jlong) -> [jdouble];
    NATIVE_POINT_CLOUD = "Java_io_ecvo_NativeBridge_nativePointCloud",
        fn native_point_cloud(handle: jlong, max_points: jint) -> [jfloat];
    NATIVE_RELEASE = "Java_io_ecvo_NativeBridge_nativeRelease",
        fn native_release(handle: jlong);
    NATIVE_MEMORY_NEEDED = "Java_io_ecvo_NativeBridge_nativeMemoryNeeded",
        fn native_memory_needed(width: jint, height: jint, fx: jdouble, fy: jdouble, cx: jdouble, cy: jdouble,
            depth_format: jint, depth_scale: jdouble, min_confidence: jint,
            preset: jint, mode: jint, live: jboolean, threads: jint, point_cloud: jboolean) -> jlong;
    NATIVE_SET_MEMORY_BUDGET = "Java_io_ecvo_NativeBridge_nativeSetMemoryBudget",
        fn native_set_memory_budget(bytes: jlong) -> jlong;
}

/// `nativeMemoryNeeded`: the bytes `nativeInit` with the same arguments would
/// allocate (and compare with the budget), without allocating; the same
/// `IllegalArgumentException`s for bad settings.
fn native_memory_needed<'local>(
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
    point_cloud: jboolean,
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
        point_cloud,
    };
    run(env, |_| {
        let need = args.memory_needed()?;
        Ok(jlong::try_from(need).unwrap_or(jlong::MAX))
    })
}

/// `nativeSetMemoryBudget`: the budget of the trackers created from now on; returns
/// the previous one.
fn native_set_memory_budget<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    bytes: jlong,
) -> jni::errors::Result<jlong> {
    run(env, |_| crate::config::set_memory_budget(bytes))
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
    point_cloud: jboolean,
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
        point_cloud,
    };
    run(env, |_| init(&args))
}

/// Pushes one frame read from two direct buffers laid out as given.
fn push_direct(
    env: &mut Env<'_>,
    handle: jlong,
    timestamp_ns: jlong,
    depth: &JByteBuffer<'_>,
    depth_row_stride: Option<jint>,
    intensity: &JByteBuffer<'_>,
    intensity_row_stride: Option<jint>,
) -> Result<jint, Failure> {
    let t = tracker(handle)?;
    let (w, h) = t.size();
    let layout = |bpp: usize, stride: Option<jint>, name: &str| -> Result<PlaneLayout, Failure> {
        match stride {
            None => Ok(PlaneLayout::packed(w, h, bpp)),
            Some(s) => Ok(PlaneLayout {
                row_stride: usize::try_from(s)
                    .map_err(|_| bad(format!("{name}: row stride {s} is negative")))?,
                ..PlaneLayout::packed(w, h, bpp)
            }),
        }
    };
    let dl = layout(2, depth_row_stride, "depth")?;
    let il = layout(1, intensity_row_stride, "intensity")?;
    let d = direct(env, depth, "depth", dl)?;
    let i = direct(env, intensity, "intensity", il)?;
    t.push(timestamp_ns, |ib, db| {
        copy_plane(i, il, ib);
        // Depth is little-endian (native order on every Android ABI), row by row.
        for (y, row) in db.chunks_exact_mut(w).enumerate() {
            let src = &d[y * dl.row_stride..y * dl.row_stride + 2 * w];
            for (v, b) in row.iter_mut().zip(src.chunks_exact(2)) {
                *v = u16::from_le_bytes([b[0], b[1]]);
            }
        }
        Ok(())
    })
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
        push_direct(env, handle, timestamp_ns, &depth, None, &intensity, None)
    })
}

fn native_push_strided<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    timestamp_ns: jlong,
    depth: JByteBuffer<'local>,
    depth_row_stride: jint,
    intensity: JByteBuffer<'local>,
    intensity_row_stride: jint,
) -> jni::errors::Result<jint> {
    run(env, |env| {
        push_direct(
            env,
            handle,
            timestamp_ns,
            &depth,
            Some(depth_row_stride),
            &intensity,
            Some(intensity_row_stride),
        )
    })
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
        let (w, h) = t.size();
        let n = w * h;
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

/// `nativeFrameQuality`: the latest frame, its pose and its registration's quality
/// into `out[0..QUALITY_SIZE]` ([`quality_doubles`]); returns its timestamp, or
/// `NO_POSE` (leaving `out` untouched) before the first frame is tracked. One copy
/// of the latest output under its lock, so the pose and its quality are of the same
/// frame; nothing allocated.
fn native_frame_quality<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    out: JDoubleArray<'local>,
) -> jni::errors::Result<jlong> {
    run(env, |env| {
        let t = tracker(handle)?;
        if out.is_null() {
            return Err(bad("out: array is null"));
        }
        let len = out.len(env)?;
        if len < QUALITY_SIZE {
            return Err(bad(format!(
                "out: array has {len} values, a frame's quality needs {QUALITY_SIZE}"
            )));
        }
        let latest = t.pipeline.latest();
        if latest.tracked == 0 {
            return Ok(NO_POSE);
        }
        let mut v = [0f64; QUALITY_SIZE];
        quality_doubles(&latest, &mut v);
        out.set_region(env, 0, &v)?;
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
        Ok(jint::from(state_code(latest.tracked, latest.state)))
    })
}

fn native_flush<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<()> {
    run(env, |_| Ok(tracker(handle)?.pipeline.flush()?))
}

fn native_set_intrinsics<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    fx: jdouble,
    fy: jdouble,
    cx: jdouble,
    cy: jdouble,
) -> jni::errors::Result<()> {
    run(env, |_| {
        let t = tracker(handle)?;
        let camera = ecvo_core::Camera {
            fx,
            fy,
            cx,
            cy,
            ..t.pipeline.intrinsics()
        };
        Ok(t.pipeline.set_intrinsics(camera)?)
    })
}

fn doubles<'local>(env: &mut Env<'local>, v: &[f64]) -> Result<JDoubleArray<'local>, Failure> {
    let a = env.new_double_array(v.len())?;
    a.set_region(env, 0, v)?;
    Ok(a)
}

/// Cloud points copied per step into a point-cloud array.
const CLOUD_CHUNK: usize = 4096;

/// Poses copied per step into a trajectory array.
const TRAJECTORY_CHUNK: usize = 1024;

/// The kept poses from index `from` on (from the window's start if `None`), 8 doubles
/// each, copied `TRAJECTORY_CHUNK` at a time: a call never allocates the whole window
/// natively, only the Java array. Asking from before the window is an
/// `IllegalArgumentException`. Without `from`, a window that moves on during the copy
/// (the tracker tracked a frame meanwhile) starts the copy again from its new start.
fn trajectory_array<'local>(
    env: &mut Env<'local>,
    pipeline: &ecvo_pipeline::Pipeline,
    from: Option<u64>,
) -> Result<JDoubleArray<'local>, Failure> {
    // Sized on the first chunk: a poll that finds nothing new allocates nothing.
    let mut records = Vec::new();
    let mut values = Vec::new();
    for _attempt in 0..16 {
        let (start, end) = pipeline.trajectory_chunk(u64::MAX, 0, &mut records);
        let first = from.unwrap_or(start);
        if first < start {
            return Err(bad(format!(
                "from: poses before index {start} were discarded (a session keeps the last {TRAJECTORY_WINDOW}); ask from {start} on"
            )));
        }
        let n =
            usize::try_from(end.saturating_sub(first)).map_err(|_| bad("trajectory too long"))?;
        let array = env.new_double_array(n * POSE_STRIDE)?;
        records.reserve(TRAJECTORY_CHUNK.min(n));
        values.reserve(TRAJECTORY_CHUNK.min(n) * POSE_STRIDE);
        let mut done = 0usize;
        let mut moved = false;
        while done < n {
            let at = first + done as u64;
            let (now_start, _) =
                pipeline.trajectory_chunk(at, TRAJECTORY_CHUNK.min(n - done), &mut records);
            if now_start > at || records.is_empty() {
                moved = true;
                break;
            }
            values.clear();
            values.extend(records.iter().flat_map(pose_doubles));
            let offset =
                i32::try_from(done * POSE_STRIDE).map_err(|_| bad("trajectory too long"))?;
            array.set_region(env, offset, &values)?;
            done += records.len();
        }
        if !moved {
            return Ok(array);
        }
        // The poses from `first` on are partly gone: asked for by index, say so (the
        // next check above does); from the window's start, copy again.
    }
    Err(Failure::IllegalState(
        "the trajectory window kept moving on during the copy; call again".into(),
    ))
}

fn native_trajectory<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
) -> jni::errors::Result<JDoubleArray<'local>> {
    run(env, |env| {
        let t = tracker(handle)?;
        trajectory_array(env, &t.pipeline, None)
    })
}

fn native_trajectory_since<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    from: jint,
) -> jni::errors::Result<JDoubleArray<'local>> {
    run(env, |env| {
        let t = tracker(handle)?;
        let from = u64::try_from(from).map_err(|_| bad(format!("from: {from} is negative")))?;
        trajectory_array(env, &t.pipeline, Some(from))
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
        // A part at a time: a whole 500,000-point cloud copied natively at once is
        // tens of MB that the C allocator may keep.
        let n = t.pipeline.cloud_len();
        let take = n.min(max);
        let a = env.new_float_array(take * 4)?;
        let mut part = Vec::with_capacity(CLOUD_CHUNK);
        let mut done = 0;
        while done < take {
            part.clear();
            let end = (done + CLOUD_CHUNK).min(take);
            t.pipeline.cloud_sample_part(n, take, done..end, &mut part);
            let v = cloud_floats(&part, part.len());
            let offset = i32::try_from(done * 4).map_err(|_| bad("cloud too large"))?;
            a.set_region(env, offset, &v)?;
            done = end;
        }
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
        let released = removed
            .as_ref()
            .is_some_and(|t| std::sync::Arc::strong_count(t) == 1);
        drop(removed);
        if released {
            crate::tracker::give_back_memory();
        }
        Ok(())
    })
}
