//! `camera.json` files and the intrinsics of the public RGB-D benchmarks.
//!
//! The file holds one JSON object with the fields of [`Camera`]:
//! `{"width": 640, "height": 480, "fx": 517.3, "fy": 516.5, "cx": 318.6, "cy": 255.3,
//! "depth_scale": 5000.0}`, where `depth_scale` is raw depth units per metre.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use ecvo_core::Camera;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::files::{MAX_CAMERA_BYTES, read_text_limited, shown};

/// Name of the camera file inside a sequence folder.
pub const CAMERA_FILE: &str = "camera.json";

/// The on-disk form of a camera; every field is required.
#[derive(Serialize, Deserialize)]
struct CameraFile {
    width: usize,
    height: usize,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    depth_scale: f64,
}

impl From<&Camera> for CameraFile {
    fn from(c: &Camera) -> Self {
        CameraFile {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            depth_scale: c.depth_scale,
        }
    }
}

impl From<CameraFile> for Camera {
    fn from(c: CameraFile) -> Self {
        Camera {
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            cx: c.cx,
            cy: c.cy,
            depth_scale: c.depth_scale,
        }
    }
}

/// Parses a camera from JSON text; `path` is only used in error messages.
///
/// The text must be one JSON object (a leading byte-order mark is ignored) with every
/// field of [`Camera`]; the camera must pass `Camera::validate`.
pub fn parse_camera_json(text: &str, path: &Path) -> Result<Camera> {
    let bad = |msg: String| Error::Camera {
        path: path.to_path_buf(),
        msg,
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| bad(shown(&e.to_string())))?;
    if !value.is_object() {
        let kind = match value {
            serde_json::Value::Array(_) => "an array",
            serde_json::Value::String(_) => "a string",
            serde_json::Value::Number(_) => "a number",
            serde_json::Value::Bool(_) => "a boolean",
            _ => "null",
        };
        return Err(bad(format!(
            "expected a JSON object {{\"width\": .., \"height\": .., \"fx\": .., \"fy\": .., \
             \"cx\": .., \"cy\": .., \"depth_scale\": ..}}, found {kind}"
        )));
    }
    let file: CameraFile = serde_json::from_value(value).map_err(|e| bad(shown(&e.to_string())))?;
    let camera = Camera::from(file);
    camera.validate().map_err(|e| Error::Camera {
        path: path.to_path_buf(),
        msg: e.to_string(),
    })?;
    Ok(camera)
}

/// Reads and validates a `camera.json` file (a regular file of at most
/// [`MAX_CAMERA_BYTES`]); errors name the file and the bad field.
pub fn load_camera_json(path: impl AsRef<Path>) -> Result<Camera> {
    let path = path.as_ref();
    let text = read_text_limited(path, MAX_CAMERA_BYTES)?;
    parse_camera_json(&text, path)
}

/// Writes `camera` as a `camera.json` file, after checking it with `Camera::validate`.
pub fn save_camera_json(path: impl AsRef<Path>, camera: &Camera) -> Result<()> {
    let path = path.as_ref();
    camera.validate().map_err(|e| Error::Camera {
        path: path.to_path_buf(),
        msg: e.to_string(),
    })?;
    let mut text =
        serde_json::to_string_pretty(&CameraFile::from(camera)).map_err(|e| Error::Camera {
            path: path.to_path_buf(),
            msg: e.to_string(),
        })?;
    text.push('\n');
    std::fs::write(path, text).map_err(|e| Error::io(path, e))
}

/// Intrinsics of the public benchmark cameras, as published with the datasets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CameraPreset {
    /// TUM RGB-D freiburg1 (`fr1`): fx 517.3, fy 516.5, cx 318.6, cy 255.3, 640x480.
    TumFr1,
    /// TUM RGB-D freiburg2 (`fr2`): fx 520.9, fy 521.0, cx 325.1, cy 249.7, 640x480.
    TumFr2,
    /// TUM RGB-D freiburg3 (`fr3`): fx 535.4, fy 539.2, cx 320.1, cy 247.6, 640x480.
    TumFr3,
    /// ICL-NUIM (`icl`): fx 481.20, fy -480.00 (flipped y), cx 319.50, cy 239.50, 640x480.
    IclNuim,
}

impl CameraPreset {
    /// All presets, in the order of their names in [`CameraPreset::NAMES`].
    pub const ALL: [CameraPreset; 4] = [
        CameraPreset::TumFr1,
        CameraPreset::TumFr2,
        CameraPreset::TumFr3,
        CameraPreset::IclNuim,
    ];

    /// The names accepted by `FromStr`, one per preset.
    pub const NAMES: [&'static str; 4] = ["fr1", "fr2", "fr3", "icl"];

    /// The camera of this preset: 640x480, 5000 depth units per metre.
    pub fn camera(self) -> Camera {
        let (fx, fy, cx, cy) = match self {
            CameraPreset::TumFr1 => (517.3, 516.5, 318.6, 255.3),
            CameraPreset::TumFr2 => (520.9, 521.0, 325.1, 249.7),
            CameraPreset::TumFr3 => (535.4, 539.2, 320.1, 247.6),
            CameraPreset::IclNuim => (481.20, -480.00, 319.50, 239.50),
        };
        Camera {
            width: 640,
            height: 480,
            fx,
            fy,
            cx,
            cy,
            depth_scale: 5000.0,
        }
    }

    /// The short name of this preset (`fr1`, `fr2`, `fr3` or `icl`).
    pub fn name(self) -> &'static str {
        match self {
            CameraPreset::TumFr1 => "fr1",
            CameraPreset::TumFr2 => "fr2",
            CameraPreset::TumFr3 => "fr3",
            CameraPreset::IclNuim => "icl",
        }
    }
}

impl fmt::Display for CameraPreset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for CameraPreset {
    type Err = Error;

    /// Parses `fr1`, `fr2`, `fr3` or `icl` (case-insensitive).
    fn from_str(s: &str) -> Result<Self> {
        let lower = s.trim().to_ascii_lowercase();
        CameraPreset::ALL
            .into_iter()
            .find(|p| p.name() == lower)
            .ok_or_else(|| {
                Error::InvalidInput(format!(
                    "unknown camera preset `{s}` (expected one of {})",
                    CameraPreset::NAMES.join(", ")
                ))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse_and_validate() {
        for (p, name) in CameraPreset::ALL.into_iter().zip(CameraPreset::NAMES) {
            assert_eq!(name.parse::<CameraPreset>().unwrap(), p);
            assert_eq!(name.to_uppercase().parse::<CameraPreset>().unwrap(), p);
            assert_eq!(p.to_string(), name);
            p.camera().validate().unwrap();
        }
        assert!("fr4".parse::<CameraPreset>().is_err());
        let icl = CameraPreset::IclNuim.camera();
        assert_eq!(
            (icl.fx, icl.fy, icl.cx, icl.cy),
            (481.2, -480.0, 319.5, 239.5)
        );
        let fr2 = CameraPreset::TumFr2.camera();
        assert_eq!(
            (fr2.fx, fr2.fy, fr2.cx, fr2.cy),
            (520.9, 521.0, 325.1, 249.7)
        );
        let fr3 = CameraPreset::TumFr3.camera();
        assert_eq!(
            (fr3.fx, fr3.fy, fr3.cx, fr3.cy),
            (535.4, 539.2, 320.1, 247.6)
        );
        assert_eq!((fr3.width, fr3.height, fr3.depth_scale), (640, 480, 5000.0));
    }

    #[test]
    fn parse_reports_file_and_field() {
        let p = Path::new("/some/where/camera.json");
        let ok = r#"{"width": 640, "height": 480, "fx": 517.3, "fy": 516.5, "cx": 318.6,
                     "cy": 255.3, "depth_scale": 5000.0}"#;
        assert_eq!(
            parse_camera_json(ok, p).unwrap(),
            CameraPreset::TumFr1.camera()
        );

        let missing = r#"{"width": 640, "height": 480, "fy": 516.5, "cx": 318.6,
                          "cy": 255.3, "depth_scale": 5000.0}"#;
        let msg = parse_camera_json(missing, p).unwrap_err().to_string();
        assert!(
            msg.contains("/some/where/camera.json") && msg.contains("fx"),
            "{msg}"
        );

        let zero = ok.replace("517.3", "0.0");
        let msg = parse_camera_json(&zero, p).unwrap_err().to_string();
        assert!(
            msg.contains("/some/where/camera.json") && msg.contains("fx"),
            "{msg}"
        );

        // JSON has no NaN; Python's json module writes it anyway.
        let nan = ok.replace("516.5", "NaN");
        let msg = parse_camera_json(&nan, p).unwrap_err().to_string();
        assert!(msg.contains("/some/where/camera.json"), "{msg}");
        // Too large for a double: serde_json refuses it, never reads it as inf.
        let inf = ok.replace("516.5", "1e400");
        let msg = parse_camera_json(&inf, p).unwrap_err().to_string();
        assert!(msg.contains("/some/where/camera.json"), "{msg}");

        // An array is not read by position.
        let arr = "[640, 480, 517.3, 516.5, 318.6, 255.3, 5000.0]";
        let msg = parse_camera_json(arr, p).unwrap_err().to_string();
        assert!(
            msg.contains("JSON object") && msg.contains("an array"),
            "{msg}"
        );

        // A byte-order mark is accepted.
        let bom = format!("\u{feff}{ok}");
        assert_eq!(
            parse_camera_json(&bom, p).unwrap(),
            CameraPreset::TumFr1.camera()
        );
    }
}
