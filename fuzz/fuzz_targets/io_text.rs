//! The text parsers of ecvo-io: camera.json, TUM image lists, ICL-NUIM
//! associations.txt, TUM trajectories, the nearest-timestamp association of two
//! image lists, and how messages show hostile text (`ecvo_io::files::shown`). The
//! first byte picks the parser.
#![no_main]

use std::path::Path;

use ecvo_io::camera::parse_camera_json;
use ecvo_io::{Trajectory, associate_stamps, parse_associations, parse_image_list};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let path = Path::new("fuzz.txt");
    match which % 6 {
        0 => {
            if let Ok(c) = parse_camera_json(text, path) {
                // What the parser accepts, the core accepts.
                assert!(c.validate().is_ok());
                assert!(c.width >= 8 && c.height >= 8 && c.width <= 8192 && c.height <= 8192);
            }
        }
        1 => {
            if let Ok(list) = parse_image_list(text, path) {
                for w in list.windows(2) {
                    assert!(w[0].timestamp < w[1].timestamp);
                }
                assert!(list.iter().all(|e| e.timestamp.is_finite()));
                // Accepted entries stay inside the list's folder.
                for e in &list {
                    let p = Path::new(&e.file);
                    assert!(!p.is_absolute(), "{:?}", e.file);
                    let mut depth = 0i64;
                    for c in p.components() {
                        match c {
                            std::path::Component::ParentDir => depth -= 1,
                            std::path::Component::Normal(_) => depth += 1,
                            _ => {}
                        }
                        assert!(depth >= 0, "{:?}", e.file);
                    }
                }
            }
        }
        2 => {
            if let Ok(frames) = parse_associations(text, path, Path::new("dir")) {
                for w in frames.windows(2) {
                    assert!(w[0].timestamp < w[1].timestamp);
                }
            }
        }
        4 => {
            // Two lists separated by a blank line `---`, paired as Sequence::open pairs
            // rgb.txt and depth.txt: one-to-one, within max_dt.
            let (x, y) = text.split_once("---").unwrap_or((text, text));
            let (Ok(x), Ok(y)) = (parse_image_list(x, path), parse_image_list(y, path)) else {
                return;
            };
            let a: Vec<f64> = x.iter().map(|e| e.timestamp).collect();
            let b: Vec<f64> = y.iter().map(|e| e.timestamp).collect();
            let pairs = associate_stamps(&a, &b, 0.02);
            let mut used = vec![false; b.len()];
            for w in pairs.windows(2) {
                assert!(w[0].0 < w[1].0);
            }
            for &(i, j) in &pairs {
                assert!((a[i] - b[j]).abs() < 0.02);
                assert!(!used[j]);
                used[j] = true;
            }
        }
        5 => {
            // Messages: no control character survives, and the length is bounded.
            let s = ecvo_io::files::shown(text);
            assert!(!s.chars().any(|c| c.is_control()));
            assert!(s.chars().count() <= ecvo_io::files::MAX_SHOWN_CHARS + 40);
        }
        _ => {
            if let Ok(t) = Trajectory::parse_tum(text, path) {
                assert_eq!(t.stamps.len(), t.poses.len());
                for (s, p) in t.iter() {
                    assert!(s.is_finite());
                    assert!(ecvo_core::se3::is_finite(p));
                    assert!((p.rotation.quaternion().norm() - 1.0).abs() < 1e-9);
                }
                // Writing and reading back gives the same trajectory.
                let mut out = Vec::new();
                t.write_tum_to(&mut out).expect("writing to a Vec");
                let back = Trajectory::parse_tum(std::str::from_utf8(&out).expect("utf-8"), path)
                    .expect("a written trajectory parses");
                assert_eq!(back.len(), t.len());
                assert_eq!(back.stamps, t.stamps);
            }
        }
    }
});
