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
        }
    }

    /// Camera position at time `t` (seconds).
    pub fn position_at(&self, t: f64) -> Point3<f64> {
        let theta = self.angle0 + self.angular_rate * t + sum(&self.angle_wobble, t);
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
        self.target + Vector3::new(sum(tx, t), sum(ty, t), sum(tz, t))
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
