//! Normal-based and contour-based removal (paper section 4.2, εn and εg).
//!
//! [`normals_and_seeds`] back-projects the smoothed depth where it needs it and, per
//! pixel, computes the axis and diagonal normals, whether they disagree (the normal
//! filter) and whether the contour test fires there (a *seed*); [`apply_masks`]
//! drops the normal filter's pixels and the 3x3 neighbourhoods of the seeds.

use rayon::prelude::*;

use super::pyramid::Planes;
use super::rows_per_task;
use super::simd::multiversion;

/// The two filter angles, as the cosine and sine the tests compare with.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Angles {
    /// cos εn: normals further apart than εn drop the pixel (`None`: no normal filter).
    pub cos_n: Option<f32>,
    /// sin εg: a cross-product normal within `90° ± εg` of the viewing ray seeds a
    /// contour (`None`: no contour filter).
    pub sin_g: Option<f32>,
}

/// Pixel counts of [`apply_masks`].
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Counts {
    /// Pixels with depth after both filters.
    pub valid: usize,
    /// Pixels with depth that the normal filter removed.
    pub by_normal: usize,
    /// Pixels with depth that the contour filter removed (and the normal one kept).
    pub by_contour: usize,
}

/// Per pixel of `z` (`ray_x.len()` wide, NaN where missing): its unit normal
/// oriented towards the camera (NaN where unknown) into `normals`, whether the
/// normal filter drops it into `normal_drop` (before the border rule of
/// [`apply_masks`]), whether the contour test fires into `seed`. Border pixels get
/// no normal and no seed.
///
/// The point of pixel `(x, y)` is `(ray_x[x] z, ray_y[y] z, z)`. Both normals need
/// all eight neighbours: the axis one is `(r − l) × (d − u)`, the diagonal one
/// `(dr − ul) × (dl − ur)`. A missing neighbour makes its normal NaN, so every
/// test below is false for it and no branch is needed.
pub(crate) fn normals_and_seeds(
    z: &[f32],
    ray_x: &[f32],
    ray_y: &[f32],
    angles: Angles,
    keep_normals: bool,
    normals: &mut Vec<[f32; 3]>,
    normal_drop: &mut Vec<u8>,
    seed: &mut Vec<u8>,
) {
    let (w, h) = (ray_x.len(), ray_y.len());
    let n = w * h;
    normal_drop.resize(n, 0);
    seed.resize(n, 0);
    if !keep_normals {
        normals.clear();
        if angles.cos_n.is_none() && angles.sin_g.is_none() {
            // Neither test is on and no normal is kept: nothing to compute.
            normal_drop.fill(0);
            seed.fill(0);
            return;
        }
        // The same tests, without the averaged normal or its store.
        normal_drop
            .par_chunks_mut(w)
            .zip(seed.par_chunks_mut(w))
            .enumerate()
            .with_min_len(rows_per_task(w))
            .for_each(|(y, (drop, seed))| {
                if y == 0 || y + 1 >= h || w < 3 {
                    drop.fill(0);
                    seed.fill(0);
                    return;
                }
                let rows = [
                    &z[(y - 1) * w..y * w],
                    &z[y * w..(y + 1) * w],
                    &z[(y + 1) * w..(y + 2) * w],
                ];
                let ry = [ray_y[y - 1], ray_y[y], ray_y[y + 1]];
                row_tests(rows, ray_x, ry, angles, drop, seed);
            });
        return;
    }
    // Every pixel is written below: interior rows by the kernel, the others here.
    normals.resize(n, [f32::NAN; 3]);
    normals
        .par_chunks_mut(w)
        .zip(normal_drop.par_chunks_mut(w))
        .zip(seed.par_chunks_mut(w))
        .enumerate()
        .with_min_len(rows_per_task(w))
        .for_each(|(y, ((normals, drop), seed))| {
            if y == 0 || y + 1 >= h || w < 3 {
                normals.fill([f32::NAN; 3]);
                drop.fill(0);
                seed.fill(0);
                return;
            }
            let rows = [
                &z[(y - 1) * w..y * w],
                &z[y * w..(y + 1) * w],
                &z[(y + 1) * w..(y + 2) * w],
            ];
            let ry = [ray_y[y - 1], ray_y[y], ray_y[y + 1]];
            row(rows, ray_x, ry, angles, normals, drop, seed);
        });
}

multiversion! {
    /// One interior row of [`normals_and_seeds`].
    fn row(
        z: [&[f32]; 3],
        ray_x: &[f32],
        ry: [f32; 3],
        angles: Angles,
        normals: &mut [[f32; 3]],
        drop: &mut [u8],
        seed: &mut [u8],
    ) = row_kernel;
}

multiversion! {
    /// [`row`] without the normals: the normal and contour tests only.
    fn row_tests(
        z: [&[f32]; 3],
        ray_x: &[f32],
        ry: [f32; 3],
        angles: Angles,
        drop: &mut [u8],
        seed: &mut [u8],
    ) = row_tests_kernel;
}

#[inline(always)]
fn row_tests_kernel(
    z: [&[f32]; 3],
    ray_x: &[f32],
    ry: [f32; 3],
    angles: Angles,
    drop: &mut [u8],
    seed: &mut [u8],
) {
    row_generic::<false>(z, ray_x, ry, angles, &mut [], drop, seed)
}

#[inline(always)]
fn row_kernel(
    z: [&[f32]; 3],
    ray_x: &[f32],
    ry: [f32; 3],
    angles: Angles,
    normals: &mut [[f32; 3]],
    drop: &mut [u8],
    seed: &mut [u8],
) {
    row_generic::<true>(z, ray_x, ry, angles, normals, drop, seed)
}

#[inline(always)]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline(always)]
fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline(always)]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// `a / |a|` and whether `|a| > 1e-12` (false for NaN).
#[inline(always)]
fn unit(a: [f32; 3]) -> ([f32; 3], bool) {
    let n = dot(a, a).sqrt();
    ([a[0] / n, a[1] / n, a[2] / n], n > 1e-12)
}
/// `a` where `m`, else NaN, without a branch.
#[inline(always)]
fn select(m: bool, a: f32) -> f32 {
    if m { a } else { f32::NAN }
}

/// One interior row: the normal test into `drop`, the contour test into `seed` and,
/// when `NORMALS`, the averaged normals into `normals` (unused otherwise).
#[inline(always)]
fn row_generic<const NORMALS: bool>(
    z: [&[f32]; 3],
    ray_x: &[f32],
    ry: [f32; 3],
    angles: Angles,
    normals: &mut [[f32; 3]],
    drop: &mut [u8],
    seed: &mut [u8],
) {
    let w = ray_x.len();
    let (zu, zc, zd) = (&z[0][..w], &z[1][..w], &z[2][..w]);
    let normal_filter = angles.cos_n.is_some();
    // With no normal filter, no angle is below -inf.
    let cos_n = angles.cos_n.unwrap_or(f32::NEG_INFINITY);
    let contour = angles.sin_g.is_some();
    let sin_g = angles.sin_g.unwrap_or(0.0);
    let point = |zr: &[f32], ry: f32, x: usize| {
        let z = zr[x];
        [ray_x[x] * z, ry * z, z]
    };
    if NORMALS {
        normals[0] = [f32::NAN; 3];
        normals[w - 1] = [f32::NAN; 3];
    }
    drop[0] = 0;
    drop[w - 1] = 0;
    seed[0] = 0;
    seed[w - 1] = 0;
    for x in 1..w - 1 {
        let c = point(zc, ry[1], x);
        let (l, r) = (point(zc, ry[1], x - 1), point(zc, ry[1], x + 1));
        let (u, d) = (point(zu, ry[0], x), point(zd, ry[2], x));
        let (ul, ur) = (point(zu, ry[0], x - 1), point(zu, ry[0], x + 1));
        let (dl, dr) = (point(zd, ry[2], x - 1), point(zd, ry[2], x + 1));
        let valid = !c[2].is_nan();

        // Normals: NaN (and not ok) when a neighbour is missing.
        let (np, np_ok) = unit(cross(sub(r, l), sub(d, u)));
        let (nd, nd_ok) = unit(cross(sub(dr, ul), sub(dl, ur)));
        let both = np_ok & nd_ok;
        let cosang = dot(np, nd);
        let apart = cosang < cos_n;
        if NORMALS {
            let (avg, avg_ok) = unit(add(np, nd));
            let away = dot(avg, c) > 0.0;
            let keep_normal = valid & both & !apart & avg_ok;
            let sign = if away { -1.0f32 } else { 1.0 };
            normals[x] = [
                select(keep_normal, avg[0] * sign),
                select(keep_normal, avg[1] * sign),
                select(keep_normal, avg[2] * sign),
            ];
        }
        drop[x] = (normal_filter & valid & !(both & !apart)) as u8;

        // Contour: NaN (and false) when c, l or u is missing.
        let nc = cross(sub(l, c), sub(u, c));
        let nn = dot(nc, nc).sqrt();
        let pn = dot(c, c).sqrt();
        seed[x] = (contour & (nn > 0.0) & ((dot(nc, c) / (nn * pn)).abs() <= sin_g)) as u8;
    }
}

multiversion! {
    /// Drops the pixels of `normal_drop` (plus the image border when `normal_filter`)
    /// and the 3x3 neighbourhoods of `seed` from the smoothed depth `z` (`w` wide),
    /// clears their `normals` (unless `normals` is empty: none kept), and writes level 0's planes: intensity in [0, 1] and
    /// the filtered depth (NaN where missing). A pixel dropped by both filters counts
    /// as removed by the normal filter. `scratch` holds two rows of masks.
    fn apply_masks(
        intensity: &[u8],
        z: &[f32],
        normal_drop: &[u8],
        seed: &[u8],
        w: usize,
        normal_filter: bool,
        normals: &mut [[f32; 3]],
        planes: &mut Planes,
        scratch: &mut Vec<u8>,
    ) -> Counts = apply_masks_kernel;
}

#[inline(always)]
fn apply_masks_kernel(
    intensity: &[u8],
    z: &[f32],
    normal_drop: &[u8],
    seed: &[u8],
    w: usize,
    normal_filter: bool,
    normals: &mut [[f32; 3]],
    planes: &mut Planes,
    scratch: &mut Vec<u8>,
) -> Counts {
    let n = z.len();
    let h = n / w.max(1);
    planes.intensity.resize(n, 0.0);
    planes.depth.resize(n, f32::NAN);
    scratch.resize(2 * w, 0);
    let (vert, drop) = scratch.split_at_mut(w);
    let (mut by_normal, mut by_contour, mut valid) = (0u32, 0u32, 0u32);
    let nf = normal_filter as u8;
    for y in 0..h {
        let r = y * w..(y + 1) * w;
        // The seeds of rows y - 1, y and y + 1 (clamped), or-ed vertically, then
        // horizontally (clamped): the 3x3 dilation, in `vert`, then `drop` bit 1.
        let (up, mid, down) = (
            &seed[y.saturating_sub(1) * w..][..w],
            &seed[r.clone()],
            &seed[(y + 1).min(h - 1) * w..][..w],
        );
        for (((v, a), b), c) in vert.iter_mut().zip(up).zip(mid).zip(down) {
            *v = a | b | c;
        }
        // Bit 0: the normal filter's drop, the border included.
        let border_row = nf & (y == 0 || y + 1 == h) as u8;
        let nd = &normal_drop[r.clone()];
        if w >= 2 {
            drop[0] = ((vert[0] | vert[1]) << 1) | nd[0] | nf;
            drop[w - 1] = ((vert[w - 2] | vert[w - 1]) << 1) | nd[w - 1] | nf;
        } else {
            drop[0] = (vert[0] << 1) | nd[0] | nf;
        }
        for x in 1..w.saturating_sub(1) {
            drop[x] = ((vert[x - 1] | vert[x] | vert[x + 1]) << 1) | nd[x] | border_row;
        }
        let (zr, ir) = (&z[r.clone()], &intensity[r.clone()]);
        let (pi, pz) = (
            &mut planes.intensity[r.clone()],
            &mut planes.depth[r.clone()],
        );
        for ((((&d, &z), &i), pi), pz) in drop.iter().zip(zr).zip(ir).zip(pi).zip(pz.iter_mut()) {
            let has = !z.is_nan();
            let keep = has & (d == 0);
            by_normal += (has & (d & 1 != 0)) as u32;
            by_contour += (has & (d == 2)) as u32;
            valid += keep as u32;
            *pi = i as f32 * (1.0 / 255.0);
            *pz = if keep { z } else { f32::NAN };
        }
        // No normals kept (`normals` empty): nothing to clear.
        if let Some(nr) = normals.get_mut(r) {
            for (n, &z) in nr.iter_mut().zip(pz.iter()) {
                if z.is_nan() {
                    *n = [f32::NAN; 3];
                }
            }
        }
    }
    Counts {
        valid: valid as usize,
        by_normal: by_normal as usize,
        by_contour: by_contour as usize,
    }
}
