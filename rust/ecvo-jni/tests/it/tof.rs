//! The two real `DEPTH16` frames of `phone_tof_samples` (a phone's ToF camera, 240x180):
//! they decode under the app's confidence rule into enough depth, and that depth,
//! centre-cropped to 16:9 and scaled to the tracker's 320x180 as the app does, prepares
//! into enough valid points to track (a frame tracked against itself stays put).
//! Skipped when the datasets are absent; a failure with `ECVO_REQUIRE_DATASETS=1`.

use ecvo_core::{
    Camera, Config, FrameView, Mode, Odometry, PreparedFrame, Preparer, Preset, TrackingState,
};
use ecvo_jni::{Confidence, Depth16Decoder, decode_depth16};

const W: usize = 240;
const H: usize = 180;
const OUT_W: usize = 320;
const OUT_H: usize = 180;

fn frames() -> Option<Vec<(String, Vec<u16>)>> {
    let dir = ecvo_io::datasets::dataset_for_test("phone_tof_samples")?;
    let mut out = Vec::new();
    for name in ["00000012_depth16.bin", "00003795_depth16.bin"] {
        let bytes = std::fs::read(dir.join(name)).expect("read DEPTH16 file");
        assert_eq!(
            bytes.len(),
            2 * W * H,
            "{name}: expected {W}x{H} 16-bit samples"
        );
        let raw = bytes
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        out.push((name.to_string(), raw));
    }
    Some(out)
}

/// The app's `DepthRemap` without distortion: the centred 16:9 window of the 4:3 frame
/// (240x135 from row 22.5), scaled by 4/3 to 320x180, nearest sample.
fn crop_to_frame(src: &[u16]) -> Vec<u16> {
    let s = W as f64 / OUT_W as f64; // 0.75
    let y0 = (H as f64 - OUT_H as f64 * s) / 2.0; // 22.5
    let mut out = vec![0u16; OUT_W * OUT_H];
    for v in 0..OUT_H {
        let y = ((v as f64 + 0.5) * s - 0.5 + y0).round() as usize;
        for u in 0..OUT_W {
            let x = ((u as f64 + 0.5) * s - 0.5).round() as usize;
            out[v * OUT_W + u] = src[y.min(H - 1) * W + x.min(W - 1)];
        }
    }
    out
}

/// A phone-like camera for the cropped frame: f about 0.8 x width of the 4:3 sensor.
fn camera() -> Camera {
    Camera {
        width: OUT_W,
        height: OUT_H,
        fx: 256.0,
        fy: 256.0,
        cx: 159.5,
        cy: 89.5,
        depth_scale: 1000.0,
    }
}

/// 8-bit intensity with texture: the depth itself, wrapped every 64 mm.
fn intensity_of(depth: &[u16]) -> Vec<u8> {
    depth.iter().map(|d| ((*d % 64) * 4) as u8).collect()
}

#[test]
fn documented_confidence_drops_most_of_one_real_frame() {
    let Some(frames) = frames() else { return };
    let kept_fraction = |raw: &[u16], min| {
        let ranged = raw.iter().filter(|v| **v & 0x1FFF != 0).count();
        let kept = raw.iter().filter(|v| decode_depth16(**v, min) != 0).count();
        kept as f64 / ranged as f64
    };
    // Frame 12 follows the documentation well enough; frame 3795 marks 81 % of its
    // ranged pixels with code 1 ("0 %"), which the documented rule throws away.
    assert!(kept_fraction(&frames[0].1, 1) > 0.95);
    assert!(kept_fraction(&frames[1].1, 1) < 0.25);
}

#[test]
fn real_frames_decode_and_prepare_into_trackable_depth() {
    let Some(frames) = frames() else { return };
    let config = Config::new(camera(), Preset::Phone, Mode::L2);
    for (name, raw) in frames {
        let decoder = Depth16Decoder::new(Confidence::Auto);
        let mut mm = raw.clone();
        let counts = decoder.decode_in_place(&mut mm);
        // AUTO keeps at least 80 % of the pixels of the 240x180 frame that have a range.
        assert!(
            counts.kept as f64 >= 0.8 * counts.ranged as f64 && counts.kept > W * H * 3 / 4,
            "{name}: {counts:?}, codes ignored {}",
            decoder.codes_ignored()
        );
        let depth = crop_to_frame(&mm);
        let gray = intensity_of(&depth);
        let mut prepared = PreparedFrame::for_config(&config);
        Preparer::new(&config)
            .prepare_into(
                FrameView {
                    timestamp: 0.0,
                    intensity: &gray,
                    depth: &depth,
                },
                &mut prepared,
            )
            .expect("prepare");
        let n = OUT_W * OUT_H;
        eprintln!(
            "{name}: {} of {} ranged kept; prepared valid depth {} of {n}; template points {:?}",
            counts.kept,
            counts.ranged,
            prepared.valid_depth,
            prepared
                .templates
                .iter()
                .map(|t| t.points.len())
                .collect::<Vec<_>>()
        );
        assert!(
            prepared.valid_depth > n / 2,
            "{name}: {} valid of {n}",
            prepared.valid_depth
        );
        for t in &prepared.templates {
            assert!(
                t.points.len() >= 100,
                "{name}: level {} has {} points",
                t.pyramid_level,
                t.points.len()
            );
        }

        // Enough to track: the same frame again registers, at (almost) no motion.
        let mut odo = Odometry::new(config.clone()).unwrap();
        for i in 0..2 {
            let out = odo
                .push(FrameView {
                    timestamp: i as f64 / 30.0,
                    intensity: &gray,
                    depth: &depth,
                })
                .unwrap();
            if i == 1 {
                assert_eq!(out.state, TrackingState::Tracking, "{name}");
                let t = out.pose.translation.vector.norm();
                assert!(t < 1e-3, "{name}: moved {t} m");
            }
        }
    }
}
