//! Smooth, exact camera trajectories.
//!
//! A path is an (elliptic) orbit around a point of interest plus sums of sinusoids on
//! the orbit angle, the position, the look-at target and the roll. Everything is an
//! analytic function of time, so poses at any time are exact and deterministic.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::rng::Rng;

/// One sinusoidal term `amplitude * sin(omega * t + phase)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Harmonic {
    /// Amplitude (units of the quantity it perturbs).
    pub amplitude: f64,
    /// Angular frequency, rad/s.
    pub omega: f64,
    /// Phase, radians.
    pub phase: f64,
}

impl Harmonic {
    /// Value at time `t` (seconds).
    #[inline]
    pub fn eval(&self, t: f64) -> f64 {
        self.amplitude * (self.omega * t + self.phase).sin()
    }

    /// Draws a harmonic with the given amplitude and a random frequency in
    /// `[omega_lo, omega_hi)` and random phase.
    fn random(rng: &mut Rng, amplitude: f64, omega_lo: f64, omega_hi: f64) -> Self {
        Self {
            amplitude,
            omega: rng.range(omega_lo, omega_hi),
            phase: rng.angle(),
        }
    }
}

/// Sum of harmonics.
fn sum(terms: &[Harmonic], t: f64) -> f64 {
    terms.iter().map(|h| h.eval(t)).sum()
}

/// A smooth camera trajectory (camera-to-world poses as analytic functions of time).
///
/// Camera position at time `t`:
/// `(cx + rx cos θ(t) + Σ dx, cy + ry sin θ(t) + Σ dy, height + Σ dz)` with
/// `θ(t) = angle0 + angular_rate t + Σ dθ`; the camera looks at `target + Σ (tx, ty, tz)`
/// with the image y axis as close to world down (−z) as possible, then rolls by `Σ roll`
/// about its optical axis.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    /// Orbit centre (x, y used).
    pub orbit_centre: Point3<f64>,
    /// Orbit semi-axis along x, metres.
    pub radius_x: f64,
    /// Orbit semi-axis along y, metres.
    pub radius_y: f64,
    /// Orbit angle at t = 0, radians.
    pub angle0: f64,
    /// Mean orbit angular rate, rad/s (sign = direction).
    pub angular_rate: f64,
    /// Perturbations of the orbit angle, radians.
    pub angle_wobble: Vec<Harmonic>,
    /// Mean camera height, metres.
    pub height: f64,
    /// Position perturbations along world x, y, z, metres.
    pub position_wobble: [Vec<Harmonic>; 3],
    /// Mean look-at target.
    pub target: Point3<f64>,
    /// Target perturbations along world x, y, z, metres.
    pub target_wobble: [Vec<Harmonic>; 3],
    /// Roll about the optical axis, radians.
    pub roll: Vec<Harmonic>,
    /// `Some(d)`: the camera looks outward from the orbit centre instead of at
    /// `target`: at the point `d` metres from its orbit position (without the position
    /// wobble) along the orbit's radial direction (at the height of `target`), with `target_wobble`
    /// read as offsets along that direction, across it (horizontal, towards the
    /// increasing orbit angle) and up (world z), so that the wobble pans and tilts the
    /// same way whichever way the camera faces.
    pub look_outward: Option<f64>,
}

/// Camera-to-world rotation looking from `eye` towards `target` with image y as close
/// to world −z as possible.
pub fn look_at(eye: &Point3<f64>, target: &Point3<f64>) -> Rotation3<f64> {
    let z = (target - eye).normalize();
    let down = -Vector3::z();
    let x = down.cross(&z).normalize();
    let y = z.cross(&x);
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]))
}

impl CameraPath {
    /// Circular orbit of `radius` around `centre` at `height`, always looking at `centre`,
    /// with angular speed `angular_speed` (rad/s) and no perturbations.
    pub fn smooth_orbit(centre: Point3<f64>, radius: f64, height: f64, angular_speed: f64) -> Self {
        Self {
            orbit_centre: centre,
            radius_x: radius,
            radius_y: radius,
            angle0: 0.0,
            angular_rate: angular_speed,
            angle_wobble: Vec::new(),
            height,
            position_wobble: Default::default(),
            target: centre,
            target_wobble: Default::default(),
            roll: Vec::new(),
            look_outward: None,
        }
    }

    /// Plausible hand-held trajectory in [`crate::Scene::room`]: a slow elliptic walk
    /// around the central box cluster (1.85 m x 1.45 m semi-axes, ≈ 0.2 m/s) at about
    /// 1.45 m height, looking down at the boxes, with slow sway, head bob, small roll and
    /// a little high-frequency hand shake. Typical speeds: 0.15–0.35 m/s, 5–25 °/s.
    /// Stays more than 0.8 m from every surface of that room.
    pub fn handheld(seed: u64) -> Self {
        let mut rng = Rng::new(seed ^ 0xC0FF_EE00_0000_0001);
        let h = Harmonic::random;
        let angular_rate = rng.sign() * rng.range(0.10, 0.13);
        Self {
            orbit_centre: Point3::new(0.0, 0.0, 0.0),
            radius_x: 1.85,
            radius_y: 1.45,
            angle0: rng.angle(),
            angular_rate,
            angle_wobble: vec![h(&mut rng, 0.25, 0.15, 0.25)],
            height: 1.45,
            position_wobble: [
                vec![h(&mut rng, 0.06, 0.4, 0.7), h(&mut rng, 0.003, 7.0, 9.0)],
                vec![h(&mut rng, 0.06, 0.4, 0.7), h(&mut rng, 0.003, 7.0, 9.0)],
                vec![
                    h(&mut rng, 0.10, 0.3, 0.45),
                    h(&mut rng, 0.02, 1.6, 2.0),
                    h(&mut rng, 0.002, 8.0, 10.0),
                ],
            ],
            target: Point3::new(0.0, 0.0, 0.5),
            target_wobble: [
                vec![h(&mut rng, 0.25, 0.2, 0.35), h(&mut rng, 0.02, 1.5, 2.5)],
                vec![h(&mut rng, 0.25, 0.2, 0.35), h(&mut rng, 0.02, 1.5, 2.5)],
                vec![h(&mut rng, 0.15, 0.3, 0.5)],
            ],
            roll: vec![h(&mut rng, 0.05, 0.4, 0.6), h(&mut rng, 0.004, 6.0, 8.0)],
            look_outward: None,
        }
    }

    /// Orbit angle at time `t` (seconds), radians.
    fn angle_at(&self, t: f64) -> f64 {
        self.angle0 + self.angular_rate * t + sum(&self.angle_wobble, t)
    }

    /// Camera position at time `t` (seconds).
    pub fn position_at(&self, t: f64) -> Point3<f64> {
        let theta = self.angle_at(t);
        let [wx, wy, wz] = &self.position_wobble;
        Point3::new(
            self.orbit_centre.x + self.radius_x * theta.cos() + sum(wx, t),
            self.orbit_centre.y + self.radius_y * theta.sin() + sum(wy, t),
            self.height + sum(wz, t),
        )
    }

    /// Look-at target at time `t` (seconds).
    pub fn target_at(&self, t: f64) -> Point3<f64> {
        let [tx, ty, tz] = &self.target_wobble;
        let Some(distance) = self.look_outward else {
            return self.target + Vector3::new(sum(tx, t), sum(ty, t), sum(tz, t));
        };
        let theta = self.angle_at(t);
        let (s, c) = theta.sin_cos();
        let radial = Vector3::new(c, s, 0.0);
        let across = Vector3::new(-s, c, 0.0);
        let base = Point3::new(
            self.orbit_centre.x + self.radius_x * c,
            self.orbit_centre.y + self.radius_y * s,
            self.target.z,
        );
        base + radial * (distance + sum(tx, t)) + across * sum(ty, t) + Vector3::z() * sum(tz, t)
    }

    /// Camera-to-world pose at time `t` (seconds); camera looks along its +z axis,
    /// x right, y down.
    pub fn pose_at(&self, t: f64) -> Isometry3<f64> {
        let eye = self.position_at(t);
        let r = look_at(&eye, &self.target_at(t))
            * Rotation3::from_axis_angle(&Vector3::z_axis(), sum(&self.roll, t));
        Isometry3::from_parts(
            Translation3::from(eye.coords),
            UnitQuaternion::from_rotation_matrix(&r),
        )
    }
}

/// Period of [`CameraPath::fast_handheld`], seconds: every frequency of that path is a
/// whole multiple of `2π / FAST_PERIOD_S`, so any 5 s of it holds its peak speeds.
pub const FAST_PERIOD_S: f64 = 5.0;

/// Height of the camera of [`CameraPath::fast_handheld`] above the floor, metres.
const FAST_HEIGHT_M: f64 = 1.5;

/// World y of the camera of [`CameraPath::fast_handheld`], metres: clear of the central
/// box cluster (|y| < 0.6) and of the chest against the far wall (y < -0.2).
const FAST_Y_M: f64 = 0.9;

/// A harmonic of [`CameraPath::fast_handheld`]: random whole multiple `k` of the base
/// frequency `2π / FAST_PERIOD_S` in `k_lo..=k_hi`, random phase, unit amplitude
/// times `weight`.
pub(crate) fn fast_harmonic(rng: &mut Rng, weight: f64, k_lo: u64, k_hi: u64) -> Harmonic {
    let k = k_lo + rng.next_u64() % (k_hi - k_lo + 1);
    Harmonic {
        amplitude: weight,
        omega: k as f64 * std::f64::consts::TAU / FAST_PERIOD_S,
        phase: rng.angle(),
    }
}

/// Scales the amplitudes of harmonics.
pub(crate) fn scaled(terms: &[Harmonic], s: f64) -> Vec<Harmonic> {
    terms
        .iter()
        .map(|h| Harmonic {
            amplitude: h.amplitude * s,
            ..*h
        })
        .collect()
}

/// Peak frame-to-frame (`dt` apart) linear (m/s) and angular (rad/s) speeds of a path,
/// over every start time on a fine grid of one period of [`CameraPath::fast_handheld`].
pub(crate) fn peak_speeds(path: &CameraPath, dt: f64) -> (f64, f64) {
    const STEPS: usize = 600;
    let (mut v, mut w) = (0.0f64, 0.0f64);
    for i in 0..STEPS {
        let t = i as f64 * FAST_PERIOD_S / STEPS as f64;
        let rel = path.pose_at(t).inverse() * path.pose_at(t + dt);
        v = v.max(rel.translation.vector.norm() / dt);
        w = w.max(rel.rotation.angle() / dt);
    }
    (v, w)
}

impl CameraPath {
    /// Fast hand-held motion in front of the wall `x = 3` of [`crate::Scene::room`],
    /// seen from `depth` metres (0.5–4 m): the camera stands at
    /// `(3 − depth, 0.9, 1.5)`, looks along +x and shakes, sways and pans so that its
    /// peak speed over 30 Hz frames is exactly `max_linear_speed` (m/s) and its peak
    /// rotation rate exactly `max_angular_speed` (rad/s).
    ///
    /// The path is periodic with period [`FAST_PERIOD_S`] (5 s, 150 frames at 30 Hz),
    /// so every 150 consecutive frames reach both peaks (within the 30 Hz sampling of
    /// that period). Translation: sums of sinusoids mostly across the view (sideways and
    /// up and down), little along it, so the distance to the wall stays near `depth`.
    /// Rotation: the look-at target moves with the camera plus a pan/tilt of its own
    /// (mostly pan) and a roll, so that translation does not turn the camera.
    ///
    /// # Panics
    /// If `depth` is outside 0.4–4.5 m or a speed is not positive.
    pub fn fast_handheld(
        seed: u64,
        depth: f64,
        max_angular_speed: f64,
        max_linear_speed: f64,
    ) -> Self {
        assert!(
            (0.4..=4.5).contains(&depth),
            "fast_handheld: depth {depth} m outside 0.4–4.5 m"
        );
        assert!(max_angular_speed > 0.0 && max_linear_speed > 0.0);
        let mut rng = Rng::new(seed ^ 0xFA57_0000_0000_0002);
        let f = fast_harmonic;
        // Translation, unscaled (camera frame: along the view = world x).
        let across = vec![f(&mut rng, 1.0, 1, 2), f(&mut rng, 0.5, 3, 5)];
        let up = vec![f(&mut rng, 0.6, 1, 3), f(&mut rng, 0.3, 4, 6)];
        let along = vec![f(&mut rng, 0.12 * depth.min(1.0), 1, 3)];
        // Rotation, unscaled: pan (target offset across / depth ≈ angle), tilt, roll.
        let pan = vec![f(&mut rng, 1.0, 1, 2), f(&mut rng, 0.4, 3, 5)];
        let tilt = vec![f(&mut rng, 0.45, 1, 3), f(&mut rng, 0.2, 4, 6)];
        let roll = vec![f(&mut rng, 0.3, 1, 3), f(&mut rng, 0.1, 4, 6)];

        let build = |st: f64, sr: f64| {
            let eye = [scaled(&along, st), scaled(&across, st), scaled(&up, st)];
            // The target follows the camera's translation, plus the pan and tilt.
            let mut target = eye.clone();
            target[1].extend(scaled(&pan, sr * depth));
            target[2].extend(scaled(&tilt, sr * depth));
            Self {
                orbit_centre: Point3::new(3.0 - depth, FAST_Y_M, 0.0),
                radius_x: 0.0,
                radius_y: 0.0,
                angle0: 0.0,
                angular_rate: 0.0,
                angle_wobble: Vec::new(),
                height: FAST_HEIGHT_M,
                position_wobble: eye,
                target: Point3::new(3.0, FAST_Y_M, FAST_HEIGHT_M),
                target_wobble: target,
                roll: scaled(&roll, sr),
                look_outward: None,
            }
        };
        let dt = 1.0 / 30.0;
        // Linear speed depends on the translation scale only (and linearly).
        let st = max_linear_speed / peak_speeds(&build(1.0, 0.0), dt).0;
        // Angular speed grows with the rotation scale: bisect for it.
        let (mut lo, mut hi) = (0.0, 1.0);
        while peak_speeds(&build(st, hi), dt).1 < max_angular_speed {
            hi *= 2.0;
        }
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if peak_speeds(&build(st, mid), dt).1 < max_angular_speed {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        build(st, 0.5 * (lo + hi))
    }
}
