//! The far-depth hand-held orbit: a large octagonal hall with furniture along its walls
//! ([`Scene::hall`]), a camera that circles near the hall's centre while panning round
//! to look at the walls from a chosen distance ([`CameraPath::far_orbit`]), and the
//! sequence of both ([`SynthSequence::orbit_320x180`]).

use nalgebra::{Point3, Vector3};

use crate::path::{CameraPath, fast_harmonic, peak_speeds, scaled};
use crate::rng::Rng;
use crate::scene::{ROOM_SURFACES, Scene, SceneBox};
use crate::sequence::SynthSequence;

/// Radius of the circle the camera of [`CameraPath::far_orbit`] walks, metres.
pub const ORBIT_RADIUS_M: f64 = 0.3;

/// Height of the camera of [`CameraPath::far_orbit`], metres.
const ORBIT_HEIGHT_M: f64 = 1.5;

/// Height of the point looked at (a slight downward tilt), metres.
const ORBIT_TARGET_HEIGHT_M: f64 = 1.35;

/// Height of [`Scene::hall`], metres.
const HALL_HEIGHT_M: f64 = 3.0;

/// Share of the peak rotation rate of [`CameraPath::far_orbit`] that its hand-held
/// jitter alone reaches; the steady pan supplies the rest.
const JITTER_SHARE: f64 = 0.2;

/// Range of viewing distances of [`CameraPath::far_orbit`] and [`Scene::hall`], metres.
pub const ORBIT_DEPTH_RANGE_M: (f64, f64) = (1.0, 4.5);

/// Apothem of the hall (distance from its centre to the middle of each of its eight
/// walls) for a viewing distance `depth`: the camera stands [`ORBIT_RADIUS_M`] off the
/// centre looking outward, the furniture stands in front of some walls and the view
/// of an octagon's corner reaches further, the floor and ceiling nearer;
/// `1.03 depth + ORBIT_RADIUS_M + 0.1` puts the mean depth of the rendered frames
/// within a few per cent of `depth` at 320x180 and 640x480 (`tests/it/orbit.rs`).
pub fn hall_apothem(depth: f64) -> f64 {
    1.03 * depth + ORBIT_RADIUS_M + 0.1
}

impl Scene {
    /// A hall for viewing its walls from `depth` metres (1–4.5): a regular octagon of
    /// apothem [`hall_apothem`]`(depth)` (a square room, floor at z = 0, 3 m high,
    /// centred on the z axis, whose corners are cut off by four boxes turned by 45°),
    /// with cabinets, chests, shelves and wall-mounted boxes in front of seven of
    /// the eight walls and the middle left free for the camera. Every texture is
    /// stretched by `depth / 2` (clamped to 0.5–2), as for the fast path, so that the
    /// detail in pixels is about that of the standard room from 2 m. The geometry
    /// depends on `depth` only; `seed` only changes the textures.
    ///
    /// # Panics
    /// If `depth` is outside [`ORBIT_DEPTH_RANGE_M`].
    pub fn hall(seed: u64, depth: f64) -> Self {
        let (lo, hi) = ORBIT_DEPTH_RANGE_M;
        assert!(
            (lo..=hi).contains(&depth),
            "hall: depth {depth} m outside {lo}–{hi} m"
        );
        let l = hall_apothem(depth);
        let h = HALL_HEIGHT_M;
        let v = Vector3::new;
        let quarter = std::f64::consts::FRAC_PI_4;
        let mut boxes = Vec::new();
        // The corners: a box turned by 45° centred on each corner, its inner face at
        // the apothem (half side l (√2 − 1)).
        let a = l * (std::f64::consts::SQRT_2 - 1.0);
        for (x, y) in [(l, l), (-l, l), (-l, -l), (l, -l)] {
            boxes.push(SceneBox::on_floor(
                0.0,
                x,
                y,
                v(a, a, h / 2.0 + 0.05),
                quarter,
            ));
        }
        // Furniture in front of the walls: (wall k at angle k·45°, offset along the
        // wall as a share of the apothem, depth, half width, half height, height of
        // the centre or None to stand on the floor).
        let w = (l / 3.0).clamp(0.7, 1.5);
        let items: [(u32, f64, f64, f64, f64, Option<f64>); 9] = [
            (0, -0.15, 0.25, 0.45 * w, 0.9, None),
            (0, 0.25, 0.08, 0.20 * w, 0.15, Some(1.7)),
            (1, 0.05, 0.35, 0.55 * w, 0.4, None),
            (2, 0.2, 0.2, 0.3 * w, 1.0, None),
            (3, -0.1, 0.1, 0.3 * w, 0.2, Some(1.5)),
            (4, 0.0, 0.3, 0.7 * w, 0.35, None),
            (4, -0.1, 0.06, 0.25 * w, 0.25, Some(1.9)),
            (6, -0.2, 0.25, 0.35 * w, 0.75, None),
            (7, 0.15, 0.12, 0.2 * w, 0.3, Some(1.2)),
        ];
        for (k, along, depth_m, half_w, half_h, centre_z) in items {
            let phi = k as f64 * quarter;
            let (s, c) = phi.sin_cos();
            let r = l - depth_m;
            let t = along * l;
            let (x, y) = (r * c - t * s, r * s + t * c);
            let half = v(depth_m, half_w, half_h);
            boxes.push(match centre_z {
                None => SceneBox::on_floor(0.0, x, y, half, phi),
                Some(z) => SceneBox::new(Point3::new(x, y, z), half, phi),
            });
        }
        let mut scene = Self::new(Point3::new(-l, -l, 0.0), Point3::new(l, l, h), boxes, seed);
        let stretch = (depth / 2.0).clamp(0.5, 2.0);
        for s in 0..scene.surface_count() {
            scene.scale_texture(s, stretch);
        }
        debug_assert_eq!(scene.surface_count(), ROOM_SURFACES + 6 * 13);
        scene
    }
}

impl CameraPath {
    /// A far-depth hand-held orbit in [`Scene::hall`]`(_, depth)`: the camera walks a
    /// circle of radius [`ORBIT_RADIUS_M`] round the hall's centre at 1.5 m height,
    /// facing outward (a little down), so that it pans round the hall's walls and
    /// furniture at a viewing distance of about `depth`, and its peak rotation rate over
    /// 30 Hz frames is `max_angular_speed` (rad/s; to within the 30 Hz sampling): a
    /// steady pan (the walk's rate) plus hand-held jitter (sway of about 2 cm and a
    /// 7–9 Hz shake of about 1.5 mm in position; pan, tilt and roll wobble), the
    /// jitter alone reaching a fifth of the peak. The direction of the walk, its start
    /// and the jitter come from `seed`. The jitter is periodic with
    /// [`crate::FAST_PERIOD_S`] and the steady pan turns the whole path, so any 150
    /// frames at 30 Hz reach the peak. Linear speed: the walk's `0.3 m × rate` plus the
    /// sway (peaks of 0.28 m/s at 30°/s, 0.42 m/s at 60°/s).
    ///
    /// # Panics
    /// If `depth` is outside [`ORBIT_DEPTH_RANGE_M`] or the speed is not positive.
    pub fn far_orbit(seed: u64, depth: f64, max_angular_speed: f64) -> Self {
        let (lo, hi) = ORBIT_DEPTH_RANGE_M;
        assert!(
            (lo..=hi).contains(&depth),
            "far_orbit: depth {depth} m outside {lo}–{hi} m"
        );
        assert!(max_angular_speed > 0.0 && max_angular_speed.is_finite());
        let mut rng = Rng::new(seed ^ 0x0B17_0000_0000_0003);
        let f = fast_harmonic;
        let direction = rng.sign();
        let angle0 = rng.angle();
        // Translation jitter, metres (absolute): sway and shake.
        let sway = |rng: &mut Rng| vec![f(rng, 0.02, 1, 3), f(rng, 0.0015, 35, 45)];
        let position = [sway(&mut rng), sway(&mut rng), sway(&mut rng)];
        // Rotation jitter, unscaled (radians; target offsets are angle × depth).
        let walk = vec![f(&mut rng, 0.05, 1, 2)];
        let pan = vec![f(&mut rng, 0.04, 2, 4), f(&mut rng, 0.002, 30, 40)];
        let tilt = vec![f(&mut rng, 0.03, 1, 3), f(&mut rng, 0.002, 30, 40)];
        let roll = vec![f(&mut rng, 0.02, 1, 3), f(&mut rng, 0.001, 30, 40)];
        let build = |rate: f64, jitter: f64| Self {
            orbit_centre: Point3::origin(),
            radius_x: ORBIT_RADIUS_M,
            radius_y: ORBIT_RADIUS_M,
            angle0,
            angular_rate: direction * rate,
            angle_wobble: scaled(&walk, jitter),
            height: ORBIT_HEIGHT_M,
            position_wobble: position.clone(),
            target: Point3::new(0.0, 0.0, ORBIT_TARGET_HEIGHT_M),
            target_wobble: [
                Vec::new(),
                scaled(&pan, jitter * depth),
                scaled(&tilt, jitter * depth),
            ],
            roll: scaled(&roll, jitter),
            look_outward: Some(depth),
        };
        let dt = 1.0 / 30.0;
        let peak = |p: &Self| peak_speeds(p, dt).1;
        // The jitter alone reaches JITTER_SHARE of the peak (its rotation grows about
        // linearly with its scale, and the sway adds a little turn of its own).
        let jitter = bisect(|s| peak(&build(0.0, s)), JITTER_SHARE * max_angular_speed);
        let rate = bisect(|r| peak(&build(r, jitter)), max_angular_speed);
        build(rate, jitter)
    }
}

/// The `x ≥ 0` at which the increasing function `g` reaches `goal` (bisection to
/// 2⁻³⁰ of the bracket), 0 if `g(0)` is already at or above it.
fn bisect(g: impl Fn(f64) -> f64, goal: f64) -> f64 {
    if g(0.0) >= goal {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    while g(hi) < goal {
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if g(mid) < goal {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

impl SynthSequence {
    /// [`Self::phone_320x180`] with the far-depth orbit instead of the slow walk:
    /// [`Scene::hall`] and [`CameraPath::far_orbit`] at viewing distance `depth`
    /// (metres) and peak rotation rate `max_angular_speed` (rad/s), both from `seed`.
    pub fn orbit_320x180(frames: usize, seed: u64, depth: f64, max_angular_speed: f64) -> Self {
        Self {
            scene: Scene::hall(seed, depth),
            path: CameraPath::far_orbit(seed, depth, max_angular_speed),
            ..Self::phone_320x180(frames, seed)
        }
    }
}

impl CameraPath {
    /// A fast in-place pan (issue 47) in [`Scene::hall`]`(_, depth)`: the camera
    /// stands at the hall's centre at 1.5 m height and pans round its walls, its pan
    /// rate swinging between 0 and `max_angular_speed` (rad/s) every
    /// [`crate::FAST_PERIOD_S`] / 2 (pan, slow to a halt, pan again: the
    /// accelerations a constant-velocity prediction misses), with a hand's small
    /// tilt and roll wobble (0.02 and 0.01 rad) and a 5 mm sway. Direction, start
    /// and wobble from `seed`.
    ///
    /// # Panics
    /// If `depth` is outside [`ORBIT_DEPTH_RANGE_M`] or the speed is not positive.
    pub fn in_place_pan(seed: u64, depth: f64, max_angular_speed: f64) -> Self {
        let (lo, hi) = ORBIT_DEPTH_RANGE_M;
        assert!(
            (lo..=hi).contains(&depth),
            "in_place_pan: depth {depth} m outside {lo}–{hi} m"
        );
        assert!(max_angular_speed > 0.0 && max_angular_speed.is_finite());
        let mut rng = Rng::new(seed ^ 0x9A40_0000_0000_0047);
        let f = fast_harmonic;
        let direction = rng.sign();
        let angle0 = rng.angle();
        // The pan rate: half the peak, plus a swing of half the peak (two cycles a
        // period), so that it goes from 0 to the peak and back.
        let mut swing = f(&mut rng, 1.0, 2, 2);
        swing.amplitude = 0.5 * max_angular_speed / swing.omega;
        let sway = |rng: &mut Rng| vec![f(rng, 0.005, 1, 3)];
        let position = [sway(&mut rng), sway(&mut rng), sway(&mut rng)];
        let tilt = vec![f(&mut rng, 0.02 * depth, 1, 3)];
        let roll = vec![f(&mut rng, 0.01, 1, 3)];
        Self {
            orbit_centre: Point3::origin(),
            radius_x: 0.0,
            radius_y: 0.0,
            angle0,
            angular_rate: direction * 0.5 * max_angular_speed,
            angle_wobble: scaled(&[swing], direction),
            height: ORBIT_HEIGHT_M,
            position_wobble: position,
            target: Point3::new(0.0, 0.0, ORBIT_TARGET_HEIGHT_M),
            target_wobble: [Vec::new(), Vec::new(), tilt],
            roll,
            look_outward: Some(depth),
        }
    }
}

impl SynthSequence {
    /// [`Self::phone_320x180`] with a fast in-place pan: [`Scene::hall`] and
    /// [`CameraPath::in_place_pan`] at viewing distance `depth` (metres) and peak pan
    /// rate `max_angular_speed` (rad/s), both from `seed`.
    pub fn pan_320x180(frames: usize, seed: u64, depth: f64, max_angular_speed: f64) -> Self {
        Self {
            scene: Scene::hall(seed, depth),
            path: CameraPath::in_place_pan(seed, depth, max_angular_speed),
            ..Self::phone_320x180(frames, seed)
        }
    }
}
