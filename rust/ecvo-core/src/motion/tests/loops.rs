//! The structure-of-arrays loops against the per-point loops they replaced
//! ([`super::super::reference`]): the warp bit for bit, the sums and the poses within
//! stated tolerances, on synthetic and on recorded frames, and the SIMD paths against
//! each other bit for bit.

use super::*;

/// Prepared frames `a` (reference) and `b` (current) of a synthetic sequence with
/// `camera` and `noise`, and the config.
fn pair(
    camera: SynthCamera,
    noise: DepthNoise,
    seed: u64,
    a: usize,
    b: usize,
    mode: Mode,
) -> (Config, PreparedFrame, PreparedFrame) {
    let mut seq = SynthSequence::phone_320x180(120, seed);
    seq.camera = camera;
    seq.noise = noise;
    let c = &seq.camera;
    let cam = Camera {
        width: c.width,
        height: c.height,
        fx: c.fx,
        fy: c.fy,
        cx: c.cx,
        cy: c.cy,
        depth_scale: c.depth_scale,
    };
    let cfg = Config::new(cam, Preset::Pc, mode);
    let mut preparer = Preparer::new(&cfg);
    let mut prep = |i: usize| {
        let f = seq.frame(i);
        let mut out = PreparedFrame::default();
        preparer
            .prepare_into(
                crate::FrameView {
                    timestamp: f.timestamp,
                    intensity: &f.intensity,
                    depth: &f.depth,
                },
                &mut out,
            )
            .unwrap();
        out
    };
    let (fa, fb) = (prep(a), prep(b));
    (cfg, fa, fb)
}

/// Small motions around the identity, to warp under.
fn poses() -> Vec<Pose> {
    [
        [0.0; 6],
        [0.01, -0.005, 0.02, 0.004, -0.006, 0.003],
        [-0.03, 0.02, -0.01, -0.01, 0.008, -0.012],
    ]
    .iter()
    .map(|v| se3::exp(&Vector6::from_column_slice(v)))
    .collect()
}

/// `|a − b| <= tol · (|b| + floor)`.
fn close(a: f64, b: f64, tol: f64, floor: f64) -> bool {
    (a - b).abs() <= tol * (b.abs() + floor)
}

/// The warp gives each point the bits the per-point warp gave it, in the same
/// order; the scale passes, the cost and the normal equations (sums in another
/// order) agree to a relative 1e-5 of each entry (1e-5 of the diagonal's scale for
/// the off-diagonal entries of `JᵀWJ`).
#[test]
fn loops_match_the_per_point_loops() {
    let cases = [
        (
            SynthCamera::phone_320x180(),
            DepthNoise::phone_like(),
            Weighting::Bivariate,
            DepthNoiseModel::Constant,
        ),
        (
            SynthCamera::phone_320x180(),
            DepthNoise::kinect_like(),
            Weighting::Scalar,
            DepthNoiseModel::Quadratic,
        ),
        (
            SynthCamera::tum_640x480(),
            DepthNoise::kinect_like(),
            Weighting::Bivariate,
            DepthNoiseModel::Quadratic,
        ),
        (
            SynthCamera::tum_640x480(),
            DepthNoise::kinect_like(),
            Weighting::Bivariate,
            DepthNoiseModel::Mixed { half_log2_alpha: 3 },
        ),
    ];
    simd::on_each_path(|path| {
        for (k, &(camera, noise, weighting, model)) in cases.iter().enumerate() {
            let (cfg, fa, fb) = pair(camera, noise, 3 + k as u64, 10, 12, Mode::L2);
            // Every other case without the photometric term (an untextured reference).
            let p = Params {
                photometric: k % 2 == 1,
                ..params(weighting, model)
            };
            for (step, template) in cfg.motion.levels.iter().zip(&fa.templates) {
                let level = &fb.levels[step.pyramid_level];
                let (mut new, mut old) = (MotionEstimator::new(), Reference::default());
                new.load(&template.points);
                old.load(&template.points);
                for t in poses() {
                    let at = format!("case {k} {path} level {}", step.pyramid_level);
                    let n = new.warp(&t, level, &p);
                    assert_eq!(n, old.warp(&t, level, &p), "{at}");
                    assert_eq!(new.counts(), old.counts(), "{at}");
                    let want = old.residuals();
                    let mut i = 0;
                    for c in new.warped() {
                        for j in 0..c.n {
                            let r = &want[i];
                            let got = [
                                c.ri[j], c.rz[j], c.sz[j], c.gx[j], c.gy[j], c.dx[j], c.dy[j],
                                c.x[j], c.y[j], c.z[j],
                            ];
                            let exp = [
                                r.ri, r.rz, r.sz, r.gx, r.gy, r.dx, r.dy, r.p[0], r.p[1], r.p[2],
                            ];
                            assert_eq!(
                                got.map(f32::to_bits),
                                exp.map(f32::to_bits),
                                "{at} point {i}"
                            );
                            if !p.photometric {
                                assert_eq!([r.ri, r.gx, r.gy], [0.0; 3], "{at} point {i}");
                            }
                            i += 1;
                        }
                    }
                    assert_eq!(new.moments(weighting), old.moments(weighting), "{at}");
                    let s = scale::next_scale(
                        &old.moments(weighting),
                        new.counts().0,
                        new.counts().1,
                        weighting,
                    )
                    .unwrap();
                    for s in [
                        s,
                        Scale {
                            ii: s.ii * 0.3,
                            iz: 0.2 * (s.ii * s.zz).sqrt(),
                            zz: s.zz * 2.0,
                        },
                    ] {
                        let wh = s.whitener(p.nu);
                        let ((a, pass_cost), (b, _)) =
                            (new.pass(&wh, weighting), old.pass(&wh, weighting));
                        for e in 0..4 {
                            assert!(
                                close(a[e], b[e], 1e-5, 1e-30),
                                "{at} pass {e}: {a:?} vs {b:?}"
                            );
                        }
                        let (a, b) = (new.cost(&wh), old.cost(&wh));
                        assert!(close(a, b, 1e-5, 0.0), "{at} cost {a} vs {b}");
                        // The pass and the normal equations sum the cost with the
                        // cost's own bits.
                        assert_eq!(pass_cost.to_bits(), a.to_bits(), "{at} pass cost");
                        let cost = a;
                        let a = new.normal_equations(level, &wh);
                        let b = old.normal_equations(level, &wh);
                        assert_eq!(a.error.to_bits(), cost.to_bits(), "{at} NE error");
                        assert_eq!(a.count, b.count);
                        let (ha, hb) = (a.hessian(), b.hessian());
                        for r in 0..6 {
                            for c in 0..6 {
                                let floor = (hb[(r, r)] * hb[(c, c)]).sqrt();
                                assert!(
                                    close(ha[(r, c)], hb[(r, c)], 1e-5, floor),
                                    "{at} H {r} {c}: {} vs {}",
                                    ha[(r, c)],
                                    hb[(r, c)]
                                );
                            }
                            let floor = hb[(r, r)].sqrt() * (b.error.max(1.0)).sqrt();
                            assert!(
                                close(a.g[r], b.g[r], 1e-5, floor),
                                "{at} g {r}: {} vs {}",
                                a.g[r],
                                b.g[r]
                            );
                        }
                    }
                }
            }
        }
    });
}

/// The pose of `MOTION` on synthetic frame pairs (two cameras, phone-like and
/// Kinect-like depth noise, both weightings, both depth noise models, one and two
/// initial guesses) agrees with the per-point loops' to 1e-5 m and 1e-5 rad, with
/// the same status; and the SIMD paths give the same bits.
#[test]
fn poses_match_the_per_point_loops() {
    let cases = [
        (
            SynthCamera::phone_320x180(),
            DepthNoise::none(),
            Mode::Naive,
            0,
            1,
        ),
        (
            SynthCamera::phone_320x180(),
            DepthNoise::phone_like(),
            Mode::L2,
            20,
            22,
        ),
        (
            SynthCamera::phone_320x180(),
            DepthNoise::kinect_like(),
            Mode::L2,
            40,
            44,
        ),
        (
            SynthCamera::tum_640x480(),
            DepthNoise::kinect_like(),
            Mode::L2,
            60,
            61,
        ),
        (
            SynthCamera::tum_640x480(),
            DepthNoise::phone_like(),
            Mode::L2,
            80,
            83,
        ),
    ];
    let mut worst = (0.0f64, 0.0f64);
    for (k, &(camera, noise, mode, a, b)) in cases.iter().enumerate() {
        let (mut cfg, fa, fb) = pair(camera, noise, 11 + k as u64, a, b, mode);
        for variant in 0..3 {
            match variant {
                1 => cfg.motion.weighting = Weighting::Scalar,
                2 => {
                    cfg.motion.weighting = Weighting::Bivariate;
                    cfg.motion.depth_noise = DepthNoiseModel::Quadratic;
                }
                _ => {}
            }
            let prior = se3::exp(&Vector6::new(0.004, 0.002, -0.003, 0.001, 0.002, -0.001));
            for inits in [vec![Pose::identity()], vec![Pose::identity(), prior]] {
                let at = format!("case {k} variant {variant} starts {}", inits.len());
                let want = estimator::motion_from(
                    &mut Reference::default(),
                    &fb,
                    &fa,
                    &inits,
                    &cfg.motion,
                );
                let mut bits = None;
                simd::on_each_path(|path| {
                    let got = MotionEstimator::new().motion_from(&fb, &fa, &inits, &cfg.motion);
                    assert_eq!(got.status, want.status, "{at} {path}");
                    assert_eq!(got.start, want.start, "{at} {path}");
                    let d = got.pose.inverse() * want.pose;
                    // 2 |sin(θ/2)| ≈ θ, accurate for small angles (unlike acos).
                    let (dt, da) = (d.translation.vector.norm(), 2.0 * d.rotation.imag().norm());
                    worst = (worst.0.max(dt), worst.1.max(da));
                    assert!(dt < 1e-5 && da < 1e-5, "{at} {path}: {dt:e} m {da:e} rad");
                    let b: Vec<u64> = got
                        .pose
                        .to_homogeneous()
                        .iter()
                        .map(|v| v.to_bits())
                        .collect();
                    if let Some(first) = &bits {
                        assert_eq!(&b, first, "{at}: the SIMD paths differ");
                    }
                    bits = Some(b);
                });
            }
        }
    }
    println!(
        "worst difference to the per-point loops: {:e} m, {:e} rad",
        worst.0, worst.1
    );
}

/// A recorded TUM RGB-D stream of the shared datasets: its camera and the `i`-th
/// colour and depth images of its lists (paired by index, close enough for a
/// test). `None` (SKIPPING printed) when the dataset is absent, a failure when
/// `ECVO_REQUIRE_DATASETS=1`.
struct Recorded {
    dir: std::path::PathBuf,
    camera: Camera,
    rgb: Vec<String>,
    depth: Vec<String>,
}

impl Recorded {
    /// The dataset `name` in `$ECVO_DATASETS`, or in the first `shared/datasets`
    /// above this crate (as `ecvo_io::datasets` finds them).
    fn open(name: &str) -> Option<Recorded> {
        use std::path::{Path, PathBuf};
        let root = std::env::var_os("ECVO_DATASETS")
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
            .or_else(|| {
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .ancestors()
                    .map(|a| a.join("shared").join("datasets"))
                    .find(|p| p.is_dir())
            });
        let Some(dir) = root
            .map(|r| r.join(name))
            .filter(|d| d.join("camera.json").is_file())
        else {
            let required = std::env::var("ECVO_REQUIRE_DATASETS").is_ok_and(|v| v.trim() == "1");
            assert!(
                !required,
                "dataset `{name}` not found, and ECVO_REQUIRE_DATASETS=1"
            );
            eprintln!("SKIPPING: dataset `{name}` not found");
            return None;
        };
        let json = std::fs::read_to_string(dir.join("camera.json")).unwrap();
        let field = |k: &str| -> f64 {
            let at = json.find(&format!("\"{k}\"")).unwrap() + k.len() + 2;
            let rest = json[at..].trim_start_matches([':', ' ']);
            let end = rest.find([',', '}']).unwrap();
            rest[..end].trim().parse().unwrap()
        };
        let camera = Camera {
            width: field("width") as usize,
            height: field("height") as usize,
            fx: field("fx"),
            fy: field("fy"),
            cx: field("cx"),
            cy: field("cy"),
            depth_scale: field("depth_scale"),
        };
        let list = |f: &str| -> Vec<String> {
            std::fs::read_to_string(dir.join(f))
                .unwrap()
                .lines()
                .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
                .map(|l| l.split_whitespace().nth(1).unwrap().to_string())
                .collect()
        };
        let (rgb, depth) = (list("rgb.txt"), list("depth.txt"));
        Some(Recorded {
            dir,
            camera,
            rgb,
            depth,
        })
    }

    /// Frame `i` prepared with `cfg`.
    fn prepared(&self, i: usize, cfg: &Config) -> PreparedFrame {
        let intensity = image::open(self.dir.join(&self.rgb[i]))
            .unwrap()
            .into_luma8();
        let depth = image::open(self.dir.join(&self.depth[i]))
            .unwrap()
            .into_luma16();
        let mut out = PreparedFrame::default();
        Preparer::new(cfg)
            .prepare_into(
                crate::FrameView {
                    timestamp: i as f64,
                    intensity: intensity.as_raw(),
                    depth: depth.as_raw(),
                },
                &mut out,
            )
            .unwrap();
        out
    }
}

/// The pose of `MOTION` on recorded frame pairs (fr1/desk at 640x480 and fr1/xyz at
/// 320x240, one to four frames apart, from the identity and from two guesses)
/// agrees with the per-point loops' to 1e-5 m and 1e-5 rad, with the same status.
#[test]
fn poses_on_recorded_frames_match_the_per_point_loops() {
    let mut worst = (0.0f64, 0.0f64);
    for (name, pairs) in [
        ("tum_fr1_desk_clip9", [(0, 1), (2, 4), (4, 8)]),
        ("tum_fr1_xyz_half", [(100, 101), (300, 302), (500, 504)]),
    ] {
        let Some(rec) = Recorded::open(name) else {
            continue;
        };
        let cfg = Config::new(rec.camera, Preset::Pc, Mode::L2);
        for (a, b) in pairs {
            let (fa, fb) = (rec.prepared(a, &cfg), rec.prepared(b, &cfg));
            let prior = se3::exp(&Vector6::new(0.004, 0.002, -0.003, 0.001, 0.002, -0.001));
            for inits in [vec![Pose::identity()], vec![Pose::identity(), prior]] {
                let at = format!("{name} {a}->{b} starts {}", inits.len());
                let want = estimator::motion_from(
                    &mut Reference::default(),
                    &fb,
                    &fa,
                    &inits,
                    &cfg.motion,
                );
                let got = MotionEstimator::new().motion_from(&fb, &fa, &inits, &cfg.motion);
                assert_eq!(got.status, want.status, "{at}");
                assert_eq!(got.start, want.start, "{at}");
                let d = got.pose.inverse() * want.pose;
                let (dt, da) = (d.translation.vector.norm(), 2.0 * d.rotation.imag().norm());
                worst = (worst.0.max(dt), worst.1.max(da));
                assert!(dt < 1e-5 && da < 1e-5, "{at}: {dt:e} m {da:e} rad");
            }
        }
    }
    println!(
        "worst difference to the per-point loops on recorded frames: {:e} m, {:e} rad",
        worst.0, worst.1
    );
}
