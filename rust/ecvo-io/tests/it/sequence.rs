//! Sequences: the shared TUM datasets, synthetic ICL-NUIM folders, streaming, the
//! writer round trip, and bad inputs.

use crate::common;

use std::path::Path;

use common::{TempDir, small_camera, test_images, write_raw_png};
use ecvo_io::{
    Camera, CameraPreset, Error, Frame, Layout, Pose, Sequence, SequenceWriter, Trajectory,
    dataset_for_test, load_camera_json, png::rgb_to_gray, save_camera_json,
};
use image::ExtendedColorType;

// ---------------------------------------------------------------- real datasets

#[test]
fn half_resolution_dataset_opens_and_decodes() {
    let Some(dir) = dataset_for_test("tum_fr1_xyz_half") else {
        return;
    };
    let seq = Sequence::open(&dir, None).unwrap();
    assert_eq!(seq.layout(), Layout::Tum);
    assert_eq!((seq.camera().width, seq.camera().height), (320, 240));
    assert_eq!(seq.camera().fx, 258.65);
    assert_eq!(seq.dir(), dir.as_path());
    // 798 colour and 798 depth images; TUM's associate.py pairs 792 of them, the last
    // being (1305031128.747363, 1305031128.754646).
    assert_eq!(seq.len(), 792);
    let last = seq.frames().last().unwrap();
    assert_eq!(
        (last.timestamp, last.depth_timestamp),
        (1305031128.747363, 1305031128.754646)
    );
    let ts = seq.timestamps();
    assert!(ts.windows(2).all(|w| w[1] > w[0]));
    assert_eq!(ts[0], 1305031102.175304);
    let first = &seq.frames()[0];
    assert!(first.rgb.ends_with("rgb/1305031102.175304.png"));
    assert!(first.depth.ends_with("depth/1305031102.160407.png"));
    for f in seq.frames() {
        assert!((f.timestamp - f.depth_timestamp).abs() < 0.02);
    }
    let gt = seq.groundtruth().expect("groundtruth.txt");
    assert!(gt.len() > 2900);

    let f = seq.load_frame(0).unwrap();
    assert_eq!((f.index, f.timestamp), (0, ts[0]));
    assert_eq!(f.intensity.len(), 320 * 240);
    assert_eq!(f.depth.len(), 320 * 240);
    let valid = f.depth.iter().filter(|&&d| d > 0).count();
    assert!(valid > 320 * 240 / 2, "{valid} valid depths");
    f.view().validate(seq.camera()).unwrap();

    // load_frame_into reuses the buffers.
    let mut g = f.clone();
    let (pi, pd) = (g.intensity.as_ptr(), g.depth.as_ptr());
    seq.load_frame_into(5, &mut g).unwrap();
    assert_eq!((g.index, g.timestamp), (5, ts[5]));
    assert_eq!((g.intensity.as_ptr(), g.depth.as_ptr()), (pi, pd));
    assert_ne!(g.intensity, f.intensity);

    assert!(matches!(
        seq.load_frame(seq.len()),
        Err(Error::FrameIndex { .. })
    ));
}

#[test]
fn streaming_reader_matches_random_access_and_recycles() {
    let Some(dir) = dataset_for_test("tum_fr1_xyz_half") else {
        return;
    };
    let seq = Sequence::open(&dir, None).unwrap();
    let mut reader = seq.reader(Some(40), 3);
    assert_eq!(reader.remaining(), 40);
    let mut n = 0;
    let mut recycled = Vec::new();
    let mut reused = 0;
    while let Some(frame) = reader.next() {
        let frame = frame.unwrap();
        assert_eq!(frame.index, n);
        if n % 9 == 0 {
            assert_eq!(frame, seq.load_frame(n).unwrap());
        }
        if recycled.contains(&frame.depth.as_ptr()) {
            reused += 1;
        }
        recycled.push(frame.depth.as_ptr());
        reader.recycle(frame);
        n += 1;
    }
    assert_eq!(n, 40);
    assert!(reused > 20, "only {reused} frames reused a recycled buffer");
    assert!(reader.next().is_none());

    // Dropping early stops and joins the thread (the test would hang otherwise).
    let mut reader = seq.reader(None, 2);
    let f = reader.next().unwrap().unwrap();
    assert_eq!(f.index, 0);
    drop(reader);

    // Never-consumed reader.
    drop(seq.reader(None, 4));
    // More frames than the sequence has.
    assert_eq!(
        seq.reader(Some(seq.len() + 10), 1)
            .skip(seq.len() - 3)
            .count(),
        3
    );
}

#[test]
fn full_resolution_dataset_and_camera_override() {
    let Some(dir) = dataset_for_test("tum_fr1_xyz_full300") else {
        return;
    };
    let seq = Sequence::open(&dir, Some(CameraPreset::TumFr1.camera())).unwrap();
    assert_eq!(*seq.camera(), CameraPreset::TumFr1.camera());
    assert_eq!(seq.len(), 294); // as TUM's associate.py pairs the 300 + 300 images
    let f = seq.load_frame(seq.len() - 1).unwrap();
    assert_eq!(f.intensity.len(), 640 * 480);

    // A camera of the wrong size: the error names the PNG and both sizes.
    let half = CameraPreset::TumFr1.camera().half();
    let msg = Sequence::open(&dir, Some(half)).unwrap_err().to_string();
    assert!(
        msg.contains(".png") && msg.contains("640x480") && msg.contains("320x240"),
        "{msg}"
    );
}

#[test]
fn colour_dataset_is_converted_to_gray() {
    let Some(dir) = dataset_for_test("tum_fr1_desk_clip9") else {
        return;
    };
    let seq = Sequence::open(&dir, None).unwrap();
    assert_eq!(seq.len(), 9);
    // The ground truth covers the whole of fr1/desk, much longer than the clip.
    let gt = seq.groundtruth().unwrap();
    assert!(gt.stamps[0] < seq.timestamps()[0] && *gt.stamps.last().unwrap() > seq.timestamps()[8]);
    let f = seq.load_frame(0).unwrap();
    let rgb = image::open(&seq.frames()[0].rgb).unwrap().to_rgb8();
    for (k, p) in rgb.pixels().enumerate().step_by(997) {
        assert_eq!(f.intensity[k], rgb_to_gray(p[0], p[1], p[2]));
    }
    let frames: Vec<Frame> = seq.reader(None, 2).map(|f| f.unwrap()).collect();
    assert_eq!(frames.len(), 9);
    assert_eq!(frames[0], f);
}

// ---------------------------------------------------------------- writer round trip

#[test]
fn writer_round_trip_is_bit_exact() {
    let tmp = TempDir::new("roundtrip");
    let dir = tmp.path().join("rec");
    let cam = small_camera(40, 30);
    let stamps = [
        1700000000.123456,
        1700000000.156789,
        1700000000.19,
        1700000001.0,
    ];
    let mut gt = Trajectory::new();
    let mut w = SequenceWriter::create(&dir, &cam).unwrap();
    let mut written = Vec::new();
    for (k, &t) in stamps.iter().enumerate() {
        let (i, d) = test_images(40, 30, k as u64);
        w.write_frame(t, &i, &d).unwrap();
        written.push((i, d));
        gt.push(t, Pose::translation(0.1 * k as f64, 1.0 / 3.0, -2.0));
    }
    // Bad calls are errors, not panics, and write nothing.
    assert!(
        w.write_frame(1700000001.0, &written[0].0, &written[0].1)
            .is_err()
    );
    assert!(
        w.write_frame(1800000000.0, &written[0].0[1..], &written[0].1)
            .is_err()
    );
    assert!(
        w.write_frame(f64::NAN, &written[0].0, &written[0].1)
            .is_err()
    );
    w.write_groundtruth(&gt).unwrap();
    assert_eq!(w.frames_written(), 4);
    assert_eq!(w.finish().unwrap(), 4);

    // Refuses to overwrite.
    assert!(SequenceWriter::create(&dir, &cam).is_err());

    assert!(dir.join("rgb/1700000000.123456.png").is_file());
    assert!(dir.join("depth/1700000000.190000.png").is_file());
    let rgb_txt = std::fs::read_to_string(dir.join("rgb.txt")).unwrap();
    assert!(rgb_txt.starts_with("# "));
    assert!(rgb_txt.contains("\n1700000000.190000 rgb/1700000000.190000.png\n"));

    let seq = Sequence::open(&dir, None).unwrap();
    assert_eq!(*seq.camera(), cam);
    assert_eq!(seq.len(), 4);
    for (k, f) in seq.reader(None, 1).enumerate() {
        let f = f.unwrap();
        assert_eq!(f.index, k);
        assert!((f.timestamp - stamps[k]).abs() < 1e-6);
        assert_eq!(f.intensity, written[k].0, "intensity of frame {k}");
        assert_eq!(f.depth, written[k].1, "depth of frame {k}");
    }
    let back = seq.groundtruth().unwrap();
    assert_eq!(back.stamps, gt.stamps);
    assert_eq!(back.poses, gt.poses);
}

// ---------------------------------------------------------------- ICL-NUIM layout

#[test]
fn icl_nuim_layout_uses_ids_as_timestamps() {
    let tmp = TempDir::new("icl");
    let dir = tmp.path();
    let cam = small_camera(16, 12);
    std::fs::create_dir_all(dir.join("rgb")).unwrap();
    std::fs::create_dir_all(dir.join("depth")).unwrap();
    let mut assoc = String::new();
    let mut images = Vec::new();
    for id in 0..3 {
        let (i, d) = test_images(16, 12, 100 + id);
        // Colour PNGs as ICL-NUIM ships them: 8-bit RGB.
        let rgb: Vec<u8> = i.iter().flat_map(|&v| [v, v / 2, 255 - v]).collect();
        write_raw_png(
            &dir.join(format!("rgb/{id}.png")),
            &rgb,
            16,
            12,
            ExtendedColorType::Rgb8,
        );
        ecvo_io::png::write_depth_png(dir.join(format!("depth/{id}.png")), &d, 16, 12).unwrap();
        assoc.push_str(&format!("{id} depth/{id}.png {id} rgb/{id}.png\n"));
        images.push((rgb, d));
    }
    std::fs::write(dir.join("associations.txt"), assoc).unwrap();
    std::fs::write(
        dir.join("livingRoom0.gt.freiburg"),
        "0 0 0 0 0 0 0 1\n1 0.01 0 0 0 0 0 1\n2 0.02 0 0 0 0 0 1\n",
    )
    .unwrap();

    // No camera.json: the error says to pass one.
    let msg = Sequence::open(dir, None).unwrap_err().to_string();
    assert!(
        msg.contains("camera.json") && msg.contains("pass a camera"),
        "{msg}"
    );

    let seq = Sequence::open(dir, Some(cam)).unwrap();
    assert_eq!(seq.layout(), Layout::IclNuim);
    assert_eq!(seq.timestamps(), vec![0.0, 1.0, 2.0]);
    assert_eq!(seq.groundtruth().unwrap().stamps, vec![0.0, 1.0, 2.0]);
    let f = seq.load_frame(2).unwrap();
    assert_eq!(f.timestamp, 2.0);
    assert_eq!(f.depth, images[2].1);
    let want: Vec<u8> = images[2]
        .0
        .chunks(3)
        .map(|p| rgb_to_gray(p[0], p[1], p[2]))
        .collect();
    assert_eq!(f.intensity, want);
}

// ---------------------------------------------------------------- bad input

/// A valid 16x12 TUM folder with two frames; returns the camera.
fn make_tum(dir: &Path) -> Camera {
    let cam = small_camera(16, 12);
    let mut w = SequenceWriter::create(dir, &cam).unwrap();
    for k in 0..2 {
        let (i, d) = test_images(16, 12, k);
        w.write_frame(10.0 + k as f64 / 30.0, &i, &d).unwrap();
    }
    w.finish().unwrap();
    cam
}

fn open_err(dir: &Path) -> String {
    let e = Sequence::open(dir, None).unwrap_err();
    let msg = e.to_string();
    println!("{msg}");
    msg
}

#[test]
fn missing_files_are_named() {
    let tmp = TempDir::new("missing");
    let msg = open_err(&tmp.path().join("nope"));
    assert!(msg.contains("nope"), "{msg}");
    let msg = open_err(tmp.path());
    assert!(msg.contains("not a sequence folder"), "{msg}");

    make_tum(tmp.path());
    std::fs::remove_file(tmp.path().join("depth.txt")).unwrap();
    let msg = open_err(tmp.path());
    assert!(msg.contains("depth.txt"), "{msg}");

    let tmp = TempDir::new("missing-png");
    make_tum(tmp.path());
    let seq = Sequence::open(tmp.path(), None).unwrap();
    let second = seq.frames()[1].depth.clone();
    std::fs::remove_file(&second).unwrap();
    let e = seq.load_frame(1).unwrap_err();
    assert!(e.to_string().contains(&*second.to_string_lossy()), "{e}");
    // A decode error ends the stream with that error.
    let items: Vec<_> = seq.reader(None, 4).collect();
    assert_eq!(items.len(), 2);
    assert!(items[0].is_ok());
    let msg = items[1].as_ref().unwrap_err().to_string();
    assert!(msg.contains(&*second.to_string_lossy()), "{msg}");

    let tmp = TempDir::new("missing-cam");
    make_tum(tmp.path());
    std::fs::remove_file(tmp.path().join("camera.json")).unwrap();
    let msg = open_err(tmp.path());
    assert!(msg.contains("pass a camera"), "{msg}");
    assert!(Sequence::open(tmp.path(), Some(small_camera(16, 12))).is_ok());
}

#[test]
fn malformed_and_non_monotonic_lines_name_file_and_line() {
    let tmp = TempDir::new("malformed");
    make_tum(tmp.path());
    let rgb = tmp.path().join("rgb.txt");
    let good = std::fs::read_to_string(&rgb).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    assert_eq!(lines.len(), 5); // 3 header lines, 2 frames

    std::fs::write(&rgb, format!("{good}\n\n10.5\n")).unwrap();
    let msg = open_err(tmp.path());
    assert!(msg.contains("rgb.txt:8:"), "{msg}");

    std::fs::write(&rgb, format!("{good}abc rgb/x.png\n")).unwrap();
    let msg = open_err(tmp.path());
    assert!(msg.contains("rgb.txt:6:") && msg.contains("abc"), "{msg}");

    // Swap the two frame lines: line 5 goes back in time.
    std::fs::write(
        &rgb,
        format!(
            "{}\n{}\n{}\n{}\n{}\n",
            lines[0], lines[1], lines[2], lines[4], lines[3]
        ),
    )
    .unwrap();
    let e = Sequence::open(tmp.path(), None).unwrap_err();
    assert!(matches!(e, Error::NonMonotonic { line: 5, .. }), "{e}");
    assert!(e.to_string().contains("rgb.txt:5:"), "{e}");

    std::fs::write(&rgb, &good).unwrap();
    std::fs::write(tmp.path().join("groundtruth.txt"), "1 2 3\n").unwrap();
    let msg = open_err(tmp.path());
    assert!(msg.contains("groundtruth.txt:1:"), "{msg}");
}

#[test]
fn wrong_bit_depth_colour_type_and_size_are_named() {
    let tmp = TempDir::new("bitdepth");
    make_tum(tmp.path());
    let seq = Sequence::open(tmp.path(), None).unwrap();
    let f1 = seq.frames()[1].clone();

    // 16-bit gray as intensity.
    let d16: Vec<u8> = vec![7; 16 * 12 * 2];
    write_raw_png(&f1.rgb, &d16, 16, 12, ExtendedColorType::L16);
    let msg = seq.load_frame(1).unwrap_err().to_string();
    assert!(
        msg.contains(&*f1.rgb.to_string_lossy()) && msg.contains("16-bit gray"),
        "{msg}"
    );

    // RGBA intensity is fine.
    let rgba: Vec<u8> = (0..16 * 12).flat_map(|k| [k as u8, 0, 255, 9]).collect();
    write_raw_png(&f1.rgb, &rgba, 16, 12, ExtendedColorType::Rgba8);
    let f = seq.load_frame(1).unwrap();
    assert_eq!(f.intensity[3], rgb_to_gray(3, 0, 255));

    // 8-bit depth.
    write_raw_png(&f1.depth, &[1u8; 16 * 12], 16, 12, ExtendedColorType::L8);
    let msg = seq.load_frame(1).unwrap_err().to_string();
    assert!(
        msg.contains(&*f1.depth.to_string_lossy()) && msg.contains("8-bit gray"),
        "{msg}"
    );

    // 16-bit RGB depth.
    write_raw_png(
        &f1.depth,
        &vec![1u8; 16 * 12 * 6],
        16,
        12,
        ExtendedColorType::Rgb16,
    );
    let msg = seq.load_frame(1).unwrap_err().to_string();
    assert!(msg.contains("depth") && msg.contains("16-bit RGB"), "{msg}");

    // Wrong size.
    ecvo_io::png::write_depth_png(&f1.depth, &[1u16; 15 * 12], 15, 12).unwrap();
    let msg = seq.load_frame(1).unwrap_err().to_string();
    assert!(
        msg.contains(&*f1.depth.to_string_lossy())
            && msg.contains("15x12")
            && msg.contains("16x12"),
        "{msg}"
    );

    // Not a PNG at all.
    std::fs::write(&f1.depth, b"not a png").unwrap();
    let msg = seq.load_frame(1).unwrap_err().to_string();
    assert!(msg.contains(&*f1.depth.to_string_lossy()), "{msg}");

    // A first frame of the wrong size is caught at open time.
    let f0 = seq.frames()[0].clone();
    write_raw_png(&f0.rgb, &[1u8; 8 * 12], 8, 12, ExtendedColorType::L8);
    let msg = open_err(tmp.path());
    assert!(
        msg.contains(&*f0.rgb.to_string_lossy()) && msg.contains("8x12"),
        "{msg}"
    );
}

#[test]
fn camera_json_errors_name_the_file() {
    let tmp = TempDir::new("camjson");
    let p = tmp.path().join("camera.json");
    let cam = CameraPreset::TumFr3.camera();
    save_camera_json(&p, &cam).unwrap();
    assert_eq!(load_camera_json(&p).unwrap(), cam);
    let good = std::fs::read_to_string(&p).unwrap();

    let check = |text: &str, what: &str| {
        std::fs::write(&p, text).unwrap();
        let msg = load_camera_json(&p).unwrap_err().to_string();
        assert!(
            msg.contains(&*p.to_string_lossy()) && msg.contains(what),
            "{msg}"
        );
    };
    check(&good.replace("535.4", "0.0"), "fx");
    check(&good.replace("539.2", "NaN"), "line");
    check(&good.replace("\"cy\"", "\"cyy\""), "cy");
    check("{", "EOF");
    let msg = load_camera_json(tmp.path().join("nothere.json"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("nothere.json"), "{msg}");

    // Through Sequence::open as well.
    let seq_dir = tmp.path().join("seq");
    make_tum(&seq_dir);
    let cj = seq_dir.join("camera.json");
    let text = std::fs::read_to_string(&cj).unwrap();
    std::fs::write(&cj, text.replace("\"fx\": 50.0", "\"fx\": 0.0")).unwrap();
    let msg = open_err(&seq_dir);
    assert!(
        msg.contains(&*cj.to_string_lossy()) && msg.contains("fx"),
        "{msg}"
    );
}
