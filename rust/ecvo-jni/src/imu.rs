//! Gyroscope samples through JNI (issue 47): `nativePushImu` (one sample) and
//! `nativePushImuBatch` (one sensor callback's worth, from primitive arrays, one JNI
//! crossing), into [`ecvo_pipeline::Pipeline::push_imu`].
//!
//! Timestamps are nanoseconds on the frames' clock (`SensorEvent.timestamp` put on the
//! camera's clock by the app) and become the engine's seconds as frame timestamps do
//! ([`ns_to_seconds`]); rates are rad/s in the IMU's axes. The tracker's
//! `ImuCalibration` is the default (the IMU aligned with the camera, on its clock): the
//! Kotlin `Tracker` rotates and shifts the samples by its own calibration before they
//! cross. A batch is read in fixed chunks of [`CHUNK`] samples into stack buffers, so a
//! push allocates nothing whatever its size; it is checked whole before any of it is
//! taken (a non-finite rate refuses the batch, as the engine does).

use ecvo_core::imu::GyroSample;
use jni::Env;
use jni::objects::{JClass, JFloatArray, JLongArray};
use jni::sys::{jdouble, jint, jlong};

use crate::error::{Failure, bad, run};
use crate::layout::ns_to_seconds;
use crate::tracker::tracker;

/// Samples read per step of a batch.
pub const CHUNK: usize = 256;

/// Most samples one batch call takes: 10 s at 400 Hz, beyond what one sensor callback
/// or one frame's worth ever holds (the pipeline's inbox keeps 8192).
pub const MAX_BATCH: usize = 4096;

fn sample(timestamp_ns: jlong, w: [f64; 3]) -> GyroSample {
    GyroSample {
        t: ns_to_seconds(timestamp_ns),
        w,
    }
}

/// Says which sample of the batch is bad, in the Kotlin caller's terms.
fn check(i: usize, s: &GyroSample) -> Result<(), Failure> {
    if s.w.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(bad(format!(
            "rates: sample {i} ({:?} rad/s) is not finite; none of the batch was taken",
            s.w
        )))
    }
}

pub(crate) fn native_push_imu<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    timestamp_ns: jlong,
    wx: jdouble,
    wy: jdouble,
    wz: jdouble,
) -> jni::errors::Result<()> {
    run(env, |_| {
        let t = tracker(handle)?;
        let s = sample(timestamp_ns, [wx, wy, wz]);
        check(0, &s)?;
        Ok(t.pipeline.push_imu(&[s])?)
    })
}

/// Reads samples `from..from + n` (n <= CHUNK) of the batch into `out`.
fn read_chunk(
    env: &Env<'_>,
    stamps: &JLongArray<'_>,
    rates: &JFloatArray<'_>,
    from: usize,
    out: &mut [GyroSample; CHUNK],
    n: usize,
) -> Result<(), Failure> {
    let mut ts = [0i64; CHUNK];
    let mut w = [0f32; 3 * CHUNK];
    let at = |k: usize| i32::try_from(k).map_err(|_| bad("batch too large"));
    stamps.get_region(env, at(from)?, &mut ts[..n])?;
    rates.get_region(env, at(3 * from)?, &mut w[..3 * n])?;
    for (k, s) in out[..n].iter_mut().enumerate() {
        *s = sample(
            ts[k],
            [
                f64::from(w[3 * k]),
                f64::from(w[3 * k + 1]),
                f64::from(w[3 * k + 2]),
            ],
        );
    }
    Ok(())
}

pub(crate) fn native_push_imu_batch<'local>(
    env: &mut Env<'local>,
    _class: JClass<'local>,
    handle: jlong,
    timestamps_ns: JLongArray<'local>,
    rates: JFloatArray<'local>,
    count: jint,
) -> jni::errors::Result<()> {
    run(env, |env| {
        let t = tracker(handle)?;
        if timestamps_ns.is_null() {
            return Err(bad("timestampsNs: array is null"));
        }
        if rates.is_null() {
            return Err(bad("rates: array is null"));
        }
        let n = usize::try_from(count).map_err(|_| bad(format!("count: {count} is negative")))?;
        if n > MAX_BATCH {
            return Err(bad(format!(
                "count: {n} samples in one batch, more than {MAX_BATCH}; push them in smaller batches"
            )));
        }
        let (lt, lr) = (timestamps_ns.len(env)?, rates.len(env)?);
        if lt < n {
            return Err(bad(format!(
                "timestampsNs: array has {lt} values, count is {n}"
            )));
        }
        if lr < 3 * n {
            return Err(bad(format!(
                "rates: array has {lr} values, {n} samples need {} (wx, wy, wz each)",
                3 * n
            )));
        }
        let env = &*env;
        let mut buf = [GyroSample::default(); CHUNK];
        // Checked whole first: a bad sample anywhere refuses the batch.
        for from in (0..n).step_by(CHUNK) {
            let m = CHUNK.min(n - from);
            read_chunk(env, &timestamps_ns, &rates, from, &mut buf, m)?;
            for (k, s) in buf[..m].iter().enumerate() {
                check(from + k, s)?;
            }
        }
        for from in (0..n).step_by(CHUNK) {
            let m = CHUNK.min(n - from);
            read_chunk(env, &timestamps_ns, &rates, from, &mut buf, m)?;
            t.pipeline.push_imu(&buf[..m])?;
        }
        Ok(())
    })
}
