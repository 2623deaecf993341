//! Template points: the reference-side pixels of each coarse-to-fine step,
//! back-projected (`[x, y, z, intensity]`), all of them or a budget chosen by
//! `select`.

use super::{D, I};
use super::{ImageLevel, Template, back_projection, level_cameras, pyramid, select};
use crate::camera::Camera;
use crate::config::Config;

/// The most template points a level of camera `c` sampled every `stride` pixels has.
pub(super) fn template_capacity(c: &Camera, stride: usize) -> usize {
    let s = stride.max(1);
    (c.width / s + 1) * (c.height / s + 1)
}

/// The most template points any step of `config`'s schedule can have.
pub fn max_template_points(config: &Config) -> usize {
    let cams = level_cameras(config);
    config
        .motion
        .levels
        .iter()
        .map(|l| template_capacity(&cams[l.pyramid_level], l.stride))
        .max()
        .unwrap_or(0)
}

/// Every `stride`-th valid pixel of a level with camera `c` and planes `p` (away
/// from the border) as a template point.
#[inline(never)]
pub(super) fn build_template(p: &pyramid::Planes, c: &Camera, stride: usize, t: &mut Template) {
    let (w, h) = (c.width, c.height);
    let (ifx, ify, cx, cy) = back_projection(c);
    t.points.clear();
    let start = (stride / 2).max(1);
    for y in (start..h - 1).step_by(stride) {
        let ry = (y as f32 - cy) * ify;
        let (zr, ir) = (
            &p.depth[y * w..(y + 1) * w],
            &p.intensity[y * w..(y + 1) * w],
        );
        for x in (start..w - 1).step_by(stride) {
            let z = zr[x];
            if z.is_finite() {
                t.points.push([(x as f32 - cx) * ifx * z, ry * z, z, ir[x]]);
            }
        }
    }
}

/// At most `budget` of the template points [`build_template`] would take, chosen by
/// [`select`] from the level's samples, row-major.
#[inline(never)]
pub(super) fn build_selected_template(
    level: &ImageLevel,
    stride: usize,
    budget: usize,
    selector: &mut select::Selector,
    t: &mut Template,
) {
    let c = level.camera();
    let w = c.width;
    let (ifx, ify, cx, cy) = back_projection(c);
    t.points.clear();
    let start = (stride / 2).max(1);
    let samples = &level.samples;
    let points = &mut t.points;
    selector.select(samples, w, c.height, stride, start, budget, |i| {
        let (x, y) = (i % w, i / w);
        let s = &samples[i];
        let z = s[D];
        points.push([
            (x as f32 - cx) * ifx * z,
            (y as f32 - cy) * ify * z,
            z,
            s[I],
        ]);
    });
}
