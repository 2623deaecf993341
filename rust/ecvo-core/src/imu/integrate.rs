//! The gyro's rotation over an interval: the rates interpolated linearly between
//! samples and integrated piecewise by the midpoint rule (exact for rates linear in
//! time about a fixed axis, and so for a constant rate).

use nalgebra::{UnitQuaternion, Vector3};

use super::{GyroRing, MAX_SAMPLE_GAP_S};

/// Why the samples could not give a rotation over an interval.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// No sample at all.
    Empty,
    /// The newest sample ends more than [`MAX_SAMPLE_GAP_S`] before the interval does.
    Late,
    /// The oldest sample starts more than [`MAX_SAMPLE_GAP_S`] after the interval, or
    /// two samples inside it are further apart than that.
    Missing,
}

/// `∏ Exp((ω(t) − bias) dt)` over `[a, b]` on the IMU's clock and in its frame:
/// the rotation of the IMU at `b` in its frame at `a` (`R_{a←b}`), for body rates
/// `ω`. The rate is interpolated linearly between samples and held beyond the first
/// and last (for at most [`MAX_SAMPLE_GAP_S`]).
pub fn integrate(
    ring: &GyroRing,
    a: f64,
    b: f64,
    bias: &Vector3<f64>,
) -> Result<UnitQuaternion<f64>, Coverage> {
    let n = ring.len();
    let (Some(first), Some(last)) = ((n > 0).then(|| ring.get(0)), ring.last()) else {
        return Err(Coverage::Empty);
    };
    if last.t < b - MAX_SAMPLE_GAP_S {
        return Err(Coverage::Late);
    }
    if first.t > a + MAX_SAMPLE_GAP_S {
        return Err(Coverage::Missing);
    }
    let mut q = UnitQuaternion::identity();
    if !(b > a) {
        return Ok(q);
    }
    // The last sample at or before `a` (or the first one, just after it).
    let mut j = ring.count_at_or_before(a).saturating_sub(1);
    let mut u = a;
    loop {
        let l = ring.get(j);
        let r = (j + 1 < n).then(|| ring.get(j + 1));
        let end = match r {
            Some(r) if r.t < b => r.t,
            _ => b,
        };
        let v = end.max(u);
        if v > u {
            if let Some(r) = r
                && r.t - l.t > MAX_SAMPLE_GAP_S
            {
                return Err(Coverage::Missing);
            }
            let m = 0.5 * (u + v);
            let w = match r {
                Some(r) if r.t > l.t => {
                    let f = ((m - l.t) / (r.t - l.t)).clamp(0.0, 1.0);
                    Vector3::from_fn(|k, _| l.w[k] + f * (r.w[k] - l.w[k]))
                }
                _ => Vector3::from(l.w),
            };
            q *= UnitQuaternion::from_scaled_axis((w - bias) * (v - u));
        }
        u = v;
        if u >= b || r.is_none() {
            break;
        }
        j += 1;
    }
    q.renormalize();
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imu::GyroSample;

    fn ring_of(rate: f64, from: f64, to: f64, w: impl Fn(f64) -> [f64; 3]) -> GyroRing {
        let mut r = GyroRing::new((rate * (to - from)) as usize + 2);
        let mut t = from;
        while t <= to {
            r.push(GyroSample { t, w: w(t) });
            t += 1.0 / rate;
        }
        r
    }

    /// A rate changing linearly in time about a fixed axis: the integral is exact
    /// whatever the sampling, and the interval's ends fall between samples.
    #[test]
    fn integration_matches_an_analytic_rotation() {
        let axis = Vector3::new(0.3, -0.8, 0.5).normalize();
        // ω(t) = (1 + 6 t) rad/s about `axis`: the angle over [a, b] is
        // (b − a) + 3 (b² − a²).
        let ring = ring_of(200.0, 0.0, 1.0, |t| (axis * (1.0 + 6.0 * t)).into());
        let (a, b) = (0.1234, 0.1567);
        let q = integrate(&ring, a, b, &Vector3::zeros()).unwrap();
        let angle = (b - a) + 3.0 * (b * b - a * a);
        let want = UnitQuaternion::from_scaled_axis(axis * angle);
        assert!(q.angle_to(&want) < 1e-12, "{}", q.angle_to(&want));
        // A known bias is taken off: the same rates plus a bias give the same rotation.
        let bias = Vector3::new(0.02, -0.01, 0.03);
        let biased = ring_of(200.0, 0.0, 1.0, |t| (axis * (1.0 + 6.0 * t) + bias).into());
        let qb = integrate(&biased, a, b, &bias).unwrap();
        assert!(qb.angle_to(&want) < 1e-12, "{}", qb.angle_to(&want));
        // Rotating about a changing axis, the piecewise product converges to the
        // exact rotation: a 360 °/s spin about z precessing at 1 rad/s about x,
        // against a fine sampling of the same rates.
        let w = |t: f64| [0.0, 0.6 * t.sin(), 6.0];
        let coarse = integrate(&ring_of(400.0, 0.0, 1.0, w), 0.2, 0.233, &Vector3::zeros());
        let fine = integrate(
            &ring_of(40000.0, 0.0, 1.0, w),
            0.2,
            0.233,
            &Vector3::zeros(),
        );
        let (coarse, fine) = (coarse.unwrap(), fine.unwrap());
        assert!(coarse.angle_to(&fine) < 1e-6, "{}", coarse.angle_to(&fine));
    }

    #[test]
    fn integration_says_what_is_missing() {
        let z = Vector3::zeros();
        let w = |_| [0.0, 0.0, 1.0];
        assert_eq!(
            integrate(&GyroRing::new(8), 0.0, 1.0, &z),
            Err(Coverage::Empty)
        );
        let ring = ring_of(200.0, 1.0, 2.0, w);
        assert_eq!(integrate(&ring, 1.5, 2.1, &z), Err(Coverage::Late));
        assert_eq!(integrate(&ring, 0.9, 1.1, &z), Err(Coverage::Missing));
        // Within the slack at both ends: held rates.
        let q = integrate(&ring, 0.99, 2.01, &z).unwrap();
        assert!((q.angle() - 1.02).abs() < 1e-9, "{}", q.angle());
        // A hole of 50 ms inside the interval.
        let mut holed = GyroRing::new(64);
        for t in [0.0, 0.005, 0.01, 0.06, 0.065, 0.07] {
            holed.push(GyroSample { t, w: w(t) });
        }
        assert_eq!(integrate(&holed, 0.0, 0.07, &z), Err(Coverage::Missing));
        assert!(integrate(&holed, 0.06, 0.07, &z).is_ok());
    }
}
