//! The image pyramid: compact planes per level, 2x2 downsampling, and the
//! interleaved samples with their gradients.

use super::simd::multiversion;
use super::{D, Sample, TEXTURE_GRADIENT};

/// One level as two compact planes, row-major.
#[derive(Clone, Debug, Default)]
pub(crate) struct Planes {
    /// Intensity in [0, 1].
    pub intensity: Vec<f32>,
    /// Filtered depth in metres, NaN where missing.
    pub depth: Vec<f32>,
}

/// 2x2 downsampling of `src` (`sw` wide) into `dst` of size `dc`: mean intensity;
/// mean depth of the valid pixels when they agree within 3 % (otherwise missing), so
/// depth is never blurred across edges or holes.
#[inline(never)]
pub(crate) fn downsample(src: &Planes, sw: usize, dst: &mut Planes, dc: crate::Camera) {
    let (w, h) = (dc.width, dc.height);
    dst.intensity.resize(w * h, 0.0);
    dst.depth.resize(w * h, f32::NAN);
    for y in 0..h {
        let (i0, z0) = (
            &src.intensity[2 * y * sw..][..2 * w],
            &src.depth[2 * y * sw..][..2 * w],
        );
        let (i1, z1) = (
            &src.intensity[(2 * y + 1) * sw..][..2 * w],
            &src.depth[(2 * y + 1) * sw..][..2 * w],
        );
        let (di, dz) = (
            &mut dst.intensity[y * w..(y + 1) * w],
            &mut dst.depth[y * w..(y + 1) * w],
        );
        for ((d, a), b) in di
            .iter_mut()
            .zip(i0.chunks_exact(2))
            .zip(i1.chunks_exact(2))
        {
            *d = (a[0] + a[1] + b[0] + b[1]) * 0.25;
        }
        for ((d, a), b) in dz
            .iter_mut()
            .zip(z0.chunks_exact(2))
            .zip(z1.chunks_exact(2))
        {
            // Branch-free: a missing (NaN) depth adds +0 to the sum (which is not
            // -0), nothing to the count, and fails both comparisons.
            let (mut sum, mut cnt, mut lo, mut hi) = (0.0f32, 0.0f32, f32::INFINITY, 0.0f32);
            for z in [a[0], a[1], b[0], b[1]] {
                let valid = !z.is_nan();
                sum += if valid { z } else { 0.0 };
                cnt += if valid { 1.0 } else { 0.0 };
                lo = if z < lo { z } else { lo };
                hi = if z > hi { z } else { hi };
            }
            *d = if cnt > 0.0 && hi - lo <= 0.03 * lo {
                sum / cnt
            } else {
                f32::NAN
            };
        }
    }
}

/// The samples of a level (`w` wide) from its planes, each written once:
/// `[I, Ix, Iy, D, Dx, Dy, 0, 0]` with central-difference gradients in units per
/// pixel; at the border the intensity gradient is 0 and the depth gradient missing.
/// Returns how many pixels have depth and an intensity gradient `|Ix| + |Iy|` of at
/// least [`TEXTURE_GRADIENT`].
#[inline(never)]
pub(crate) fn samples(p: &Planes, w: usize, out: &mut Vec<Sample>) -> usize {
    let n = p.intensity.len();
    let h = n / w.max(1);
    if out.len() != n {
        out.clear();
        out.resize(n, [0.0; 8]);
    }
    let (pi, pz) = (&p.intensity, &p.depth);
    let border = |i: usize| [pi[i], 0.0, 0.0, pz[i], f32::NAN, f32::NAN, 0.0, 0.0];
    let textured =
        |s: &Sample| (s[D].is_finite() && s[1].abs() + s[2].abs() >= TEXTURE_GRADIENT) as usize;
    let mut count = 0;
    for (y, row) in out.chunks_exact_mut(w).enumerate() {
        let r = y * w;
        if y == 0 || y + 1 == h || w < 3 {
            for (x, s) in row.iter_mut().enumerate() {
                *s = border(r + x);
                count += textured(s);
            }
            continue;
        }
        let (iu, ic, id) = (&pi[r - w..r], &pi[r..r + w], &pi[r + w..r + 2 * w]);
        let (zu, zc, zd) = (&pz[r - w..r], &pz[r..r + w], &pz[r + w..r + 2 * w]);
        row[0] = border(r);
        row[w - 1] = border(r + w - 1);
        count += textured(&row[0]) + textured(&row[w - 1]);
        for x in 1..w - 1 {
            let s = [
                ic[x],
                0.5 * (ic[x + 1] - ic[x - 1]),
                0.5 * (id[x] - iu[x]),
                zc[x],
                0.5 * (zc[x + 1] - zc[x - 1]),
                0.5 * (zd[x] - zu[x]),
                0.0,
                0.0,
            ];
            count += textured(&s);
            row[x] = s;
        }
    }
    count
}

/// The texture count [`samples`] returns, without writing the samples: the pixels of
/// a level (`w` wide) with depth and an intensity gradient `|Ix| + |Iy|` of at least
/// [`TEXTURE_GRADIENT`] (none on the border, whose gradient is 0).
pub(crate) fn textured(p: &Planes, w: usize) -> usize {
    let n = p.intensity.len();
    let h = n / w.max(1);
    if w < 3 || h < 3 {
        return 0;
    }
    let (pi, pz) = (&p.intensity, &p.depth);
    (1..h - 1)
        .map(|y| {
            let r = y * w;
            textured_row(
                &pi[r - w..r],
                &pi[r..r + w],
                &pi[r + w..r + 2 * w],
                &pz[r..r + w],
            ) as usize
        })
        .sum()
}

multiversion! {
    /// [`textured`]'s count over the interior of one row `ic` (`iu` above, `id` below,
    /// `zc` its depth).
    fn textured_row(iu: &[f32], ic: &[f32], id: &[f32], zc: &[f32]) -> u32 = textured_row_kernel;
}

#[inline(always)]
fn textured_row_kernel(iu: &[f32], ic: &[f32], id: &[f32], zc: &[f32]) -> u32 {
    let w = ic.len();
    let (iu, id, zc) = (&iu[..w], &id[..w], &zc[..w]);
    let mut count = 0u32;
    for x in 1..w - 1 {
        let gx = 0.5 * (ic[x + 1] - ic[x - 1]);
        let gy = 0.5 * (id[x] - iu[x]);
        // Branch-free (`&`, not `&&`), so that it vectorises.
        let has_depth = zc[x].is_finite();
        count += (has_depth & (gx.abs() + gy.abs() >= TEXTURE_GRADIENT)) as u32;
    }
    count
}
