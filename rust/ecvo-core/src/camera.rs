//! Pinhole intrinsics and depth units of an RGB-D stream.

use crate::error::{Error, Result};

/// Pinhole camera of an RGB-D stream whose intensity is registered to its depth.
///
/// `fy` may be negative (ICL-NUIM stores its images with the y axis flipped).
/// `depth_scale` is the number of raw depth units per metre (5000 for TUM, 1000
/// for millimetres); a raw depth of 0 means "no measurement".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Focal length along x, in pixels.
    pub fx: f64,
    /// Focal length along y, in pixels (negative for a flipped y axis).
    pub fy: f64,
    /// Principal point x, in pixels (pixel centres at integer coordinates).
    pub cx: f64,
    /// Principal point y, in pixels.
    pub cy: f64,
    /// Raw depth units per metre.
    pub depth_scale: f64,
}

impl Camera {
    /// Checks that `self` can replace `old` mid-stream: valid, and the same image size
    /// (new intrinsics, such as a zoom; another size needs a new tracker).
    pub fn validate_change_from(&self, old: &Camera) -> Result<()> {
        self.validate()?;
        if (self.width, self.height) != (old.width, old.height) {
            return Err(Error::InvalidConfig {
                field: "width/height",
                why: format!(
                    "{}x{} differs from the stream's {}x{}; a new image size needs a new tracker",
                    self.width, self.height, old.width, old.height
                ),
            });
        }
        Ok(())
    }

    /// Checks that every field is finite and usable; the error names the field.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, why: String| Err(Error::InvalidConfig { field, why });
        if self.width < 8 || self.height < 8 {
            return bad(
                "width/height",
                format!("{}x{} is smaller than 8x8", self.width, self.height),
            );
        }
        if self.width > 8192 || self.height > 8192 {
            return bad(
                "width/height",
                format!("{}x{} is larger than 8192x8192", self.width, self.height),
            );
        }
        for (field, v) in [("fx", self.fx), ("fy", self.fy)] {
            if !v.is_finite() || v.abs() < 1e-6 {
                return bad(
                    field,
                    format!("focal length must be finite and non-zero, got {v}"),
                );
            }
        }
        for (field, v) in [("cx", self.cx), ("cy", self.cy)] {
            if !v.is_finite() {
                return bad(field, format!("principal point must be finite, got {v}"));
            }
        }
        if !self.depth_scale.is_finite() || self.depth_scale <= 0.0 {
            return bad(
                "depth_scale",
                format!("must be finite and positive, got {}", self.depth_scale),
            );
        }
        Ok(())
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.width * self.height
    }

    /// The camera of an image downsampled by 2x2 averaging: pixel centres move, so the
    /// principal point becomes `(c + 0.5) / 2 - 0.5`, not `c / 2`.
    pub fn half(&self) -> Camera {
        Camera {
            width: self.width / 2,
            height: self.height / 2,
            fx: self.fx / 2.0,
            fy: self.fy / 2.0,
            cx: (self.cx + 0.5) / 2.0 - 0.5,
            cy: (self.cy + 0.5) / 2.0 - 0.5,
            depth_scale: self.depth_scale,
        }
    }
}

/// One RGB-D frame as it arrives: borrowed 8-bit intensity and 16-bit raw depth,
/// both `width * height` row-major, registered to each other.
#[derive(Clone, Copy, Debug)]
pub struct FrameView<'a> {
    /// Capture time in seconds.
    pub timestamp: f64,
    /// 8-bit gray intensity.
    pub intensity: &'a [u8],
    /// Raw depth in `Camera::depth_scale` units per metre; 0 = no measurement.
    pub depth: &'a [u16],
}

impl FrameView<'_> {
    /// Checks the buffer sizes and the timestamp against `camera`.
    pub fn validate(&self, camera: &Camera) -> Result<()> {
        let n = camera.pixels();
        if self.intensity.len() != n {
            return Err(Error::BadFrame(format!(
                "intensity has {} values, expected {} ({}x{})",
                self.intensity.len(),
                n,
                camera.width,
                camera.height
            )));
        }
        if self.depth.len() != n {
            return Err(Error::BadFrame(format!(
                "depth has {} values, expected {} ({}x{})",
                self.depth.len(),
                n,
                camera.width,
                camera.height
            )));
        }
        if !self.timestamp.is_finite() {
            return Err(Error::BadFrame(format!(
                "timestamp {} is not finite",
                self.timestamp
            )));
        }
        Ok(())
    }
}

/// The TUM fr1 camera at half resolution (320x240): the unit tests' camera.
#[cfg(test)]
pub(crate) fn tum_fr1_half() -> Camera {
    Camera {
        width: 320,
        height: 240,
        fx: 258.65,
        fy: 258.25,
        cx: 159.05,
        cy: 127.4,
        depth_scale: 5000.0,
    }
}

/// The TUM fr1 camera at full resolution (640x480).
#[cfg(test)]
pub(crate) fn tum_fr1() -> Camera {
    Camera {
        width: 640,
        height: 480,
        fx: 517.3,
        fy: 516.5,
        cx: 318.6,
        cy: 255.3,
        depth_scale: 5000.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        tum_fr1_half()
    }

    #[test]
    fn half_moves_the_principal_point_with_pixel_centres() {
        let full = tum_fr1();
        let h = full.half();
        assert_eq!((h.width, h.height), (320, 240));
        assert!((h.cx - 159.05).abs() < 1e-12);
        assert!((h.cy - 127.4).abs() < 1e-12);
    }

    #[test]
    fn validate_names_the_bad_field() {
        assert!(cam().validate().is_ok());
        let mut c = cam();
        c.fx = f64::NAN;
        assert!(matches!(
            c.validate(),
            Err(Error::InvalidConfig { field: "fx", .. })
        ));
        let mut c = cam();
        c.fy = 0.0;
        assert!(matches!(
            c.validate(),
            Err(Error::InvalidConfig { field: "fy", .. })
        ));
        let mut c = cam();
        c.fy = -481.2; // ICL-NUIM
        assert!(c.validate().is_ok());
        let mut c = cam();
        c.depth_scale = 0.0;
        assert!(matches!(
            c.validate(),
            Err(Error::InvalidConfig {
                field: "depth_scale",
                ..
            })
        ));
    }

    #[test]
    fn frame_view_checks_sizes() {
        let c = cam();
        let i = vec![0u8; c.pixels()];
        let d = vec![0u16; c.pixels() - 1];
        let f = FrameView {
            timestamp: 0.0,
            intensity: &i,
            depth: &d,
        };
        assert!(matches!(f.validate(&c), Err(Error::BadFrame(_))));
    }
}
