//! The DEPTH16 decoder of ecvo-jni (`decode_depth16`) on arbitrary planes, checked
//! against the format's definition; a whole 240x180 plane (the phone ToF size) also
//! goes through the filter stage.
#![no_main]

use ecvo_core::{Camera, Config, FrameView, Mode, PreparedFrame, Preparer, Preset};
use ecvo_jni::decode_depth16;
use libfuzzer_sys::fuzz_target;

const W: usize = 240;
const H: usize = 180;

fuzz_target!(|data: &[u8]| {
    let Some((&conf, plane)) = data.split_first() else {
        return;
    };
    let min_conf = conf % 8;
    let raw: Vec<u16> = plane
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    let decoded: Vec<u16> = raw.iter().map(|&r| decode_depth16(r, min_conf)).collect();
    for (&r, &d) in raw.iter().zip(&decoded) {
        let code = r >> 13;
        let level = if code == 0 { 7 } else { code - 1 };
        assert!(d <= 0x1FFF);
        if level < u16::from(min_conf) {
            assert_eq!(d, 0);
        } else {
            assert_eq!(d, r & 0x1FFF);
        }
        // Confidence 0 keeps every sample's range.
        assert_eq!(decode_depth16(r, 0), r & 0x1FFF);
    }
    if decoded.len() >= W * H {
        let camera = Camera {
            width: W,
            height: H,
            fx: 178.0,
            fy: 178.0,
            cx: 119.5,
            cy: 89.5,
            depth_scale: 1000.0,
        };
        let config = Config::new(camera, Preset::Phone, Mode::L2);
        let intensity: Vec<u8> = decoded[..W * H].iter().map(|&d| (d >> 5) as u8).collect();
        let mut prep = Preparer::new(&config);
        let mut out = PreparedFrame::for_config(&config);
        let view = FrameView {
            timestamp: 0.0,
            intensity: &intensity,
            depth: &decoded[..W * H],
        };
        prep.prepare_into(view, &mut out).expect("sizes match");
    }
});
