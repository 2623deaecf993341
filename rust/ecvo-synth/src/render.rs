//! Exact ray-cast rendering of intensity, depth and viewing-angle images.

use nalgebra::{Isometry3, Point3, Vector3};

use crate::camera::SynthCamera;
use crate::scene::{Hit, Scene};

/// Surface id stored for pixels whose ray hits nothing (camera outside the room).
pub const NO_SURFACE: u32 = u32::MAX;

/// A noise-free rendered frame. All images are row-major, `width * height` long.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Anti-aliased intensity rounded to 8 bits.
    pub intensity: Vec<u8>,
    /// Anti-aliased intensity before rounding (0–255).
    pub intensity_f32: Vec<f32>,
    /// Exact depth (camera-frame z, metres) at the pixel centre; 0 where nothing is hit.
    pub depth_m: Vec<f32>,
    /// `|cos|` of the angle between the pixel-centre viewing ray and the surface normal
    /// (1 = seen head-on, 0 = grazing); 0 where nothing is hit.
    pub normal_dot_view: Vec<f32>,
    /// Surface id hit by the pixel-centre ray (see [`crate::Hit::surface`]), or
    /// [`NO_SURFACE`].
    pub surface_id: Vec<u32>,
}

/// Renders `scene` seen by `camera` at `pose` (camera-to-world).
///
/// Intensity is anti-aliased with five samples per pixel: the pixel centre (weight 1/2)
/// and the four pixel corners (weight 1/8 each, shared with the neighbouring pixels, so
/// this costs about two ray casts per pixel). Depth, viewing angle and surface id are
/// those of the exact ray through the pixel centre.
pub fn render(scene: &Scene, camera: &SynthCamera, pose: &Isometry3<f64>) -> Rendered {
    let (w, h) = (camera.width, camera.height);
    let mut out = Rendered::empty(w, h);
    let rot = pose.rotation.to_rotation_matrix();
    let prepared = scene.prepare(&Point3::from(pose.translation.vector));
    let sample = |u: f64, v: f64| {
        scene
            .cast_from(&prepared, &(rot * camera.ray(u, v)))
            .map_or(0.0, |s| scene.radiance(s.surface, &s.point))
    };
    let corner_row = |v: f64| -> Vec<f64> { (0..=w).map(|k| sample(k as f64 - 0.5, v)).collect() };
    let mut top = corner_row(-0.5);
    for v in 0..h {
        let bottom = corner_row(v as f64 + 0.5);
        for u in 0..w {
            let dir = rot * camera.ray(u as f64, v as f64);
            let Some(hit) = scene.cast_from(&prepared, &dir) else {
                continue;
            };
            let i = v * w + u;
            out.set_geometry(i, &hit, &dir);
            let corners = top[u] + top[u + 1] + bottom[u] + bottom[u + 1];
            out.set_intensity(
                i,
                0.5 * scene.radiance(hit.surface, &hit.point) + 0.125 * corners,
            );
        }
        top = bottom;
    }
    out
}

/// Renders with `n x n` intensity samples per pixel (`n >= 1`) on a regular grid over
/// the pixel footprint (box filter); slower than [`render`] for `n >= 2`. Depth, viewing
/// angle and surface id are those of the exact ray through the pixel centre.
pub fn render_supersampled(
    scene: &Scene,
    camera: &SynthCamera,
    pose: &Isometry3<f64>,
    n: usize,
) -> Rendered {
    let n = n.max(1);
    let (w, h) = (camera.width, camera.height);
    let mut out = Rendered::empty(w, h);
    let rot = pose.rotation.to_rotation_matrix();
    let prepared = scene.prepare(&Point3::from(pose.translation.vector));
    let offsets: Vec<f64> = (0..n).map(|k| (k as f64 + 0.5) / n as f64 - 0.5).collect();
    let centre_is_sample = n % 2 == 1;
    let inv_samples = 1.0 / (n * n) as f64;
    for v in 0..h {
        for u in 0..w {
            let i = v * w + u;
            let (uf, vf) = (u as f64, v as f64);
            let dir = rot * camera.ray(uf, vf);
            let Some(hit) = scene.cast_from(&prepared, &dir) else {
                continue;
            };
            out.set_geometry(i, &hit, &dir);
            let mut sum = 0.0;
            for &dv in &offsets {
                for &du in &offsets {
                    if centre_is_sample && du == 0.0 && dv == 0.0 {
                        sum += scene.radiance(hit.surface, &hit.point);
                        continue;
                    }
                    let d = rot * camera.ray(uf + du, vf + dv);
                    if let Some(s) = scene.cast_from(&prepared, &d) {
                        sum += scene.radiance(s.surface, &s.point);
                    }
                }
            }
            out.set_intensity(i, sum * inv_samples);
        }
    }
    out
}

impl Rendered {
    /// All-missing image of the given size.
    fn empty(width: usize, height: usize) -> Self {
        let count = width * height;
        Self {
            width,
            height,
            intensity: vec![0; count],
            intensity_f32: vec![0.0; count],
            depth_m: vec![0.0; count],
            normal_dot_view: vec![0.0; count],
            surface_id: vec![NO_SURFACE; count],
        }
    }

    /// Stores the pixel-centre hit (`dir` is the camera ray with unit z in the camera
    /// frame, so the ray parameter is the depth).
    #[inline]
    fn set_geometry(&mut self, i: usize, hit: &Hit, dir: &Vector3<f64>) {
        self.depth_m[i] = hit.t as f32;
        self.normal_dot_view[i] = (hit.normal.dot(dir).abs() / dir.norm()) as f32;
        self.surface_id[i] = hit.surface;
    }

    /// Stores an intensity value (and its 8-bit rounding).
    #[inline]
    fn set_intensity(&mut self, i: usize, value: f64) {
        self.intensity_f32[i] = value as f32;
        self.intensity[i] = value.round().clamp(0.0, 255.0) as u8;
    }

    /// Bilinear interpolation of `intensity_f32` at `(u, v)`; `None` outside the image.
    pub fn intensity_bilinear(&self, u: f64, v: f64) -> Option<f64> {
        bilinear(&self.intensity_f32, self.width, self.height, u, v)
    }

    /// Bilinear interpolation of `depth_m` at `(u, v)`; `None` outside the image.
    pub fn depth_bilinear(&self, u: f64, v: f64) -> Option<f64> {
        bilinear(&self.depth_m, self.width, self.height, u, v)
    }
}

/// Bilinear interpolation of a row-major `f32` image (pixel centres at integers).
fn bilinear(img: &[f32], w: usize, h: usize, u: f64, v: f64) -> Option<f64> {
    if !(u >= 0.0 && v >= 0.0 && u <= (w - 1) as f64 && v <= (h - 1) as f64) {
        return None;
    }
    let (x0, y0) = (
        (u.floor() as usize).min(w.saturating_sub(2)),
        (v.floor() as usize).min(h.saturating_sub(2)),
    );
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (ax, ay) = (u - x0 as f64, v - y0 as f64);
    let p = |x: usize, y: usize| img[y * w + x] as f64;
    let top = p(x0, y0) * (1.0 - ax) + p(x1, y0) * ax;
    let bottom = p(x0, y1) * (1.0 - ax) + p(x1, y1) * ax;
    Some(top * (1.0 - ay) + bottom * ay)
}
