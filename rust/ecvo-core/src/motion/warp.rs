//! Warping the template into the current frame: residuals and what the Jacobians need.

use crate::prepare::Sample;
use crate::scale;

/// One warped template point: its residuals and what its Jacobian needs.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Residual {
    /// Photometric residual.
    pub(super) ri: f32,
    /// Depth residual times its gain `sz`, NaN when the current depth is missing there.
    pub(super) rz: f32,
    /// The depth residual's gain: λ, or λ / z² with the quadratic noise model.
    pub(super) sz: f32,
    /// Intensity gradient at `u'` (per pixel).
    pub(super) gx: f32,
    pub(super) gy: f32,
    /// Depth gradient at `u'` (metres per pixel).
    pub(super) dx: f32,
    pub(super) dy: f32,
    /// The warped point `T q` in current-camera coordinates.
    pub(super) p: [f32; 3],
}

impl scale::Pair for Residual {
    #[inline(always)]
    fn ri(&self) -> f32 {
        self.ri
    }
    #[inline(always)]
    fn rz(&self) -> f32 {
        self.rz
    }
}

/// The warp of one linearisation: `T_{j→i}`, the current level's intrinsics and
/// samples. Shared by the chunks of the parallel loop.
pub(super) struct Warp<'a> {
    pub(super) r: [[f32; 4]; 3],
    /// fx, fy, cx, cy.
    pub(super) f: [f32; 4],
    pub(super) w: usize,
    /// Largest u and v a bilinear lookup may start from (exclusive).
    pub(super) max: [f32; 2],
    pub(super) samples: &'a [Sample],
    pub(super) lambda: f32,
    pub(super) quadratic: bool,
}

impl Warp<'_> {
    /// Warps `points` and stores the residuals of those that land inside the level.
    pub(super) fn run(&self, points: &[[f32; 4]], out: &mut Vec<Residual>) {
        let r = &self.r;
        let [fx, fy, cx, cy] = self.f;
        let [umax, vmax] = self.max;
        out.clear();
        for q in points {
            let x = r[0][0] * q[0] + r[0][1] * q[1] + r[0][2] * q[2] + r[0][3];
            let y = r[1][0] * q[0] + r[1][1] * q[1] + r[1][2] * q[2] + r[1][3];
            let z = r[2][0] * q[0] + r[2][1] * q[1] + r[2][2] * q[2] + r[2][3];
            if z <= 1e-3 {
                continue;
            }
            let iz = 1.0 / z;
            let u = fx * x * iz + cx;
            let v = fy * y * iz + cy;
            // `!(a >= b)` also rejects NaN.
            if !(u >= 0.0 && v >= 0.0 && u < umax && v < vmax) {
                continue;
            }
            let s = bilinear(self.samples, self.w, u, v);
            let ri = s[0] - q[3];
            let rz = s[3] - z;
            let depth_ok = rz.is_finite() && s[4].is_finite() && s[5].is_finite();
            // The depth residual's gain: λ, over z² for the quadratic noise model.
            let sz = if self.quadratic {
                let ze = z.max(0.3);
                self.lambda / (ze * ze)
            } else {
                self.lambda
            };
            out.push(Residual {
                ri,
                rz: if depth_ok { sz * rz } else { f32::NAN },
                sz,
                gx: s[1],
                gy: s[2],
                dx: s[4],
                dy: s[5],
                p: [x, y, z],
            });
        }
    }
}

/// Bilinear lookup of all channels at `(u, v)`; the caller guarantees
/// `0 <= u < w - 1` and `0 <= v < h - 1`. Missing depth (NaN) propagates.
#[inline(always)]
fn bilinear(s: &[Sample], w: usize, u: f32, v: f32) -> Sample {
    let (x0, y0) = (u as usize, v as usize);
    let (ax, ay) = (u - x0 as f32, v - y0 as f32);
    let i = y0 * w + x0;
    let (p00, p01, p10, p11) = (&s[i], &s[i + 1], &s[i + w], &s[i + w + 1]);
    let (w00, w01, w10, w11) = (
        (1.0 - ax) * (1.0 - ay),
        ax * (1.0 - ay),
        (1.0 - ax) * ay,
        ax * ay,
    );
    std::array::from_fn(|c| w00 * p00[c] + w01 * p01[c] + w10 * p10[c] + w11 * p11[c])
}
