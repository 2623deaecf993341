//! Warping the template into the current frame, structure of arrays: the template
//! points and the residuals are one `f32` slice per quantity.
//!
//! A warp runs three loops over a chunk: [`project`] moves and projects every point
//! and finds its bilinear cell (a plain loop the compiler vectorises); [`gather`]
//! interpolates the six channels of the level at the points that landed inside it
//! (one 8-lane vector per point: a level's pixel is 32 bytes) and packs those points
//! to the front of the arrays, branch-free, before their channels are split into
//! arrays; [`depth`] turns the interpolated depth
//! into the scaled depth residual (vectorised again). Every point goes through the
//! same IEEE operations, in the same order, as the per-point warp this replaced.

use super::lanes::LANES;
use crate::config::DepthNoiseModel;
use crate::prepare::Sample;
use crate::prepare::simd::multiversion;

/// One chunk of a template, `[x, y, z, intensity]` of each point split into arrays.
#[derive(Clone, Debug, Default)]
pub(super) struct TemplateChunk {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    i: Vec<f32>,
}

impl TemplateChunk {
    /// A chunk with room for `n` points.
    pub(super) fn with_capacity(n: usize) -> Self {
        let v = || Vec::with_capacity(n);
        TemplateChunk {
            x: v(),
            y: v(),
            z: v(),
            i: v(),
        }
    }

    /// Takes the points `pts`.
    pub(super) fn load(&mut self, pts: &[[f32; 4]]) {
        for (c, a) in [&mut self.x, &mut self.y, &mut self.z, &mut self.i]
            .into_iter()
            .enumerate()
        {
            a.clear();
            a.extend(pts.iter().map(|q| q[c]));
        }
    }
}

/// The residuals of one chunk after a warp: the `n` points that landed inside the
/// level, in template order, then neutral points up to a multiple of [`LANES`]
/// (zero residuals, gradients and gain at `(0, 0, 1)`: every sum over them adds
/// zeros), so that the summing loops run on whole blocks.
#[derive(Clone, Debug, Default)]
pub(super) struct Chunk {
    /// Residuals stored.
    pub(super) n: usize,
    /// Residuals with a depth residual.
    pub(super) two: usize,
    /// Photometric residual.
    pub(super) ri: Vec<f32>,
    /// Depth residual times its gain `sz`, NaN when the current depth is missing.
    pub(super) rz: Vec<f32>,
    /// The depth residual's gain: λ, or λ / z² with the quadratic noise model.
    pub(super) sz: Vec<f32>,
    /// Intensity gradient at `u'` (per pixel).
    pub(super) gx: Vec<f32>,
    /// See `gx`.
    pub(super) gy: Vec<f32>,
    /// Depth gradient at `u'` (metres per pixel).
    pub(super) dx: Vec<f32>,
    /// See `dx`.
    pub(super) dy: Vec<f32>,
    /// The warped point `T q` in current-camera coordinates.
    pub(super) x: Vec<f32>,
    /// See `x`.
    pub(super) y: Vec<f32>,
    /// See `x`.
    pub(super) z: Vec<f32>,
    /// Scratch of the warp: index of the bilinear cell's top-left pixel (-1 when the
    /// point misses the level) and the offsets in the cell.
    cell: Vec<i32>,
    ax: Vec<f32>,
    ay: Vec<f32>,
    /// Scratch of the warp: the interpolated pixel of each point kept.
    tmp: Vec<Sample>,
}

impl Chunk {
    /// A chunk with room for `n` template points.
    pub(super) fn with_capacity(n: usize) -> Self {
        let n = n.next_multiple_of(LANES);
        let v = || Vec::with_capacity(n);
        Chunk {
            n: 0,
            two: 0,
            ri: v(),
            rz: v(),
            sz: v(),
            gx: v(),
            gy: v(),
            dx: v(),
            dy: v(),
            x: v(),
            y: v(),
            z: v(),
            cell: Vec::with_capacity(n),
            ax: v(),
            ay: v(),
            tmp: Vec::with_capacity(n),
        }
    }

    /// The stored residuals and the padding after them.
    pub(super) fn padded(&self) -> usize {
        self.n.next_multiple_of(LANES)
    }
}

/// The warp of one linearisation: `T_{j→i}`, the current level's intrinsics and
/// samples. Shared by the chunks of the parallel loop.
pub(super) struct Warp<'a> {
    /// `T_{j→i}`, rows of `[R | t]`.
    pub(super) r: [[f32; 4]; 3],
    /// fx, fy, cx, cy.
    pub(super) f: [f32; 4],
    /// Level width.
    pub(super) w: usize,
    /// Largest u and v a bilinear lookup may start from (exclusive).
    pub(super) max: [f32; 2],
    /// The level's pixels.
    pub(super) samples: &'a [Sample],
    /// λ.
    pub(super) lambda: f32,
    /// The depth residual's gain as a function of depth.
    pub(super) noise: NoiseGain,
    /// False: no photometric term (residuals and gradients zero; see
    /// `Params::photometric`).
    pub(super) photometric: bool,
}

/// The depth residual's gain as a function of the predicted depth z (metres, at
/// least 0.3): λ, `λ / z²`, or `c / √(α + z⁴)` with `c = λ √(α + 1)`
/// ([`DepthNoiseModel`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum NoiseGain {
    /// λ.
    Constant,
    /// `λ / z²`.
    Quadratic,
    /// `c / √(α + z⁴)`.
    Mixed {
        /// α, m⁴.
        alpha: f32,
        /// `λ √(α + 1)`.
        c: f32,
    },
}

impl NoiseGain {
    /// The gain of `model` for depth gain `lambda` (`Fitted` reads as `Quadratic`).
    pub(super) fn of(model: DepthNoiseModel, lambda: f32) -> NoiseGain {
        match model {
            DepthNoiseModel::Constant => NoiseGain::Constant,
            DepthNoiseModel::Quadratic | DepthNoiseModel::Fitted => NoiseGain::Quadratic,
            DepthNoiseModel::Mixed { half_log2_alpha } => {
                let alpha = 2f64.powf(half_log2_alpha as f64 / 2.0);
                NoiseGain::Mixed {
                    alpha: alpha as f32,
                    c: (lambda as f64 * (alpha + 1.0).sqrt()) as f32,
                }
            }
        }
    }

    /// The gain at predicted depth `z`.
    #[inline(always)]
    pub(super) fn at(self, lambda: f32, z: f32) -> f32 {
        match self {
            NoiseGain::Constant => lambda,
            NoiseGain::Quadratic => {
                let ze = z.max(0.3);
                lambda / (ze * ze)
            }
            NoiseGain::Mixed { alpha, c } => {
                let ze = z.max(0.3);
                let z2 = ze * ze;
                c / (alpha + z2 * z2).sqrt()
            }
        }
    }
}

impl Warp<'_> {
    /// Warps the points of `q` and stores the residuals of those that land inside the
    /// level in `out`.
    pub(super) fn run(&self, q: &TemplateChunk, out: &mut Chunk) {
        let m = q.x.len();
        let len = m.next_multiple_of(LANES);
        for a in [
            &mut out.ri,
            &mut out.rz,
            &mut out.sz,
            &mut out.gx,
            &mut out.gy,
            &mut out.dx,
            &mut out.dy,
            &mut out.x,
            &mut out.y,
            &mut out.z,
            &mut out.ax,
            &mut out.ay,
        ] {
            a.resize(len, 0.0);
        }
        out.cell.resize(len, -1);
        out.tmp.resize(len, [0.0; 8]);
        project(
            &self.r,
            &self.f,
            &self.max,
            self.w as i32,
            &q.x,
            &q.y,
            &q.z,
            &mut out.x[..m],
            &mut out.y[..m],
            &mut out.z[..m],
            &mut out.cell[..m],
            &mut out.ax[..m],
            &mut out.ay[..m],
        );
        let n = gather(
            self.samples,
            self.w,
            &q.i,
            &out.cell[..m],
            &out.ax[..m],
            &out.ay[..m],
            &mut out.x[..m],
            &mut out.y[..m],
            &mut out.z[..m],
            &mut out.ri[..m],
            &mut out.tmp[..m],
        );
        depth(
            self.lambda,
            self.noise,
            &out.tmp[..n],
            &out.z[..n],
            &mut out.rz[..n],
            &mut out.sz[..n],
            &mut out.gx[..n],
            &mut out.gy[..n],
            &mut out.dx[..n],
            &mut out.dy[..n],
        );
        if !self.photometric {
            for a in [&mut out.ri, &mut out.gx, &mut out.gy] {
                a[..n].fill(0.0);
            }
        }
        out.n = n;
        out.two = out.rz[..n].iter().filter(|r| r.is_finite()).count();
        let end = n.next_multiple_of(LANES);
        for a in [
            &mut out.ri,
            &mut out.rz,
            &mut out.sz,
            &mut out.gx,
            &mut out.gy,
            &mut out.dx,
            &mut out.dy,
            &mut out.x,
            &mut out.y,
        ] {
            a[n..end].fill(0.0);
        }
        out.z[n..end].fill(1.0);
    }
}

multiversion! {
    /// Moves and projects every template point; `cell` gets the index of the top-left
    /// pixel of its bilinear cell, or -1 when it does not land inside the level.
    fn project(
        r: &[[f32; 4]; 3],
        f: &[f32; 4],
        max: &[f32; 2],
        w: i32,
        qx: &[f32],
        qy: &[f32],
        qz: &[f32],
        x: &mut [f32],
        y: &mut [f32],
        z: &mut [f32],
        cell: &mut [i32],
        ax: &mut [f32],
        ay: &mut [f32],
    ) = project_kernel;
}

#[inline(always)]
fn project_kernel(
    r: &[[f32; 4]; 3],
    f: &[f32; 4],
    max: &[f32; 2],
    w: i32,
    qx: &[f32],
    qy: &[f32],
    qz: &[f32],
    x: &mut [f32],
    y: &mut [f32],
    z: &mut [f32],
    cell: &mut [i32],
    ax: &mut [f32],
    ay: &mut [f32],
) {
    let m = x.len();
    let (qx, qy, qz) = (&qx[..m], &qy[..m], &qz[..m]);
    let (y, z, cell, ax, ay) = (
        &mut y[..m],
        &mut z[..m],
        &mut cell[..m],
        &mut ax[..m],
        &mut ay[..m],
    );
    let [fx, fy, cx, cy] = *f;
    let [umax, vmax] = *max;
    for k in 0..m {
        let q = [qx[k], qy[k], qz[k]];
        let px = r[0][0] * q[0] + r[0][1] * q[1] + r[0][2] * q[2] + r[0][3];
        let py = r[1][0] * q[0] + r[1][1] * q[1] + r[1][2] * q[2] + r[1][3];
        let pz = r[2][0] * q[0] + r[2][1] * q[1] + r[2][2] * q[2] + r[2][3];
        let iz = 1.0 / pz;
        let u = fx * px * iz + cx;
        let v = fy * py * iz + cy;
        // Every comparison is false for NaN.
        let ok = (pz > 1e-3) & (u >= 0.0) & (v >= 0.0) & (u < umax) & (v < vmax);
        let (u, v) = if ok { (u, v) } else { (0.0, 0.0) };
        // SAFETY: 0 <= u, v < the level's size (or 0): in range of i32. (`as` would
        // saturate, which does not vectorise.)
        let (x0, y0): (i32, i32) = unsafe { (u.to_int_unchecked(), v.to_int_unchecked()) };
        x[k] = px;
        y[k] = py;
        z[k] = pz;
        ax[k] = u - x0 as f32;
        ay[k] = v - y0 as f32;
        cell[k] = if ok { y0 * w + x0 } else { -1 };
    }
}

multiversion! {
    /// Bilinear lookup of the six channels at the points whose `cell` is not -1; their
    /// warped coordinates, photometric residual (`qi` is the template's intensity)
    /// and interpolated pixel (all eight lanes, so that it is one vector) are packed
    /// to the front of the arrays, in order. Returns how many there are.
    fn gather(
        s: &[Sample],
        w: usize,
        qi: &[f32],
        cell: &[i32],
        ax: &[f32],
        ay: &[f32],
        x: &mut [f32],
        y: &mut [f32],
        z: &mut [f32],
        ri: &mut [f32],
        tmp: &mut [Sample],
    ) -> usize = gather_kernel;
}

#[inline(always)]
fn gather_kernel(
    s: &[Sample],
    w: usize,
    qi: &[f32],
    cell: &[i32],
    ax: &[f32],
    ay: &[f32],
    x: &mut [f32],
    y: &mut [f32],
    z: &mut [f32],
    ri: &mut [f32],
    tmp: &mut [Sample],
) -> usize {
    let m = cell.len();
    let (qi, ax, ay) = (&qi[..m], &ax[..m], &ay[..m]);
    let (x, y, z) = (&mut x[..m], &mut y[..m], &mut z[..m]);
    let (ri, tmp) = (&mut ri[..m], &mut tmp[..m]);
    let mut n = 0;
    for k in 0..m {
        let c = cell[k];
        // A point outside the level reads the first cell and is not kept.
        let i = c.max(0) as usize;
        let (ax, ay) = (ax[k], ay[k]);
        // One bounds check for the cell's four pixels.
        let cell_px = &s[i..i + w + 2];
        let (p00, p01, p10, p11) = (&cell_px[0], &cell_px[1], &cell_px[w], &cell_px[w + 1]);
        let v = lerp_sample(p00, p01, p10, p11, ax, ay);
        // n <= k: the point is read before its slot is (over)written.
        let (px, py, pz) = (x[k], y[k], z[k]);
        x[n] = px;
        y[n] = py;
        z[n] = pz;
        ri[n] = v[0] - qi[k];
        tmp[n] = v;
        n += (c >= 0) as usize;
    }
    n
}

/// Bilinear interpolation of every channel of a cell's corners `p00 p01` (top row)
/// and `p10 p11` at offsets `(ax, ay)`: along x on both rows, then along y. Three
/// lerps take fewer operations than weighing the four corners, and NaN (missing
/// depth) in any corner still gives NaN. The warp and the per-point reference both
/// interpolate with it.
#[inline(always)]
pub(super) fn lerp_sample(
    p00: &Sample,
    p01: &Sample,
    p10: &Sample,
    p11: &Sample,
    ax: f32,
    ay: f32,
) -> Sample {
    let mut v = [0.0; 8];
    for c in 0..8 {
        let top = p00[c] + ax * (p01[c] - p00[c]);
        let bottom = p10[c] + ax * (p11[c] - p10[c]);
        v[c] = top + ay * (bottom - top);
    }
    v
}

multiversion! {
    /// Splits the interpolated pixels `tmp` into the gradient arrays, turns their
    /// depth into the scaled depth residual `sz (D(u') − z)`, NaN where the depth or
    /// its gradient is missing, and stores the gain `sz`.
    fn depth(
        lambda: f32,
        noise: NoiseGain,
        tmp: &[Sample],
        z: &[f32],
        rz: &mut [f32],
        sz: &mut [f32],
        gx: &mut [f32],
        gy: &mut [f32],
        dx: &mut [f32],
        dy: &mut [f32],
    ) = depth_kernel;
}

#[inline(always)]
fn depth_kernel(
    lambda: f32,
    noise: NoiseGain,
    tmp: &[Sample],
    z: &[f32],
    rz: &mut [f32],
    sz: &mut [f32],
    gx: &mut [f32],
    gy: &mut [f32],
    dx: &mut [f32],
    dy: &mut [f32],
) {
    let n = rz.len();
    let (tmp, z, sz) = (&tmp[..n], &z[..n], &mut sz[..n]);
    let (gx, gy, dx, dy) = (&mut gx[..n], &mut gy[..n], &mut dx[..n], &mut dy[..n]);
    for k in 0..n {
        let v = &tmp[k];
        gx[k] = v[1];
        gy[k] = v[2];
        rz[k] = v[3];
        dx[k] = v[4];
        dy[k] = v[5];
    }
    // One loop per form, so that each vectorises without a branch on the form.
    match noise {
        NoiseGain::Constant => scale_depth(rz, sz, z, dx, dy, |_| lambda),
        NoiseGain::Quadratic => scale_depth(rz, sz, z, dx, dy, |z| noise.at(lambda, z)),
        NoiseGain::Mixed { .. } => scale_depth(rz, sz, z, dx, dy, |z| noise.at(lambda, z)),
    }
}

/// `rz ← gain(z) (rz − z)`, NaN where the depth or its gradient is missing;
/// `sz ← gain(z)`.
#[inline(always)]
fn scale_depth(
    rz: &mut [f32],
    sz: &mut [f32],
    z: &[f32],
    dx: &[f32],
    dy: &[f32],
    gain: impl Fn(f32) -> f32,
) {
    let n = rz.len();
    let (sz, z, dx, dy) = (&mut sz[..n], &z[..n], &dx[..n], &dy[..n]);
    for k in 0..n {
        let r = rz[k] - z[k];
        let ok = r.is_finite() & dx[k].is_finite() & dy[k].is_finite();
        let s = gain(z[k]);
        rz[k] = if ok { s * r } else { f32::NAN };
        sz[k] = s;
    }
}
