//! Renders a few frames of the phone preset, prints timings and statistics and writes
//! grayscale PNG previews (intensity, noisy depth) to a directory (default `/tmp`).
//!
//! `cargo run --release -p ecvo-synth --example preview [-- OUT_DIR]`

use std::time::Instant;

use ecvo_synth::{SynthSequence, apply_noise, render};

/// CRC-32 (IEEE) of a byte string.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in data {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Minimal 8-bit grayscale PNG encoder (zlib stream made of stored deflate blocks).
fn png_gray(width: usize, height: usize, pixels: &[u8]) -> Vec<u8> {
    let mut raw = Vec::with_capacity((width + 1) * height);
    for row in pixels.chunks(width) {
        raw.push(0); // filter: none
        raw.extend_from_slice(row);
    }
    let mut z = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = raw.chunks(65_535).collect();
    for (i, block) in blocks.iter().enumerate() {
        z.push(u8::from(i + 1 == blocks.len()));
        let len = block.len() as u16;
        z.extend_from_slice(&len.to_le_bytes());
        z.extend_from_slice(&(!len).to_le_bytes());
        z.extend_from_slice(block);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &x in &raw {
        a = (a + x as u32) % 65_521;
        b = (b + a) % 65_521;
    }
    z.extend_from_slice(&((b << 16) | a).to_be_bytes());
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut c = kind.to_vec();
        c.extend_from_slice(data);
        out.extend_from_slice(&c);
        out.extend_from_slice(&crc32(&c).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&(width as u32).to_be_bytes());
    ihdr.extend_from_slice(&(height as u32).to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &z);
    chunk(b"IEND", &[]);
    out
}

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "/tmp".into());
    let seq = SynthSequence::phone_320x180(300, 1);
    let cam = seq.camera;
    for i in [0usize, 100, 200, 299] {
        let pose = seq.pose(i);
        let t0 = Instant::now();
        let r = render(&seq.scene, &cam, &pose);
        let t_render = t0.elapsed();
        let t1 = Instant::now();
        let (gray, depth) = apply_noise(&r, &cam, &seq.noise, seq.frame_seed(i));
        let t_noise = t1.elapsed();
        let valid = depth.iter().filter(|&&d| d > 0).count() as f64 / depth.len() as f64;
        let (zmin, zmax) = r
            .depth_m
            .iter()
            .fold((f32::MAX, 0.0f32), |(a, b), &z| (a.min(z), b.max(z)));
        println!(
            "frame {i}: render {:.1} ms, noise {:.1} ms, valid depth {:.1} %, clean depth {zmin:.2}..{zmax:.2} m, pos {:?}",
            t_render.as_secs_f64() * 1e3,
            t_noise.as_secs_f64() * 1e3,
            valid * 100.0,
            pose.translation.vector.as_slice()
        );
        let depth8: Vec<u8> = depth
            .iter()
            .map(|&d| {
                if d == 0 {
                    0
                } else {
                    (255.0 - d as f64 / 6000.0 * 240.0) as u8
                }
            })
            .collect();
        std::fs::write(
            format!("{dir}/ecvo-synth-{i}-gray.png"),
            png_gray(cam.width, cam.height, &gray),
        )
        .unwrap();
        std::fs::write(
            format!("{dir}/ecvo-synth-{i}-depth.png"),
            png_gray(cam.width, cam.height, &depth8),
        )
        .unwrap();
    }
}
