//! Pinhole intrinsics and depth units of an RGB-D stream.

use crate::error::{Error, Result};
use crate::num::Num;

/// The smallest image side [`Camera::validate`] accepts, in pixels. The pyramid
/// schedules use fewer levels on small images ([`crate::Schedule::levels_for`]), so
/// every size from `MIN_SIDE x MIN_SIDE` up runs (though an image this small has too
/// few pixels to track: [`crate::MotionConfig::min_valid_pixels`]).
pub const MIN_SIDE: usize = 8;
/// The largest image side [`Camera::validate`] accepts, in pixels.
pub const MAX_SIDE: usize = 8192;
/// The smallest focal length [`Camera::validate`] accepts, as a fraction of the larger
/// image side.
pub const MIN_FOCAL_PER_SIDE: f64 = 0.05;
/// The largest focal length [`Camera::validate`] accepts, as a multiple of the larger
/// image side.
pub const MAX_FOCAL_PER_SIDE: f64 = 50.0;
/// How far outside the image [`Camera::validate`] lets the principal point lie, as a
/// fraction of the image side along that axis.
pub const PRINCIPAL_POINT_MARGIN: f64 = 0.1;
/// The smallest `depth_scale` [`Camera::validate`] accepts: raw units per metre
/// (1: depth in metres).
pub const MIN_DEPTH_SCALE: f64 = 1.0;
/// The largest `depth_scale` [`Camera::validate`] accepts (1e6: micrometres).
pub const MAX_DEPTH_SCALE: f64 = 1e6;

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

    /// Checks that every field is finite and plausible for the image size; the error
    /// names the field and its value. The one intrinsics check of ecvo: the command
    /// line, the JNI library and `set_intrinsics` all go through it.
    ///
    /// - `width`, `height`: [`MIN_SIDE`]`..=`[`MAX_SIDE`] pixels.
    /// - `fx`: positive (a negative `fx` would mirror the motion along x without any
    ///   sign of it in the residuals), and `fy` non-zero (it may be negative: ICL-NUIM
    ///   stores its images with the y axis flipped); both with `|f|` between
    ///   [`MIN_FOCAL_PER_SIDE`] and [`MAX_FOCAL_PER_SIDE`] times the larger image side
    ///   (a 170-degree fisheye has about 0.09, a 10x telephoto on a phone about 8).
    /// - `cx`, `cy`: within [`PRINCIPAL_POINT_MARGIN`] of the image side outside the
    ///   image (pixel centres at `0..width-1`).
    /// - `depth_scale`: [`MIN_DEPTH_SCALE`]`..=`[`MAX_DEPTH_SCALE`] raw units per metre
    ///   (1 for metres, 1000 for millimetres, 5000 for TUM, 1e6 for micrometres).
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, why: String| Err(Error::InvalidConfig { field, why });
        if self.width < MIN_SIDE || self.height < MIN_SIDE {
            return bad(
                "width/height",
                format!(
                    "{}x{} is smaller than {MIN_SIDE}x{MIN_SIDE}",
                    self.width, self.height
                ),
            );
        }
        if self.width > MAX_SIDE || self.height > MAX_SIDE {
            return bad(
                "width/height",
                format!(
                    "{}x{} is larger than {MAX_SIDE}x{MAX_SIDE}",
                    self.width, self.height
                ),
            );
        }
        let side = self.width.max(self.height) as f64;
        let (lo, hi) = (MIN_FOCAL_PER_SIDE * side, MAX_FOCAL_PER_SIDE * side);
        for (field, v) in [("fx", self.fx), ("fy", self.fy)] {
            if !v.is_finite() || v == 0.0 {
                return bad(
                    field,
                    format!("focal length must be finite and non-zero, got {}", Num(v)),
                );
            }
            if !(lo..=hi).contains(&v.abs()) {
                return bad(
                    field,
                    format!(
                        "focal length {} px is implausible for a {}x{} image: |{field}| must be in [{}, {}] ({MIN_FOCAL_PER_SIDE} to {MAX_FOCAL_PER_SIDE} times the larger side)",
                        Num(v),
                        self.width,
                        self.height,
                        Num(lo),
                        Num(hi)
                    ),
                );
            }
        }
        if self.fx < 0.0 {
            return bad(
                "fx",
                format!(
                    "{} is negative: it would mirror the motion along x; flip the image instead",
                    Num(self.fx)
                ),
            );
        }
        for (field, v, n) in [("cx", self.cx, self.width), ("cy", self.cy, self.height)] {
            let margin = PRINCIPAL_POINT_MARGIN * n as f64;
            let (lo, hi) = (-0.5 - margin, n as f64 - 0.5 + margin);
            if !v.is_finite() || !(lo..=hi).contains(&v) {
                return bad(
                    field,
                    format!(
                        "principal point {} is outside the {}x{} image (allowed [{}, {}])",
                        Num(v),
                        self.width,
                        self.height,
                        Num(lo),
                        Num(hi)
                    ),
                );
            }
        }
        if !(MIN_DEPTH_SCALE..=MAX_DEPTH_SCALE).contains(&self.depth_scale) {
            return bad(
                "depth_scale",
                format!(
                    "{} raw units per metre is not in [{MIN_DEPTH_SCALE}, {MAX_DEPTH_SCALE}] (1000 for millimetres, 5000 for TUM)",
                    Num(self.depth_scale)
                ),
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
        for (field, f) in [
            ("fx", (|c: &mut Camera| c.fx = -258.65) as fn(&mut Camera)),
            ("fx", |c| c.fx = 1e-5),
            ("fx", |c| c.fx = 1e300),
            ("fy", |c| c.fy = 20_000.0),
            ("cx", |c| c.cx = 1e9),
            ("cx", |c| c.cx = -1e9),
            ("cy", |c| c.cy = 300.0),
            ("cy", |c| c.cy = f64::INFINITY),
            ("depth_scale", |c| c.depth_scale = 4.9e-324),
            ("depth_scale", |c| c.depth_scale = 1e-300),
            ("depth_scale", |c| c.depth_scale = 2e6),
            ("depth_scale", |c| c.depth_scale = f64::NAN),
        ] {
            let mut c = cam();
            f(&mut c);
            match c.validate() {
                Err(e @ Error::InvalidConfig { field: got, .. }) => {
                    assert_eq!(got, field, "{c:?}: {e}");
                }
                other => panic!("{c:?} gave {other:?}, expected an error on {field}"),
            }
        }
        // The limits themselves are accepted: a wide fisheye, a long telephoto, a
        // principal point a little outside the image, depth in metres.
        for f in [
            (|c: &mut Camera| c.fx = 0.05 * 320.0) as fn(&mut Camera),
            |c| c.fy = -50.0 * 320.0,
            |c| c.cx = -0.5 - 32.0,
            |c| c.cy = 239.5 + 24.0,
            |c| c.depth_scale = 1.0,
            |c| c.depth_scale = 1e6,
        ] {
            let mut c = cam();
            f(&mut c);
            assert!(c.validate().is_ok(), "{c:?}: {:?}", c.validate());
        }
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
