//! Deterministic synthetic RGB-D data with exact ground truth for testing ecvo.
//!
//! * [`Scene::room`]: a textured room (floor, ceiling, four walls) with boxes, ray-cast
//!   exactly. Textures are smooth, band-limited procedural functions evaluated at the exact
//!   3-D hit point, with view-independent shading, so brightness constancy holds exactly.
//! * [`render`]: intensity (anti-aliased, 5 samples per pixel), exact pixel-centre depth (camera z), viewing
//!   angle and surface ids for a camera-to-world pose.
//! * [`DepthNoise`] / [`apply_noise`]: sensor noise (Gaussian depth noise growing with
//!   depth, disparity quantisation, grazing-angle, edge, weak-signal and random
//!   dropouts, flying pixels, image noise; Kinect, phone, time-of-flight presets).
//! * [`CameraPath`]: smooth analytic trajectories (orbit, slow hand-held walk, fast
//!   hand-held shaking and panning at a chosen depth, a far-depth hand-held orbit
//!   panning round [`Scene::hall`]).
//! * [`imu`]: simulated IMUs (gyroscope and accelerometer with a phone's noise, bias,
//!   rotation and time offset) on any trajectory, and a smooth spline through sampled poses.
//! * [`SynthSequence`]: everything together, frame by frame
//!   ([`SynthSequence::phone_320x180`], [`SynthSequence::fast_320x180`],
//!   [`SynthSequence::orbit_320x180`]).
//!
//! Pure and deterministic: no I/O, no threads, no global state.

mod camera;
pub mod imu;
mod noise;
mod orbit;
mod path;
mod render;
pub mod rng;
mod scene;
mod sequence;
mod texture;

pub use camera::SynthCamera;
pub use noise::{
    DepthNoise, EdgeDropout, FlyingPixels, LowSignal, apply_noise, edge_mask, metres_to_raw,
    to_raw_depth,
};
pub use orbit::{ORBIT_DEPTH_RANGE_M, ORBIT_RADIUS_M, hall_apothem};
pub use path::{CameraPath, FAST_PERIOD_S, Harmonic, look_at};
pub use render::{NO_SURFACE, Rendered, render, render_supersampled};
pub use scene::{Hit, ROOM_SURFACES, RayOrigin, Scene, SceneBox};
pub use sequence::{
    FAST_MAX_ANGULAR_SPEED, FAST_MAX_LINEAR_SPEED, FAST_WALL_SURFACE, SynthFrame, SynthSequence,
};
pub use texture::Texture;
