use super::*;

fn cam() -> Camera {
    crate::camera::tum_fr1_half()
}

/// Asserts that `validate` names `field` for each of `values` set by `set`.
fn rejected(field: &str, values: &[f64], set: impl Fn(&mut Config, f64)) {
    for &v in values {
        let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
        set(&mut c, v);
        match c.validate() {
            Err(Error::InvalidConfig { field: f, .. }) => assert_eq!(f, field, "{v}"),
            other => panic!("{field} = {v} gave {other:?}"),
        }
    }
}

#[test]
fn presets_carry_the_papers_values() {
    let pc = Config::new(cam(), Preset::Pc, Mode::L2);
    assert_eq!(
        pc.reference_levels,
        vec![
            ReferenceLevel::mm_deg(30.0, 7.0),
            ReferenceLevel::mm_deg(120.0, 12.0)
        ]
    );
    assert_eq!(pc.filter.normal_max_angle_deg, Some(28.0));
    assert_eq!(pc.filter.contour_angle_deg, Some(7.0));
    assert_eq!(pc.motion.depth_gain, 1.8);
    let phone = Config::new(cam(), Preset::Phone, Mode::L1);
    assert_eq!(
        phone.reference_levels,
        vec![ReferenceLevel::mm_deg(30.0, 3.0)]
    );
    assert_eq!(phone.filter.normal_max_angle_deg, Some(45.0));
    assert_eq!(phone.filter.contour_angle_deg, Some(20.0));
    assert!(
        Config::new(cam(), Preset::Pc, Mode::Naive)
            .reference_levels
            .is_empty()
    );
    assert!(pc.validate().is_ok() && phone.validate().is_ok());
    // The paper's method registers against a reference only at a correction.
    assert_eq!(Config::paper(cam(), Preset::Pc, Mode::L2).refine_every, 0);
    assert!(pc.refine_every > 0);
}

#[test]
fn schedules_parse_by_name_and_by_steps() {
    assert_eq!(
        parse_schedule("paper", &cam()).unwrap(),
        Schedule::PaperSampling.levels()
    );
    assert_eq!(
        parse_schedule(" 3/1/20, 2/1/15,1/1/10,0/2/8", &cam()).unwrap(),
        Schedule::PyramidStride2.levels()
    );
    for bad in ["", "3/1", "3/1/20,", "a/1/2", "3/-1/2", "pyramid-stride3"] {
        assert!(
            matches!(
                parse_schedule(bad, &cam()),
                Err(Error::InvalidConfig {
                    field: "schedule",
                    ..
                })
            ),
            "{bad:?} parsed"
        );
    }
}

#[test]
fn validate_rejects_bad_fields() {
    let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
    c.motion.depth_gain = f64::NAN;
    assert!(matches!(
        c.validate(),
        Err(Error::InvalidConfig {
            field: "motion.depth_gain",
            ..
        })
    ));
    let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
    c.motion.levels[0].pyramid_level = 6;
    assert!(matches!(
        c.validate(),
        Err(Error::InvalidConfig {
            field: "motion.levels",
            ..
        })
    ));
    let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
    c.filter.contour_angle_deg = Some(95.0);
    assert!(matches!(
        c.validate(),
        Err(Error::InvalidConfig {
            field: "filter.contour_angle_deg",
            ..
        })
    ));
    rejected("max_spread_jump", &[1.0, 0.5, f64::NAN], |c, v| {
        c.max_spread_jump = v
    });
    rejected(
        "motion.depth_only_texture_fraction",
        &[-0.1, 1.5, f64::NAN],
        |c, v| c.motion.depth_only_texture_fraction = v,
    );
    rejected(
        "motion.max_fine_depth_weight",
        &[0.0, -1.0, f64::NAN],
        |c, v| c.motion.max_fine_depth_weight = v,
    );
    rejected(
        "motion.min_predicted_decrease",
        &[-1e-3, 1.0, f64::NAN, f64::INFINITY],
        |c, v| c.motion.min_predicted_decrease = v,
    );
    rejected(
        "motion.min_update_px",
        &[-0.01, f64::NAN, f64::INFINITY],
        |c, v| c.motion.min_update_px = v,
    );
    for bad in [0, 21] {
        let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
        c.motion.scale_passes_per_update = bad;
        assert!(matches!(
            c.validate(),
            Err(Error::InvalidConfig {
                field: "motion.scale_passes_per_update",
                ..
            })
        ));
    }
    let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
    c.motion.min_predicted_decrease = 0.0;
    c.motion.min_update_px = 0.0;
    assert!(c.validate().is_ok(), "0 switches the stops off");
    let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
    c.max_spread_jump = f64::INFINITY;
    c.motion.max_fine_depth_weight = f64::INFINITY;
    assert!(c.validate().is_ok(), "infinity switches the checks off");
}

#[test]
fn pyramid_schedules_move_up_on_large_images() {
    let steps = |c: &Camera| {
        Config::new(*c, Preset::Pc, Mode::L2)
            .motion
            .levels
            .iter()
            .map(|l| (l.pyramid_level, l.stride, l.max_iterations))
            .collect::<Vec<_>>()
    };
    let as_written = vec![(3, 1, 20), (2, 1, 15), (1, 1, 10), (0, 2, 8)];
    let phone = Camera {
        width: 320,
        height: 180,
        ..cam()
    };
    assert_eq!(steps(&cam()), as_written, "320x240");
    assert_eq!(steps(&phone), as_written, "320x180");
    let vga = crate::camera::tum_fr1();
    assert_eq!((vga.width, vga.height), (640, 480));
    assert_eq!(
        steps(&vga),
        vec![(4, 1, 20), (3, 1, 15), (2, 1, 10), (1, 1, 8)],
        "640x480: every pixel of the half-resolution image last"
    );
    let big = Camera {
        width: 1280,
        height: 960,
        ..vga
    };
    assert_eq!(Schedule::shift_for(&big), 2);
    assert_eq!(steps(&big)[3], (2, 1, 8));
    let huge = Camera {
        width: 8192,
        height: 6144,
        ..vga
    };
    assert_eq!(Schedule::shift_for(&huge), 3, "capped: level 6 at most");
    for c in [cam(), vga, big, huge] {
        assert!(Config::new(c, Preset::Pc, Mode::L2).validate().is_ok());
    }
    // Named on the command line, the same; the paper's sampling is never moved, and
    // steps written out are taken as written.
    assert_eq!(
        parse_schedule("pyramid-stride2", &vga).unwrap(),
        Config::new(vga, Preset::Pc, Mode::L2).motion.levels
    );
    assert_eq!(
        parse_schedule("paper", &vga).unwrap(),
        Schedule::PaperSampling.levels()
    );
    assert_eq!(
        parse_schedule("3/1/20,2/1/15,1/1/10,0/2/8", &vga).unwrap(),
        Schedule::PyramidStride2.levels()
    );
    assert_eq!(
        Config::paper(vga, Preset::Pc, Mode::L2).motion.levels,
        Schedule::PaperSampling.levels()
    );
}

#[test]
fn point_budgets_parse_apply_and_validate() {
    let steps = parse_schedule("3/1/20,1/1/10/4096,0/2/8/2048", &cam()).unwrap();
    assert_eq!(
        steps.iter().map(|l| l.max_points).collect::<Vec<_>>(),
        vec![None, Some(4096), Some(2048)]
    );
    assert!(
        parse_schedule("0/2/8/x", &cam()).is_err() && parse_schedule("0/2/8/1/1", &cam()).is_err()
    );
    assert_eq!(
        parse_point_budget(" 1=4096, 0=all").unwrap(),
        vec![(1, Some(4096)), (0, None)]
    );
    assert!(parse_point_budget("none").unwrap().is_empty());
    for bad in ["1", "1=", "x=5", "1=-3"] {
        assert!(parse_point_budget(bad).is_err(), "{bad:?} parsed");
    }
    let mut c = Config::new(cam(), Preset::Pc, Mode::L2);
    c.motion.set_point_budget(0, Some(3000));
    assert_eq!(c.motion.levels[3].max_points, Some(3000));
    assert!(c.motion.levels[..3].iter().all(|l| l.max_points.is_none()));
    assert!(c.validate().is_ok());
    c.motion.set_point_budget(0, Some(MIN_POINT_BUDGET - 1));
    assert!(matches!(
        c.validate(),
        Err(Error::InvalidConfig {
            field: "motion.levels.max_points",
            ..
        })
    ));
    // The paper's schedule samples every pixel it names.
    let paper = Config::paper(cam(), Preset::Pc, Mode::L2);
    assert!(paper.motion.levels.iter().all(|l| l.max_points.is_none()));
}

#[test]
fn levels_parse() {
    let l = parse_levels("30mm:7deg,0.12m:12deg").unwrap();
    assert_eq!(
        l,
        vec![
            ReferenceLevel::mm_deg(30.0, 7.0),
            ReferenceLevel {
                max_distance_m: 0.12,
                max_angle_deg: 12.0
            }
        ]
    );
    assert!(parse_levels("").unwrap().is_empty());
    assert!(parse_levels("30:7").is_err());
    assert!(parse_levels("30mm:7").is_err());
    assert!(parse_levels("-3mm:7deg").is_err());
}
