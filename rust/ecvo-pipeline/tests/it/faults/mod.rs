//! Fault injection on the tracker: a synthetic phone stream (320x180, ground truth
//! known) with a fault in frames `START..START + LEN`, run through the sequential
//! engine (`Odometry`) and through the pipeline (offline), frame by frame.
//!
//! Shared by `tests/it/fault_injection.rs` (which asserts on the results) and
//! `examples/faults.rs` (which prints the table of the README):
//! `cargo run --release -p ecvo-pipeline --example faults`.

#![allow(dead_code)]

use ecvo_core::nalgebra::{Translation3, UnitQuaternion, Vector3};
use ecvo_core::{Camera, Config, FrameView, Mode, Odometry, Pose, Preset, TrackingState, se3};
use ecvo_pipeline::{Admission, Pipeline, PipelineOptions, PushStatus};
use ecvo_synth::{SynthCamera, SynthSequence, apply_noise, render};

/// Frames in a run.
pub const FRAMES: usize = 60;
/// First faulty frame.
pub const START: usize = 20;
/// Faulty frames.
pub const LEN: usize = 5;
/// A tracked frame whose frame-to-frame motion is further than this from the truth
/// (metres, degrees) is wrong.
pub const WRONG_M: f64 = 0.02;
/// See [`WRONG_M`].
pub const WRONG_DEG: f64 = 2.0;
/// Frames in a row that must be tracked for tracking to count as recovered.
pub const STABLE: usize = 5;

/// The faults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// Intensity all 0 (depth still valid).
    BlackIntensity,
    /// Covered lens: intensity and depth all 0.
    CoveredLens,
    /// The last good frame delivered again and again (new timestamps).
    FrozenFrame,
    /// The camera jumps 30 cm and 20° between two frames and stays displaced.
    Jump30cm20deg,
    /// Each faulty frame carries the previous frame's timestamp.
    DuplicatedTimestamps,
    /// Timestamps run backwards through the faulty frames.
    BackwardsTimestamps,
    /// Depth and intensity are random numbers (NaN-free by construction).
    GarbageDepth,
    /// The lens zooms: focal lengths 30 % longer than the configured camera's.
    IntrinsicsZoom,
    /// The same zoom, announced: the caller passes the new intrinsics
    /// (`set_intrinsics`) with the first zoomed frame, and the old ones back after.
    IntrinsicsZoomAnnounced,
    /// The frames come at another resolution (160x90) than the configured 320x180.
    IntrinsicsResolution,
}

impl Fault {
    /// Every fault, in table order.
    pub const ALL: [Fault; 10] = [
        Fault::BlackIntensity,
        Fault::CoveredLens,
        Fault::FrozenFrame,
        Fault::Jump30cm20deg,
        Fault::DuplicatedTimestamps,
        Fault::BackwardsTimestamps,
        Fault::GarbageDepth,
        Fault::IntrinsicsZoom,
        Fault::IntrinsicsZoomAnnounced,
        Fault::IntrinsicsResolution,
    ];

    /// The name in the table.
    pub fn name(self) -> &'static str {
        match self {
            Fault::BlackIntensity => "black frames (intensity 0)",
            Fault::CoveredLens => "covered lens (all-zero depth, black)",
            Fault::FrozenFrame => "frozen frame repeated",
            Fault::Jump30cm20deg => "sudden 30 cm / 20° jump",
            Fault::DuplicatedTimestamps => "duplicated timestamps",
            Fault::BackwardsTimestamps => "backwards timestamps",
            Fault::GarbageDepth => "garbage depth and intensity",
            Fault::IntrinsicsZoom => "intrinsics change: fx, fy x1.3, not told",
            Fault::IntrinsicsZoomAnnounced => "intrinsics change: fx, fy x1.3, `set_intrinsics`",
            Fault::IntrinsicsResolution => "intrinsics change: 160x90 frames",
        }
    }
}

/// One frame as pushed, with the true camera pose.
pub struct Input {
    pub timestamp: f64,
    pub intensity: Vec<u8>,
    pub depth: Vec<u16>,
    pub truth: Pose,
    /// New intrinsics the caller passes before this frame (`set_intrinsics`).
    pub announce: Option<Camera>,
}

/// What happened to one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// The push failed with an error.
    Rejected,
    /// The pipeline reported the frame bit-identical to the previous one
    /// (`PushStatus::Repeated`) and did not track it.
    Repeated,
    /// Tracked with this state and pose.
    Tracked(TrackingState, Pose),
}

/// The engine a stream runs through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// `ecvo_core::Odometry`.
    Core,
    /// `ecvo_pipeline::Pipeline`, offline, 2 threads.
    Pipeline,
}

/// The figures of one run.
#[derive(Clone, Debug)]
pub struct Report {
    pub fault: Fault,
    pub engine: Engine,
    pub outcomes: Vec<Outcome>,
    /// Faulty frames rejected by `push`.
    pub rejected: usize,
    /// Faulty frames reported repeated by `push` (not tracked).
    pub repeated: usize,
    /// Faulty frames flagged `Lost`.
    pub lost: usize,
    /// Faulty frames tracked with a frame-to-frame motion close to the truth.
    pub tracked_ok: usize,
    /// Faulty frames reported `Tracking` with a wrong motion: silently wrong.
    pub silently_wrong: usize,
    /// Frames from the first faulty one to the first flagged (rejected or lost) one,
    /// counting both (1 = flagged at once); `None`: never flagged.
    pub detected_after: Option<usize>,
    /// Good frames after the fault until `STABLE` frames in a row are tracked, the
    /// first of them counted (1 = the first good frame tracks); `None`: never.
    pub recovered_after: Option<usize>,
    /// Good frames after the fault reported `Tracking` with a wrong motion.
    pub wrong_after: usize,
    /// Error of the estimated motion from the last frame before the fault to the last
    /// frame of the stream, against the truth (metres, degrees).
    pub drift_m: f64,
    pub drift_deg: f64,
    /// Every pose finite.
    pub finite: bool,
}

fn camera_of(c: &SynthCamera) -> Camera {
    Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    }
}

/// The configuration every run uses (phone preset, L2).
pub fn config() -> Config {
    Config::new(
        camera_of(&SynthCamera::phone_320x180()),
        Preset::Phone,
        Mode::L2,
    )
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// The sequence every stream is made from.
fn sequence() -> SynthSequence {
    SynthSequence::phone_320x180(FRAMES, 11)
}

/// The frames of [`sequence`] as it renders them (intensity, depth), rendered once per
/// process: every fault's stream keeps most of them unchanged, and rendering costs
/// more than tracking.
fn clean_frames() -> &'static [(Vec<u8>, Vec<u16>)] {
    static CLEAN: std::sync::OnceLock<Vec<(Vec<u8>, Vec<u16>)>> = std::sync::OnceLock::new();
    CLEAN.get_or_init(|| {
        let seq = sequence();
        (0..FRAMES)
            .map(|i| {
                let f = seq.frame(i);
                (f.intensity, f.depth)
            })
            .collect()
    })
}

/// The stream with `fault` in frames `START..START + LEN`.
pub fn stream(fault: Fault) -> Vec<Input> {
    let seq = sequence();
    let jump = Pose::from_parts(
        Translation3::new(0.3, 0.0, 0.0),
        UnitQuaternion::from_scaled_axis(Vector3::y() * 20f64.to_radians()),
    );
    let faulty = |i: usize| (START..START + LEN).contains(&i);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut out: Vec<Input> = Vec::with_capacity(FRAMES);
    for i in 0..FRAMES {
        let mut timestamp = seq.timestamp(i);
        let mut truth = seq.pose(i);
        let mut camera = seq.camera;
        let jumped = fault == Fault::Jump30cm20deg && i >= START;
        if jumped {
            truth *= jump;
        }
        let zoom = matches!(
            fault,
            Fault::IntrinsicsZoom | Fault::IntrinsicsZoomAnnounced
        );
        let zoomed = zoom && faulty(i);
        if zoomed {
            camera.fx *= 1.3;
            camera.fy *= 1.3;
        }
        let resized = fault == Fault::IntrinsicsResolution && faulty(i);
        if resized {
            camera = SynthCamera {
                width: 160,
                height: 90,
                fx: 125.0,
                fy: 125.0,
                cx: 79.5,
                cy: 44.5,
                depth_scale: 1000.0,
            };
        }
        let (mut intensity, mut depth) = if fault == Fault::FrozenFrame && faulty(i) {
            let last = &out[START - 1];
            (last.intensity.clone(), last.depth.clone())
        } else if !(jumped || zoomed || resized) {
            // What the render below gives with the sequence's own camera and pose.
            clean_frames()[i].clone()
        } else {
            let r = render(&seq.scene, &camera, &truth);
            apply_noise(&r, &camera, &seq.noise, seq.frame_seed(i))
        };
        if faulty(i) {
            match fault {
                Fault::BlackIntensity => intensity.fill(0),
                Fault::CoveredLens => {
                    intensity.fill(0);
                    depth.fill(0);
                }
                Fault::GarbageDepth => {
                    for (g, d) in intensity.iter_mut().zip(depth.iter_mut()) {
                        let r = rng.next();
                        *g = r as u8;
                        *d = (r >> 8) as u16;
                    }
                }
                Fault::DuplicatedTimestamps => timestamp = out[i - 1].timestamp,
                Fault::BackwardsTimestamps => {
                    timestamp = seq.timestamp(START - 1) - (i + 1 - START) as f64 / seq.fps
                }
                _ => {}
            }
        }
        let announce = (fault == Fault::IntrinsicsZoomAnnounced
            && (i == START || i == START + LEN))
            .then(|| camera_of(&camera));
        out.push(Input {
            timestamp,
            intensity,
            depth,
            truth,
            announce,
        });
    }
    out
}

/// Runs `inputs` through `engine`; one outcome per input.
pub fn run(engine: Engine, inputs: &[Input]) -> Vec<Outcome> {
    let config = config();
    match engine {
        Engine::Core => {
            let mut odo = Odometry::new(config).expect("valid configuration");
            inputs
                .iter()
                .map(|f| {
                    if let Some(c) = f.announce {
                        odo.set_intrinsics(c).expect("valid intrinsics");
                    }
                    match odo.push(FrameView {
                        timestamp: f.timestamp,
                        intensity: &f.intensity,
                        depth: &f.depth,
                    }) {
                        Ok(o) => Outcome::Tracked(o.state, o.pose),
                        Err(_) => Outcome::Rejected,
                    }
                })
                .collect()
        }
        Engine::Pipeline => {
            let p = Pipeline::new(
                config,
                PipelineOptions {
                    threads: 2,
                    admission: Admission::Offline,
                    keep_trajectory: true,
                    ..PipelineOptions::default()
                },
            )
            .expect("valid options");
            let pushed: Vec<Option<PushStatus>> = inputs
                .iter()
                .map(|f| {
                    if let Some(c) = f.announce {
                        p.set_intrinsics(c).expect("valid intrinsics");
                    }
                    p.push_view(FrameView {
                        timestamp: f.timestamp,
                        intensity: &f.intensity,
                        depth: &f.depth,
                    })
                    .ok()
                })
                .collect();
            let summary = p.finish().expect("the pipeline finishes");
            let mut records = summary.trajectory.iter();
            pushed
                .iter()
                .map(|status| match status {
                    None => Outcome::Rejected,
                    Some(PushStatus::Repeated) => Outcome::Repeated,
                    Some(_) => {
                        let r = records.next().expect("one record per queued frame");
                        Outcome::Tracked(r.state, r.pose)
                    }
                })
                .collect()
        }
    }
}

fn motion_error(est: &Pose, truth: &Pose) -> (f64, f64) {
    let e = est.inverse() * truth;
    (e.translation.vector.norm(), se3::angle(&e).to_degrees())
}

/// The figures of `outcomes` against the truth of `inputs`.
pub fn report(fault: Fault, engine: Engine, inputs: &[Input], outcomes: Vec<Outcome>) -> Report {
    let end = START + LEN;
    let mut r = Report {
        fault,
        engine,
        outcomes: Vec::new(),
        rejected: 0,
        repeated: 0,
        lost: 0,
        tracked_ok: 0,
        silently_wrong: 0,
        detected_after: None,
        recovered_after: None,
        wrong_after: 0,
        drift_m: f64::NAN,
        drift_deg: f64::NAN,
        finite: true,
    };
    // The last frame tracked (not lost) before frame i, for frame-to-frame motions.
    let mut last: Option<(Pose, Pose)> = None;
    let mut run = 0usize;
    for (i, (o, f)) in outcomes.iter().zip(inputs).enumerate() {
        let faulty = (START..end).contains(&i);
        let flagged = match o {
            Outcome::Rejected => {
                if faulty {
                    r.rejected += 1;
                }
                true
            }
            Outcome::Repeated => {
                if faulty {
                    r.repeated += 1;
                }
                true
            }
            Outcome::Tracked(state, pose) => {
                r.finite &= se3::is_finite(pose);
                let wrong = match (state, last) {
                    (TrackingState::Tracking, Some((pe, pt))) => {
                        let (m, d) =
                            motion_error(&(pe.inverse() * pose), &(pt.inverse() * f.truth));
                        m > WRONG_M || d > WRONG_DEG
                    }
                    _ => false,
                };
                let lost = *state == TrackingState::Lost;
                if faulty {
                    if lost {
                        r.lost += 1;
                    } else if wrong {
                        r.silently_wrong += 1;
                    } else {
                        r.tracked_ok += 1;
                    }
                } else if i >= end && wrong {
                    r.wrong_after += 1;
                }
                // A lost frame keeps the last good pose: motions are measured from
                // the last frame that was not lost.
                if !lost {
                    last = Some((*pose, f.truth));
                }
                lost
            }
        };
        if faulty && flagged && r.detected_after.is_none() {
            r.detected_after = Some(i - START + 1);
        }
        if i >= end {
            run = if flagged { 0 } else { run + 1 };
            if run == STABLE && r.recovered_after.is_none() {
                r.recovered_after = Some(i + 1 - STABLE - end + 1);
            }
        }
    }
    if let (Outcome::Tracked(_, before), Outcome::Tracked(_, after)) =
        (outcomes[START - 1], outcomes[FRAMES - 1])
    {
        let (m, d) = motion_error(
            &(before.inverse() * after),
            &(inputs[START - 1].truth.inverse() * inputs[FRAMES - 1].truth),
        );
        r.drift_m = m;
        r.drift_deg = d;
    }
    r.outcomes = outcomes;
    r
}

/// Runs one fault through one engine.
pub fn measure(fault: Fault, engine: Engine) -> Report {
    let inputs = stream(fault);
    let outcomes = run(engine, &inputs);
    report(fault, engine, &inputs, outcomes)
}

fn opt(v: Option<usize>) -> String {
    v.map_or_else(|| "never".to_string(), |v| v.to_string())
}

/// The markdown table of the README.
pub fn table(reports: &[Report]) -> String {
    let mut s = format!(
        "| fault ({LEN} frames from frame {START} of {FRAMES}) | engine | rejected | repeated (not tracked) | flagged lost | tracked right | silently wrong | detected after | recovered after | wrong after | drift across fault (cm / °) | finite |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for r in reports {
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} / {:.2} | {} |\n",
            r.fault.name(),
            match r.engine {
                Engine::Core => "core",
                Engine::Pipeline => "pipeline",
            },
            r.rejected,
            r.repeated,
            r.lost,
            r.tracked_ok,
            r.silently_wrong,
            opt(r.detected_after),
            opt(r.recovered_after),
            r.wrong_after,
            r.drift_m * 100.0,
            r.drift_deg,
            if r.finite { "yes" } else { "NO" },
        );
    }
    s
}
