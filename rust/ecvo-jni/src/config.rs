//! `nativeInit`'s arguments, checked into the engine's configuration.

use std::sync::atomic::{AtomicUsize, Ordering};

use ecvo_core::{Camera, Config, DEFAULT_MEMORY_BUDGET, Mode, Preset};
use ecvo_pipeline::{Admission, GeometryOptions, Pipeline, PipelineOptions};
use ecvo_settings::{Settings, SettingsError};
use jni::sys::{jint, jlong};

use crate::depth16::Confidence;
use crate::error::{Failure, bad};
use crate::layout::{DepthFormat, TRAJECTORY_WINDOW};

/// The memory budget of the trackers `nativeInit` creates from now on, in bytes
/// (`nativeSetMemoryBudget`); [`DEFAULT_MEMORY_BUDGET`] (512 MiB) until set.
static MEMORY_BUDGET: AtomicUsize = AtomicUsize::new(DEFAULT_MEMORY_BUDGET);

/// The memory budget of the trackers created from now on, in bytes.
pub fn memory_budget() -> usize {
    MEMORY_BUDGET.load(Ordering::Relaxed)
}

/// Sets the memory budget of the trackers created from now on (trackers already
/// running keep theirs); returns the previous one. Refuses 0 and negative values.
pub fn set_memory_budget(bytes: jlong) -> Result<jlong, Failure> {
    let b = usize::try_from(bytes)
        .ok()
        .filter(|&b| b > 0)
        .ok_or_else(|| {
            bad(format!(
                "memoryBudget: {bytes} bytes is not a positive size"
            ))
        })?;
    let old = MEMORY_BUDGET.swap(b, Ordering::Relaxed);
    Ok(jlong::try_from(old).unwrap_or(jlong::MAX))
}

/// The settings of `nativeInit`, checked; the error names the bad field.
#[derive(Clone, Debug)]
pub struct InitArgs {
    /// Frame width in pixels.
    pub width: jint,
    /// Frame height in pixels.
    pub height: jint,
    /// Focal length x.
    pub fx: f64,
    /// Focal length y.
    pub fy: f64,
    /// Principal point x.
    pub cx: f64,
    /// Principal point y.
    pub cy: f64,
    /// `DepthFormat` code.
    pub depth_format: jint,
    /// Units per metre for `CUSTOM_SCALE`.
    pub depth_scale: f64,
    /// 0..=7, or -1 for [`Confidence::Auto`]; `DEPTH16` only.
    pub min_confidence: jint,
    /// `Preset` code.
    pub preset: jint,
    /// `Mode` code.
    pub mode: jint,
    /// Live (drop when busy) or offline.
    pub live: bool,
    /// Compute threads.
    pub threads: jint,
    /// Build the reference frames' point cloud (the geometry stage).
    pub point_cloud: bool,
}

impl InitArgs {
    /// What the app passes for a `width` x `height` depth camera in live mode: a
    /// focal length of 0.8 x the larger side, the principal point at the centre,
    /// depth in millimetres, the phone preset with two levels, two threads and the
    /// point cloud (the memory tests and examples measure this).
    pub fn app(width: jint, height: jint) -> InitArgs {
        let f = 0.8 * width.max(height) as f64;
        InitArgs {
            width,
            height,
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
            depth_format: 0,
            depth_scale: 1000.0,
            min_confidence: 0,
            preset: 1,
            mode: 2,
            live: true,
            threads: 2,
            point_cloud: true,
        }
    }

    /// The tracker configuration, pipeline options and depth decoding these settings
    /// describe, or `IllegalArgument` naming the bad field.
    pub fn build(&self) -> Result<(Config, PipelineOptions, DepthFormat, Confidence), Failure> {
        let size = |v: jint, name: &str| {
            usize::try_from(v).map_err(|_| bad(format!("{name}: {v} is negative")))
        };
        let width = size(self.width, "width")?;
        let height = size(self.height, "height")?;
        let format = DepthFormat::from_code(self.depth_format).ok_or_else(|| {
            bad(format!(
                "depthFormat: unknown code {} (0 MILLIMETRES, 1 DEPTH16, 2 CUSTOM_SCALE)",
                self.depth_format
            ))
        })?;
        let depth_scale = match format {
            DepthFormat::Millimetres | DepthFormat::Depth16 => 1000.0,
            DepthFormat::CustomScale => {
                let (lo, hi) = (
                    ecvo_core::camera::MIN_DEPTH_SCALE,
                    ecvo_core::camera::MAX_DEPTH_SCALE,
                );
                if !(lo..=hi).contains(&self.depth_scale) {
                    return Err(bad(format!(
                        "depthScale: {} units per metre is not in [{lo}, {hi}] (1000 for millimetres)",
                        ecvo_core::Num(self.depth_scale)
                    )));
                }
                self.depth_scale
            }
        };
        let min_confidence = match format {
            DepthFormat::Depth16 if self.min_confidence == -1 => Confidence::Auto,
            DepthFormat::Depth16 => u8::try_from(self.min_confidence)
                .ok()
                .filter(|c| *c <= 7)
                .map(Confidence::Documented)
                .ok_or_else(|| {
                    bad(format!(
                        "minConfidence: {} is not in 0..7 or -1 (auto)",
                        self.min_confidence
                    ))
                })?,
            _ => Confidence::Documented(0),
        };
        let preset = match self.preset {
            0 => Preset::Pc,
            1 => Preset::Phone,
            c => return Err(bad(format!("preset: unknown code {c} (0 PC, 1 PHONE)"))),
        };
        let mode = match self.mode {
            0 => Mode::Naive,
            1 => Mode::L1,
            2 => Mode::L2,
            c => return Err(bad(format!("mode: unknown code {c} (0 NAIVE, 1 L1, 2 L2)"))),
        };
        let threads = size(self.threads, "threads")?;
        if !(1..=256).contains(&threads) {
            return Err(bad(format!("threads: {threads} is not in 1..256")));
        }
        for (name, v) in [
            ("fx", self.fx),
            ("fy", self.fy),
            ("cx", self.cx),
            ("cy", self.cy),
        ] {
            if !v.is_finite() {
                return Err(bad(format!("{name}: {} is not finite", ecvo_core::Num(v))));
            }
        }
        let camera = Camera {
            width,
            height,
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            depth_scale,
        };
        // The one place settings become a Config (ecvo-settings), as for the CLI
        // and the Python package.
        let settings = Settings {
            memory_budget: Some(memory_budget()),
            ..Settings::new(preset, mode)
        };
        let config = settings.config(camera).map_err(|e| match e {
            SettingsError::Invalid(e) => bad(e.to_string()),
            e => bad(e.to_string()),
        })?;
        let options = PipelineOptions {
            threads,
            admission: if self.live {
                Admission::Live
            } else {
                Admission::Offline
            },
            geometry: self.point_cloud.then(GeometryOptions::default),
            keep_trajectory: true,
            trajectory_window: Some(TRAJECTORY_WINDOW),
            ..PipelineOptions::default()
        };
        Ok((config, options, format, min_confidence))
    }

    /// The bytes a tracker of these settings allocates ([`Pipeline::memory_needed`]),
    /// what `nativeInit` compares with the budget; or `IllegalArgument` naming the
    /// bad field.
    pub fn memory_needed(&self) -> Result<usize, Failure> {
        let (config, options, _, _) = self.build()?;
        Ok(Pipeline::memory_needed(&config, &options))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn init_names_bad_fields() {
        let good = InitArgs {
            width: 320,
            height: 180,
            fx: 250.0,
            fy: 250.0,
            cx: 159.5,
            cy: 89.5,
            depth_format: 0,
            depth_scale: 1000.0,
            min_confidence: 0,
            preset: 1,
            mode: 2,
            live: true,
            threads: 2,
            point_cloud: true,
        };
        assert!(good.build().is_ok());
        let msg = |a: InitArgs| match a.build() {
            Err(Failure::IllegalArgument(m)) => m,
            other => panic!("expected IllegalArgument, got {other:?}"),
        };
        assert!(
            msg(InitArgs {
                fx: f64::NAN,
                ..good.clone()
            })
            .contains("fx")
        );
        assert!(
            msg(InitArgs {
                width: 0,
                ..good.clone()
            })
            .contains("width")
        );
        assert!(
            msg(InitArgs {
                mode: 3,
                ..good.clone()
            })
            .contains("mode")
        );
        assert!(
            msg(InitArgs {
                preset: -1,
                ..good.clone()
            })
            .contains("preset")
        );
        assert!(
            msg(InitArgs {
                depth_format: 9,
                ..good.clone()
            })
            .contains("depthFormat")
        );
        assert!(
            msg(InitArgs {
                depth_format: 2,
                depth_scale: 0.0,
                ..good.clone()
            })
            .contains("depthScale")
        );
        // Numbers as written or with an exponent, never a 300-digit decimal.
        let m = msg(InitArgs {
            depth_format: 2,
            depth_scale: 1e300,
            ..good.clone()
        });
        assert!(m.starts_with("depthScale: 1e300 units per metre"), "{m}");
        assert!(m.len() < 120, "{} characters: {m}", m.len());
        let m = msg(InitArgs {
            fx: 1e300,
            ..good.clone()
        });
        assert!(m.contains("focal length 1e300 px"), "{m}");
        assert!(m.len() < 200, "{} characters: {m}", m.len());
        assert!(
            msg(InitArgs {
                depth_format: 1,
                min_confidence: 8,
                ..good.clone()
            })
            .contains("minConfidence")
        );
        assert!(
            msg(InitArgs {
                threads: 0,
                ..good.clone()
            })
            .contains("threads")
        );
        assert!(
            msg(InitArgs {
                threads: -3,
                ..good
            })
            .contains("threads")
        );
    }
}
