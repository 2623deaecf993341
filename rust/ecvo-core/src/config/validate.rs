//! [`Config::validate`]: every field checked, the error naming the first bad one.

use super::{Config, MAX_PYRAMID_LEVEL, MIN_LEVEL_SIDE, MIN_POINT_BUDGET, Schedule};
use crate::error::{Error, Result};

impl Config {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &'static str, why: String| Err(Error::InvalidConfig { field, why });
        self.camera.validate()?;
        self.imu.validate()?;
        let f = &self.filter;
        if let Some(b) = f.bilateral {
            if b.radius == 0 || b.radius > 8 {
                return bad(
                    "filter.bilateral.radius",
                    format!("{} is not in 1..=8", b.radius),
                );
            }
            if !(b.sigma_space_px > 0.0 && b.sigma_space_px.is_finite()) {
                return bad(
                    "filter.bilateral.sigma_space_px",
                    format!("{} is not positive", b.sigma_space_px),
                );
            }
            // Above 0.35 a missing neighbour (depth 0) would get a range weight and
            // pull the smoothed depth towards 0.
            if !(b.sigma_depth_rel > 0.0 && b.sigma_depth_rel <= 0.35) {
                return bad(
                    "filter.bilateral.sigma_depth_rel",
                    format!("{} is not in (0, 0.35]", b.sigma_depth_rel),
                );
            }
        }
        for (field, v) in [
            ("filter.normal_max_angle_deg", f.normal_max_angle_deg),
            ("filter.contour_angle_deg", f.contour_angle_deg),
        ] {
            if let Some(v) = v
                && !(v > 0.0 && v < 90.0)
            {
                return bad(field, format!("{v} is not an angle in (0, 90) degrees"));
            }
        }
        if !(f.min_depth_m >= 0.0 && f.max_depth_m > f.min_depth_m && f.max_depth_m.is_finite()) {
            return bad(
                "filter.min_depth_m/max_depth_m",
                format!(
                    "[{}, {}] is not a depth range",
                    f.min_depth_m, f.max_depth_m
                ),
            );
        }
        let m = &self.motion;
        if !(m.depth_gain >= 0.0 && m.depth_gain.is_finite()) {
            return bad(
                "motion.depth_gain",
                format!("{} is not finite and non-negative", m.depth_gain),
            );
        }
        if !(m.t_dof > 0.0 && m.t_dof.is_finite()) {
            return bad("motion.t_dof", format!("{} is not positive", m.t_dof));
        }
        if m.levels.is_empty() {
            return bad("motion.levels", "no coarse-to-fine level".into());
        }
        let deepest = m.levels.iter().map(|l| l.pyramid_level).max().unwrap_or(0);
        let allowed = Schedule::max_level_for(&self.camera);
        if deepest > allowed {
            let (w, h) = (self.camera.width >> deepest, self.camera.height >> deepest);
            return bad(
                "motion.levels",
                format!(
                    "the schedule uses pyramid level {deepest}, which is {w}x{h} for a {}x{} image; this size allows levels 0..={allowed} (each at least {MIN_LEVEL_SIDE}x{MIN_LEVEL_SIDE}, at most level {MAX_PYRAMID_LEVEL})",
                    self.camera.width, self.camera.height
                ),
            );
        }
        for l in &m.levels {
            if l.stride == 0 || l.stride > 16 {
                return bad(
                    "motion.levels.stride",
                    format!("{} is not in 1..=16", l.stride),
                );
            }
            if let Some(n) = l.max_points
                && n < MIN_POINT_BUDGET
            {
                return bad(
                    "motion.levels.max_points",
                    format!("{n} is below {MIN_POINT_BUDGET}"),
                );
            }
            if l.max_iterations == 0 || l.max_iterations > 1000 {
                return bad(
                    "motion.levels.max_iterations",
                    format!("{} is not in 1..=1000", l.max_iterations),
                );
            }
        }
        if !(m.min_update > 0.0 && m.min_update.is_finite()) {
            return bad(
                "motion.min_update",
                format!("{} is not positive", m.min_update),
            );
        }
        if !(m.min_update_px >= 0.0 && m.min_update_px.is_finite()) {
            return bad(
                "motion.min_update_px",
                format!("{} is not a finite non-negative number", m.min_update_px),
            );
        }
        if !(m.min_predicted_decrease >= 0.0 && m.min_predicted_decrease < 1.0) {
            return bad(
                "motion.min_predicted_decrease",
                format!("{} is not in [0, 1)", m.min_predicted_decrease),
            );
        }
        if !(1..=crate::config::MAX_SCALE_PASSES).contains(&m.scale_passes_per_update) {
            return bad(
                "motion.scale_passes_per_update",
                format!(
                    "{} is not in 1..={}",
                    m.scale_passes_per_update,
                    crate::config::MAX_SCALE_PASSES
                ),
            );
        }
        if !(m.scale_tolerance > 0.0 && m.scale_tolerance <= 0.1) {
            return bad(
                "motion.scale_tolerance",
                format!("{} is not in (0, 0.1]", m.scale_tolerance),
            );
        }
        if !(m.max_intensity_sigma > 0.0 && m.max_depth_sigma_m > 0.0) {
            return bad(
                "motion.max_intensity_sigma/max_depth_sigma_m",
                "must be positive".into(),
            );
        }
        if !(m.max_fine_depth_weight > 0.0) {
            return bad(
                "motion.max_fine_depth_weight",
                format!("{} is not positive", m.max_fine_depth_weight),
            );
        }
        if !(0.0..=1.0).contains(&m.depth_only_texture_fraction) {
            return bad(
                "motion.depth_only_texture_fraction",
                format!("{} is not in [0, 1]", m.depth_only_texture_fraction),
            );
        }
        if !(m.max_translation_m > 0.0 && m.max_rotation_deg > 0.0) {
            return bad(
                "motion.max_translation_m/max_rotation_deg",
                "must be positive".into(),
            );
        }
        if !(self.max_speed_m_s > 0.0) {
            return Err(Error::InvalidConfig {
                field: "max_speed_m_s",
                why: format!("{} is not positive", self.max_speed_m_s),
            });
        }
        if !(self.max_spread_jump > 1.0) {
            return bad(
                "max_spread_jump",
                format!("{} is not above 1", self.max_spread_jump),
            );
        }
        if !(self.max_correction_distance > 0.0) {
            return bad(
                "max_correction_distance",
                format!("{} is not positive", self.max_correction_distance),
            );
        }
        if self.keyframes && self.reference_levels.is_empty() {
            return bad(
                "keyframes",
                "keyframe tracking needs a reference level (the keyframe is the level-1 reference)"
                    .into(),
            );
        }
        if !(self.keyframe_max_spread_growth >= 1.0) {
            return bad(
                "keyframe_max_spread_growth",
                format!("{} is not at least 1", self.keyframe_max_spread_growth),
            );
        }
        for (field, v) in [
            ("keyframe_min_overlap", self.keyframe_min_overlap),
            ("min_anchor_depth_fraction", self.min_anchor_depth_fraction),
            (
                "min_anchor_texture_fraction",
                self.min_anchor_texture_fraction,
            ),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(field, format!("{v} is not a fraction in [0, 1]"));
            }
        }
        if self.memory_budget == 0 {
            return bad("memory_budget", "0 bytes is no budget".into());
        }
        for l in &self.reference_levels {
            if !(l.max_distance_m >= 0.0 && l.max_distance_m.is_finite()) {
                return bad(
                    "reference_levels.max_distance_m",
                    format!("{} is not a distance", l.max_distance_m),
                );
            }
            if !(l.max_angle_deg >= 0.0 && l.max_angle_deg < 180.0) {
                return bad(
                    "reference_levels.max_angle_deg",
                    format!("{} is not in [0, 180)", l.max_angle_deg),
                );
            }
        }
        Ok(())
    }
}
