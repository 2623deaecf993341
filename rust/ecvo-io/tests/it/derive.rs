//! `ecvo_io::derive`: the half-resolution copy made as the shared datasets' README
//! describes, checked against `tum_fr1_xyz_half`, which was made that way from the
//! frames `tum_fr1_xyz_full300` holds; and end to end on a small folder.

use std::fs;
use std::path::Path;

use ecvo_io::derive::{DeriveOptions, derive_sequence};
use ecvo_io::png::{read_depth_png, read_intensity_png, write_depth_png, write_intensity_png};
use ecvo_io::{load_camera_json, save_camera_json};

use crate::common::{TempDir, small_camera};

fn data_lines(path: &Path) -> Vec<String> {
    fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(str::to_string)
        .collect()
}

/// The first 6 entries of each list of the 640x480 frames, halved, are those of the
/// 320x240 set: depth pixel for pixel, gray within 1 (full300's gray is rounded); the
/// lists, the ground truth and the intrinsics too.
#[test]
fn half_of_full300_is_tum_fr1_xyz_half() {
    let Some(full) = ecvo_io::dataset_for_test("tum_fr1_xyz_full300") else {
        return;
    };
    let Some(half) = ecvo_io::dataset_for_test("tum_fr1_xyz_half") else {
        return;
    };
    let tmp = TempDir::new("derive-half");
    let out = tmp.path().join("half");
    let opts = DeriveOptions {
        first_entries: Some(6),
        half: true,
        ..DeriveOptions::default()
    };
    let r = derive_sequence(&full, &out, &opts).unwrap();
    assert_eq!((r.rgb, r.depth, r.width, r.height), (6, 6, 320, 240));
    let (a, b) = (
        load_camera_json(out.join("camera.json")).unwrap(),
        load_camera_json(half.join("camera.json")).unwrap(),
    );
    assert_eq!(
        (a.width, a.height, a.depth_scale),
        (b.width, b.height, b.depth_scale)
    );
    for (x, y) in [(a.fx, b.fx), (a.fy, b.fy), (a.cx, b.cx), (a.cy, b.cy)] {
        assert!((x - y).abs() < 1e-9, "{a:?} against {b:?}");
    }
    for list in ["rgb.txt", "depth.txt"] {
        let got = data_lines(&out.join(list));
        assert_eq!(got[..], data_lines(&half.join(list))[..6], "{list}");
        for line in got {
            let file = line.split_whitespace().nth(1).unwrap().to_string();
            let (mut g, mut w) = (Vec::new(), Vec::new());
            if list == "rgb.txt" {
                read_intensity_png(out.join(&file), 320, 240, &mut g).unwrap();
                read_intensity_png(half.join(&file), 320, 240, &mut w).unwrap();
                // tum_fr1_xyz_half was made from the colour originals, full300 holds
                // them as rounded gray: each block's four roundings move its mean by
                // at most 0.5, so a value by at most 1.
                let off = g.iter().zip(&w).map(|(p, q)| p.abs_diff(*q)).max().unwrap();
                assert!(off <= 1, "{file}: gray differs by {off}");
                let same = g.iter().zip(&w).filter(|(p, q)| p == q).count();
                assert!(
                    same * 10 > g.len() * 6,
                    "{file}: only {same} of {} gray values equal",
                    g.len()
                );
            } else {
                let (mut gd, mut wd) = (Vec::new(), Vec::new());
                read_depth_png(out.join(&file), 320, 240, &mut gd).unwrap();
                read_depth_png(half.join(&file), 320, 240, &mut wd).unwrap();
                let differ = gd.iter().zip(&wd).filter(|(p, q)| p != q).count();
                assert_eq!(differ, 0, "{file}: {differ} depth pixels differ");
                assert!(
                    wd.iter().filter(|&&d| d == 0).count() > 1000,
                    "{file}: some blocks are invalid"
                );
            }
        }
    }
    assert_eq!(
        fs::read(out.join("groundtruth.txt")).unwrap(),
        fs::read(full.join("groundtruth.txt")).unwrap()
    );
}

/// A 16x16 sequence of 3 colour and 2 depth frames, one colour frame unpaired: the
/// half copy holds every listed image, `--first 1` the first pair only, and the
/// numbers are the rule's.
#[test]
fn derive_a_small_folder() {
    let tmp = TempDir::new("derive-small");
    let src = tmp.path().join("src");
    fs::create_dir_all(src.join("rgb")).unwrap();
    fs::create_dir_all(src.join("depth")).unwrap();
    let cam = small_camera(16, 16);
    save_camera_json(src.join("camera.json"), &cam).unwrap();
    let gray: Vec<u8> = (0..256).map(|i| ((i % 16) * 10 + i / 16) as u8).collect();
    // Depth 1000 but for: (3, 0) 1030, within 3 % of its block; (1, 2) 1031, beyond;
    // (2, 2) 0, invalid.
    let mut depth = vec![1000u16; 256];
    depth[3] = 1030;
    depth[2 * 16 + 1] = 1031;
    depth[2 * 16 + 2] = 0;
    let mut rgb_list = String::from("# color images\n# timestamp filename\n");
    let mut depth_list = String::from("# depth maps\n");
    for (k, t) in ["1.000000", "1.033000", "1.500000"].iter().enumerate() {
        write_intensity_png(src.join(format!("rgb/{t}.png")), &gray, 16, 16).unwrap();
        rgb_list += &format!("{t} rgb/{t}.png\n");
        if k < 2 {
            write_depth_png(src.join(format!("depth/{t}.png")), &depth, 16, 16).unwrap();
            depth_list += &format!("{t} depth/{t}.png\n");
        }
    }
    fs::write(src.join("rgb.txt"), &rgb_list).unwrap();
    fs::write(src.join("depth.txt"), &depth_list).unwrap();
    let out = tmp.path().join("half");
    let opts = DeriveOptions {
        half: true,
        ..DeriveOptions::default()
    };
    let r = derive_sequence(&src, &out, &opts).unwrap();
    assert_eq!((r.rgb, r.depth, r.width, r.height), (3, 2, 8, 8));
    assert_eq!(fs::read_to_string(out.join("rgb.txt")).unwrap(), rgb_list);
    let (mut g, mut d) = (Vec::new(), Vec::new());
    read_intensity_png(out.join("rgb/1.500000.png"), 8, 8, &mut g).unwrap();
    // (0 + 10 + 1 + 11) / 4 = 5.5 -> 6 (ties to even), (20 + 30 + 21 + 31) / 4 = 25.5
    // -> 26, the last (154 + 164 + 155 + 165) / 4 = 159.5 -> 160.
    assert_eq!((g[0], g[1], g[63]), (6, 26, 160));
    read_depth_png(out.join("depth/1.033000.png"), 8, 8, &mut d).unwrap();
    // 1007.5 -> 1008 (ties to even); 1031 is 3.1 % above 1000: invalid; a 0: invalid.
    assert_eq!(
        (d[0], d[1], d[2], d[8], d[9], d[63]),
        (1000, 1008, 1000, 0, 0, 1000)
    );
    assert_eq!(d.iter().filter(|&&v| v == 0).count(), 2);
    let c = load_camera_json(out.join("camera.json")).unwrap();
    assert_eq!((c.width, c.height), (8, 8));
    assert!((c.cx - ((cam.cx + 0.5) / 2.0 - 0.5)).abs() < 1e-12);
    assert!((c.fx - cam.fx / 2.0).abs() < 1e-12);
    // The first pair only.
    let first = tmp.path().join("first");
    let opts = DeriveOptions {
        first_pairs: Some(1),
        ..DeriveOptions::default()
    };
    let r = derive_sequence(&src, &first, &opts).unwrap();
    assert_eq!((r.rgb, r.depth, r.width, r.height), (1, 1, 16, 16));
    assert_eq!(
        data_lines(&first.join("depth.txt")),
        vec!["1.000000 depth/1.000000.png"]
    );
    assert_eq!(
        fs::read(first.join("rgb/1.000000.png")).unwrap(),
        fs::read(src.join("rgb/1.000000.png")).unwrap()
    );
}
