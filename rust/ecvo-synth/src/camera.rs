//! Pinhole camera model used by the renderer.

use nalgebra::{Point3, Vector3};

/// Pinhole RGB-D camera: image size, intrinsics (pixels) and raw depth scale.
///
/// Convention: camera looks along +z, x to the right, y down; a point `(x, y, z)` in
/// the camera frame projects to `u = fx x / z + cx`, `v = fy y / z + cy` (pixel centres
/// at integer coordinates). A negative `fy` (or `fx`) simply mirrors the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SynthCamera {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Focal length along x, in pixels.
    pub fx: f64,
    /// Focal length along y, in pixels (may be negative).
    pub fy: f64,
    /// Principal point x, in pixels.
    pub cx: f64,
    /// Principal point y, in pixels.
    pub cy: f64,
    /// Raw depth units per metre (1000 for millimetres, 5000 for TUM).
    pub depth_scale: f64,
}

impl SynthCamera {
    /// Phone-like 320x180 camera: fx = fy = 250 (about 65° horizontal field of view),
    /// principal point at the image centre, depth in millimetres.
    pub fn phone_320x180() -> Self {
        Self {
            width: 320,
            height: 180,
            fx: 250.0,
            fy: 250.0,
            cx: 159.5,
            cy: 89.5,
            depth_scale: 1000.0,
        }
    }

    /// TUM RGB-D (Freiburg default) 640x480 camera with depth scale 5000.
    pub fn tum_640x480() -> Self {
        Self {
            width: 640,
            height: 480,
            fx: 525.0,
            fy: 525.0,
            cx: 319.5,
            cy: 239.5,
            depth_scale: 5000.0,
        }
    }

    /// Number of pixels (`width * height`).
    pub fn pixel_count(&self) -> usize {
        self.width * self.height
    }

    /// Projects a camera-frame point to pixel coordinates; `None` if `z <= 0`.
    pub fn project(&self, p: &Point3<f64>) -> Option<(f64, f64)> {
        if p.z <= 0.0 {
            return None;
        }
        Some((self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy))
    }

    /// Camera-frame ray direction through pixel `(u, v)`, scaled so that its z component
    /// is exactly 1 (so the ray parameter equals depth).
    pub fn ray(&self, u: f64, v: f64) -> Vector3<f64> {
        Vector3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0)
    }

    /// Back-projects pixel `(u, v)` with depth `z` (metres, along the optical axis) to a
    /// camera-frame point.
    pub fn backproject(&self, u: f64, v: f64, z: f64) -> Point3<f64> {
        Point3::from(self.ray(u, v) * z)
    }

    /// True when `(u, v)` lies inside the image (pixel-centre convention, inclusive of the
    /// outermost pixel centres).
    pub fn contains(&self, u: f64, v: f64) -> bool {
        u >= 0.0 && v >= 0.0 && u <= (self.width - 1) as f64 && v <= (self.height - 1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_backproject_roundtrip_with_negative_fy() {
        let mut cam = SynthCamera::phone_320x180();
        for fy in [250.0, -250.0] {
            cam.fy = fy;
            let p = cam.backproject(12.25, 170.5, 2.5);
            let (u, v) = cam.project(&p).unwrap();
            assert!((u - 12.25).abs() < 1e-12 && (v - 170.5).abs() < 1e-12);
            assert_eq!(p.z, 2.5);
        }
        // With fy < 0 a point below the axis (y > 0) appears in the upper half.
        let (_, v) = cam.project(&Point3::new(0.0, 0.5, 2.0)).unwrap();
        assert!(v < cam.cy);
        assert!(cam.project(&Point3::new(0.0, 0.0, -1.0)).is_none());
    }
}
