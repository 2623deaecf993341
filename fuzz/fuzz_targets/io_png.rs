//! The PNG readers of ecvo-io on arbitrary bytes: the header, then intensity and depth
//! decoding at the size the header claims (small sizes only: the sequence reader checks
//! the size against camera.json before decoding, and camera.json caps it at 8192x8192).
#![no_main]

use std::path::Path;

use ecvo_io::png::{decode_depth_png, decode_intensity_png, png_size_of};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.png");
    let Ok((w, h)) = png_size_of(data, path) else {
        return;
    };
    // Also a mismatching size: must be an error, never a panic or an allocation.
    let mut i = Vec::new();
    let mut d = Vec::new();
    assert!(decode_intensity_png(data, path, w + 1, h, &mut i).is_err());
    assert!(decode_depth_png(data, path, w, h + 1, &mut d).is_err());
    if w.saturating_mul(h) > 1 << 20 {
        return;
    }
    if decode_intensity_png(data, path, w, h, &mut i).is_ok() {
        assert_eq!(i.len(), w * h);
    }
    if decode_depth_png(data, path, w, h, &mut d).is_ok() {
        assert_eq!(d.len(), w * h);
    }
});
