//! The numbers that cross the boundary: code tables, array layouts and conversions
//! shared with the Kotlin side (`TrackerConfig.kt`, `TimedPose.kt`, `TrackerStats.kt`).

use ecvo_core::{LostReason, Pose, TrackingState};
use ecvo_pipeline::{CloudPoint, LatestPose, PipelineStats, PoseRecord};
use jni::sys::{jint, jlong};

/// What `nativeGetPose` returns when there is no pose yet (`Tracker.NO_POSE`).
pub const NO_POSE: jlong = jlong::MIN;

/// Doubles per pose in `nativeTrajectory` (`TimedPose.STRIDE`).
pub const POSE_STRIDE: usize = 8;

/// Poses a session keeps (`Tracker.TRAJECTORY_WINDOW`): about 18 minutes at 30 Hz, 2.9
/// MB. Older poses are discarded, so that a session of any length holds a constant
/// amount of memory; a UI reading `trajectorySince` at every poll keeps its own copy.
pub const TRAJECTORY_WINDOW: usize = 32_768;

/// Doubles per reference in `nativeReferences` (`ReferenceFrame.STRIDE`).
pub const REFERENCE_STRIDE: usize = 9;

/// Doubles in `nativeStats` (`TrackerStats.SIZE`).
pub const STATS_SIZE: usize = 21;

/// Doubles in `nativeFrameQuality` (`FrameQuality.SIZE`; layout in [`quality_doubles`]).
pub const QUALITY_SIZE: usize = 53;

/// `io.ecvo.LostReason` codes: 0 while not lost, then the [`LostReason`] variants in
/// their declaration order, 1 ([`LostReason::NoValidDepth`]) to 7
/// ([`LostReason::SpreadJump`]).
pub fn lost_reason_code(reason: Option<LostReason>) -> u8 {
    match reason {
        None => 0,
        Some(LostReason::NoValidDepth) => 1,
        Some(LostReason::TooFewPoints) => 2,
        Some(LostReason::Degenerate) => 3,
        Some(LostReason::Diverged) => 4,
        Some(LostReason::Inconsistent) => 5,
        Some(LostReason::ImplausibleSpeed) => 6,
        Some(LostReason::SpreadJump) => 7,
    }
}

/// `io.ecvo.TrackingState` codes (`nativeState`).
pub fn state_code(tracked: u64, state: TrackingState) -> u8 {
    match state {
        _ if tracked == 0 => 0,
        TrackingState::Initialising => 0,
        TrackingState::Tracking => 1,
        TrackingState::Lost => 2,
    }
}

/// The latest frame and the quality of its registration as the [`QUALITY_SIZE`]
/// doubles of `nativeFrameQuality` (`FrameQuality.kt` reads them):
///
/// | index | value |
/// |---|---|
/// | 0 | frame index (0-based, in tracking order) |
/// | 1 | state code (0 initialising, 1 tracking, 2 lost) |
/// | 2 | lost reason code ([`lost_reason_code`]) |
/// | 3..11 | pose: t (s), tx, ty, tz, qx, qy, qz, qw, as `nativeTrajectory` |
/// | 11..47 | 6x6 information matrix, row-major, ordered (rx, ry, rz, tx, ty, tz) as Open3D and ecvo-py (the engine's twist is `[v; ω]`); zeros without a registration |
/// | 47..50 | residual scale Σ_II, Σ_IZ, Σ_ZZ; NaN without one |
/// | 50 | template points that landed on valid pixels at the finest step |
/// | 51 | template points of the finest step |
/// | 52 | reference levels (the frame became the reference at 1..=n) |
///
/// Nothing is allocated: it fills `out`.
pub fn quality_doubles(latest: &LatestPose, out: &mut [f64; QUALITY_SIZE]) {
    out[0] = latest.tracked.saturating_sub(1) as f64;
    out[1] = f64::from(state_code(latest.tracked, latest.state));
    out[2] = f64::from(lost_reason_code(latest.lost_reason));
    let t = latest.pose.translation.vector;
    let q = latest.pose.rotation.quaternion();
    out[3..11].copy_from_slice(&[latest.timestamp, t.x, t.y, t.z, q.i, q.j, q.k, q.w]);
    let reg = latest.registration.as_ref();
    // The engine orders the twist [v; ω]; Open3D (and ecvo-py) [ω; v].
    let swap = |k: usize| (k + 3) % 6;
    for i in 0..6 {
        for j in 0..6 {
            out[11 + 6 * i + j] = reg.map_or(0.0, |r| r.information[(swap(i), swap(j))]);
        }
    }
    let scale = reg.and_then(|r| r.scale);
    out[47..50].copy_from_slice(&scale.map_or([f64::NAN; 3], |s| [s.ii, s.iz, s.zz]));
    out[50] = reg.map_or(0.0, |r| r.valid_pixels as f64);
    out[51] = reg.map_or(0.0, |r| r.template_points as f64);
    out[52] = f64::from(latest.reference_levels);
}

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

/// The 21 doubles of `nativeStats` (layout in `TrackerStats.kt`; 15..21 are the IMU's
/// counters, `Counters::imu`).
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
        s.poses_discarded as f64,
        c.imu.samples as f64,
        c.imu.refused as f64,
        c.imu.dropped as f64,
        c.imu.priors as f64,
        c.imu.late as f64,
        c.imu.missing as f64,
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
