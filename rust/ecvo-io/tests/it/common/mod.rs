//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh folder under the system temp dir, removed on drop.
pub struct TempDir(PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let p = std::env::temp_dir().join(format!("ecvo-io-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A small test camera.
pub fn small_camera(width: usize, height: usize) -> ecvo_io::Camera {
    ecvo_io::Camera {
        width,
        height,
        fx: 50.0,
        fy: 50.0,
        cx: (width as f64 - 1.0) / 2.0,
        cy: (height as f64 - 1.0) / 2.0,
        depth_scale: 5000.0,
    }
}

/// Deterministic pseudo-random test images covering the full value ranges.
pub fn test_images(width: usize, height: usize, seed: u64) -> (Vec<u8>, Vec<u16>) {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 33) as u32
    };
    let n = width * height;
    let intensity = (0..n).map(|_| next() as u8).collect();
    let depth = (0..n)
        .map(|k| match k % 7 {
            0 => 0,
            1 => u16::MAX,
            _ => next() as u16,
        })
        .collect();
    (intensity, depth)
}

/// Writes a PNG with the `image` crate in any layout (to make bad inputs).
pub fn write_raw_png(path: &Path, bytes: &[u8], w: u32, h: u32, ct: image::ExtendedColorType) {
    image::save_buffer_with_format(path, bytes, w, h, ct, image::ImageFormat::Png).unwrap();
}
