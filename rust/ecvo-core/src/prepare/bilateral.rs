//! Raw depth to metres, and the bilateral filter over valid pixels.

use super::rows;
use super::simd::multiversion;

/// How raw depth becomes metres: `z = raw * scale`, missing when `raw` is 0 or `z`
/// is outside `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthRange {
    pub scale: f32,
    pub lo: f32,
    pub hi: f32,
}

impl DepthRange {
    /// Depth in metres, or `missing`.
    #[inline(always)]
    fn metres(&self, d: u16, missing: f32) -> f32 {
        let z = d as f32 * self.scale;
        if d != 0 && z >= self.lo && z <= self.hi {
            z
        } else {
            missing
        }
    }
}

/// Depth in metres, NaN where missing (the output when there is no bilateral filter).
#[inline(never)]
pub(crate) fn load_plain(raw: &[u16], range: DepthRange, out: &mut [f32]) {
    for (o, &d) in out.iter_mut().zip(raw) {
        *o = range.metres(d, f32::NAN);
    }
}

/// Depth in metres with missing pixels as 0, padded by `radius` zeros on every
/// side: a tap outside the image, like a missing pixel, gets range weight exactly 0
/// (config validation keeps σ small enough for that), so the padded filter adds the
/// same terms in the same order as one clipped at the border. The padding is
/// written only when the buffer is (re)sized: the interior covers the rest.
#[inline(never)]
pub(crate) fn load_padded(
    raw: &[u16],
    w: usize,
    h: usize,
    radius: usize,
    range: DepthRange,
    padded: &mut Vec<f32>,
) {
    fill_padded(raw, w, h, radius, padded, |z| range.metres(z, 0.0));
}

/// [`load_padded`] from depth already in metres (NaN where missing): a coarser
/// level's planes, for the half-resolution filter of a lookup frame.
#[inline(never)]
pub(crate) fn load_padded_metres(
    depth: &[f32],
    w: usize,
    h: usize,
    radius: usize,
    padded: &mut Vec<f32>,
) {
    fill_padded(depth, w, h, radius, padded, |z| {
        if z.is_nan() { 0.0 } else { z }
    });
}

/// The interior of a padded buffer (`radius` zeros on every side, written when the
/// buffer is (re)sized) from `src`, `w` x `h`, each pixel through `metres`.
#[inline(always)]
fn fill_padded<T: Copy>(
    src: &[T],
    w: usize,
    h: usize,
    radius: usize,
    padded: &mut Vec<f32>,
    metres: impl Fn(T) -> f32,
) {
    let pw = w + 2 * radius;
    let len = pw * (h + 2 * radius);
    if padded.len() != len {
        padded.clear();
        padded.resize(len, 0.0);
    }
    for (dst, src) in padded[radius * pw..]
        .chunks_exact_mut(pw)
        .zip(src.chunks_exact(w))
    {
        for (d, &z) in dst[radius..radius + w].iter_mut().zip(src) {
            *d = metres(z);
        }
    }
}

/// The bilateral filter of `padded` (from [`load_padded`]) into `out` (`w` wide),
/// NaN where the centre is missing. The range weight is `(1 − x/4)⁴` for
/// `x = Δz² / (2σ²)`, clamped at 0: it follows `exp(−x)` closely near 0, is exactly 0
/// beyond 2.8σ, and keeps the inner loop free of branches and table lookups. σ is
/// `sigma_rel` times the centre depth. Missing neighbours enter as depth 0, whose
/// range weight is 0.
pub(crate) fn filter(
    padded: &[f32],
    spatial: &[f32],
    w: usize,
    radius: usize,
    sigma_rel: f32,
    out: &mut [f32],
) {
    rows(out, w, |y, row| {
        filter_row(padded, spatial, w, radius, sigma_rel, y, row)
    });
}

multiversion! {
    /// One output row of [`filter`].
    fn filter_row(
        padded: &[f32],
        spatial: &[f32],
        w: usize,
        radius: usize,
        sigma_rel: f32,
        y: usize,
        out: &mut [f32],
    ) = filter_row_kernel;
}

#[inline(always)]
fn filter_row_kernel(
    padded: &[f32],
    spatial: &[f32],
    w: usize,
    radius: usize,
    sigma_rel: f32,
    y: usize,
    out: &mut [f32],
) {
    // Blocks of pixels, each filtered tap after tap. A whole block is a fixed 16
    // pixels, whose sums stay in registers over all the taps (one AVX-512 vector,
    // two AVX or four SSE/NEON ones); the row's last pixels take a shorter block.
    // Two calls, not a closure: a closure is compiled as a function of its own,
    // without this copy's target features (seen in the AVX-512 disassembly).
    const B: usize = 16;
    let pw = w + 2 * radius;
    let whole = w - w % B;
    for bx in (0..whole).step_by(B) {
        filter_block::<B>(
            padded,
            spatial,
            pw,
            radius,
            sigma_rel,
            y,
            bx,
            B,
            &mut out[bx..bx + B],
        );
    }
    if whole < w {
        filter_block::<B>(
            padded,
            spatial,
            pw,
            radius,
            sigma_rel,
            y,
            whole,
            w - whole,
            &mut out[whole..w],
        );
    }
}

/// The pixels `bx..bx + n` (`n <= N`) of output row `y`. Every pixel adds its taps
/// in the same order, whatever the block: the results do not depend on `N`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn filter_block<const N: usize>(
    padded: &[f32],
    spatial: &[f32],
    pw: usize,
    radius: usize,
    sigma_rel: f32,
    y: usize,
    bx: usize,
    n: usize,
    out: &mut [f32],
) {
    let side = 2 * radius + 1;
    // A short block is padded with the row's own pixels; they are not stored.
    let mut zc = [0.0f32; N];
    let centre = &padded[(y + radius) * pw + radius + bx..][..n];
    zc[..n].copy_from_slice(centre);
    let mut quarter_inv = [0.0f32; N];
    for (q, &z) in quarter_inv.iter_mut().zip(&zc) {
        let s = sigma_rel * z;
        *q = 0.25 / (2.0 * s * s);
    }
    let (mut acc, mut wsum) = ([0.0f32; N], [0.0f32; N]);
    let mut src = [0.0f32; N];
    for dy in 0..side {
        let row = &padded[(y + dy) * pw + bx..];
        for dx in 0..side {
            let ws = spatial[dy * side + dx];
            src[..n].copy_from_slice(&row[dx..dx + n]);
            for i in 0..N {
                let z = src[i];
                let d = z - zc[i];
                let t = (1.0 - d * d * quarter_inv[i]).max(0.0);
                let t2 = t * t;
                let wgt = ws * t2 * t2;
                acc[i] += wgt * z;
                wsum[i] += wgt;
            }
        }
    }
    for i in 0..n {
        out[i] = if zc[i] == 0.0 {
            f32::NAN
        } else {
            acc[i] / wsum[i]
        };
    }
}
