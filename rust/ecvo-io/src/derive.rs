//! Derived copies of a TUM-layout sequence, made the way the project's shared datasets
//! were (`../shared/datasets/README.md`): the first N colour/depth pairs, colour turned
//! into 8-bit gray, and the half-resolution copy. `scripts/datasets/get-tum.sh` runs
//! them through `cargo run -p ecvo-io --example derive`.
//!
//! Half resolution, per 2x2 block of the full-resolution images:
//! - gray: the mean of the four pixels' `0.299 R + 0.587 G + 0.114 B` (unrounded),
//!   rounded to nearest, ties to even;
//! - depth: the mean of the four raw depths (rounded the same way) when all four are
//!   valid (non-zero) and agree within 3 % (largest ≤ 1.03 × smallest), else 0;
//! - intrinsics: f / 2 and (c + 0.5) / 2 - 0.5 ([`Camera::half`]).

use std::fs;
use std::path::Path;

use ecvo_core::Camera;

use crate::camera::{load_camera_json, save_camera_json};
use crate::error::{Error, Result};
use crate::list::associate_stamps;
use crate::png::{read_depth_png, read_intensity_png, write_depth_png, write_intensity_png};
use crate::sequence::MAX_RGB_DEPTH_DT;

/// What [`derive_sequence`] makes.
#[derive(Clone, Copy, Debug, Default)]
pub struct DeriveOptions {
    /// Only the first N colour/depth pairs (nearest timestamps within 0.02 s); all
    /// listed images otherwise, paired or not.
    pub first_pairs: Option<usize>,
    /// Only the first N entries of each list (`tum_fr1_xyz_full300` is the first 300
    /// of fr1/xyz's: 294 pairs).
    pub first_entries: Option<usize>,
    /// Colour images written as 8-bit gray (`0.299 R + 0.587 G + 0.114 B`, rounded);
    /// otherwise copied as they are (unless `half`).
    pub gray: bool,
    /// The half-resolution copy (gray, see the module's text).
    pub half: bool,
}

/// What [`derive_sequence`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeriveReport {
    /// Colour (or gray) images written.
    pub rgb: usize,
    /// Depth images written.
    pub depth: usize,
    /// Image size written.
    pub width: usize,
    /// Image size written.
    pub height: usize,
}

/// `n / d` rounded to nearest, ties to even (as numpy's `round`, with which the shared
/// half-resolution sets were made).
fn div_round_even(n: u32, d: u32) -> u32 {
    let (q, r) = (n / d, n % d);
    if 2 * r > d || (2 * r == d && q % 2 == 1) {
        q + 1
    } else {
        q
    }
}

/// The gray image at half resolution from a colour (or gray) image of `width` x
/// `height` RGB pixels: the mean of each 2x2 block of `0.299 R + 0.587 G + 0.114 B`,
/// unrounded, then rounded to nearest (ties to even). An odd last row or column is left
/// out.
pub fn half_gray(rgb: &[u8], width: usize, height: usize) -> Vec<u8> {
    let milli = |i: usize| {
        299 * rgb[3 * i] as u32 + 587 * rgb[3 * i + 1] as u32 + 114 * rgb[3 * i + 2] as u32
    };
    let (w2, h2) = (width / 2, height / 2);
    let mut out = Vec::with_capacity(w2 * h2);
    for y in 0..h2 {
        let (r0, r1) = (2 * y * width, (2 * y + 1) * width);
        for x in 0..w2 {
            let sum = milli(r0 + 2 * x)
                + milli(r0 + 2 * x + 1)
                + milli(r1 + 2 * x)
                + milli(r1 + 2 * x + 1);
            out.push(div_round_even(sum, 4000) as u8);
        }
    }
    out
}

/// The depth image at half resolution: a block's mean (rounded to nearest, ties to
/// even) when its four values are valid (non-zero) and the largest is at most 1.03
/// times the smallest, else 0 (no measurement).
pub fn half_depth(src: &[u16], width: usize, height: usize) -> Vec<u16> {
    let (w2, h2) = (width / 2, height / 2);
    let mut out = Vec::with_capacity(w2 * h2);
    for y in 0..h2 {
        let (r0, r1) = (&src[2 * y * width..], &src[(2 * y + 1) * width..]);
        for x in 0..w2 {
            let v = [r0[2 * x], r0[2 * x + 1], r1[2 * x], r1[2 * x + 1]].map(u32::from);
            let (lo, hi) = (*v.iter().min().unwrap(), *v.iter().max().unwrap());
            // hi <= 1.03 lo, exactly in integers.
            let d = if lo > 0 && 100 * hi <= 103 * lo {
                div_round_even(v.iter().sum::<u32>(), 4)
            } else {
                0
            };
            out.push(d as u16);
        }
    }
    out
}

/// The RGB pixels of a colour or gray PNG of `width` x `height` (gray repeated).
fn read_rgb(path: &Path, width: usize, height: usize) -> Result<Vec<u8>> {
    let bad = |why: String| Error::InvalidInput(format!("{}: {why}", path.display()));
    let img = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?
        .decode()
        .map_err(|e| bad(e.to_string()))?;
    if (img.width() as usize, img.height() as usize) != (width, height) {
        return Err(bad(format!(
            "{}x{}, not {width}x{height}",
            img.width(),
            img.height()
        )));
    }
    Ok(img.to_rgb8().into_raw())
}

/// One data line of a list: its text as written, timestamp and file.
struct Line {
    text: String,
    timestamp: f64,
    file: String,
}

fn read_list(path: &Path) -> Result<(Vec<String>, Vec<Line>)> {
    let text = crate::list::read_text(path)?;
    let mut comments = Vec::new();
    let mut lines = Vec::new();
    for (k, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.is_empty() || t.starts_with('#') {
            if lines.is_empty() {
                comments.push(l.to_string());
            }
            continue;
        }
        let mut f = t.split_whitespace();
        let (Some(ts), Some(file), None) = (f.next(), f.next(), f.next()) else {
            return Err(Error::parse(path, k + 1, "expected `timestamp filename`"));
        };
        let timestamp = crate::list::parse_f64(path, k + 1, "timestamp", ts)?;
        if file.starts_with('/') || file.split('/').any(|c| c == "..") {
            return Err(Error::parse(path, k + 1, "the file is outside the folder"));
        }
        lines.push(Line {
            text: l.to_string(),
            timestamp,
            file: file.to_string(),
        });
    }
    Ok((comments, lines))
}

fn write_list(path: &Path, comments: &[String], lines: &[&Line]) -> Result<()> {
    let mut text = String::new();
    for l in comments {
        text += l;
        text.push('\n');
    }
    for l in lines {
        text += &l.text;
        text.push('\n');
    }
    fs::write(path, text).map_err(|e| Error::io(path, e))
}

fn create_parent(path: &Path) -> Result<()> {
    match path.parent() {
        Some(p) => fs::create_dir_all(p).map_err(|e| Error::io(p, e)),
        None => Ok(()),
    }
}

/// Writes the derived copy of the TUM-layout sequence `src` (with its `camera.json`)
/// to `dst`: `rgb.txt` and `depth.txt` (the kept lines as written), their images,
/// `groundtruth.txt` copied whole, and `camera.json` (halved with `half`).
pub fn derive_sequence(src: &Path, dst: &Path, opts: &DeriveOptions) -> Result<DeriveReport> {
    let camera: Camera = load_camera_json(src.join("camera.json"))?;
    let (rgb_comments, rgb) = read_list(&src.join("rgb.txt"))?;
    let (depth_comments, depth) = read_list(&src.join("depth.txt"))?;
    let (mut rgb_kept, mut depth_kept): (Vec<&Line>, Vec<&Line>) = match opts.first_pairs {
        Some(n) => {
            let stamps = |l: &[Line]| l.iter().map(|l| l.timestamp).collect::<Vec<_>>();
            let mut pairs = associate_stamps(&stamps(&rgb), &stamps(&depth), MAX_RGB_DEPTH_DT);
            pairs.sort_unstable();
            pairs.truncate(n);
            let mut d: Vec<usize> = pairs.iter().map(|p| p.1).collect();
            d.sort_unstable();
            (
                pairs.iter().map(|p| &rgb[p.0]).collect(),
                d.iter().map(|&j| &depth[j]).collect(),
            )
        }
        None => (rgb.iter().collect(), depth.iter().collect()),
    };
    if let Some(n) = opts.first_entries {
        rgb_kept.truncate(n);
        depth_kept.truncate(n);
    }
    fs::create_dir_all(dst).map_err(|e| Error::io(dst, e))?;
    let (w, h) = (camera.width, camera.height);
    let out_camera = if opts.half { camera.half() } else { camera };
    let mut gray = Vec::new();
    for l in &rgb_kept {
        let (from, to) = (src.join(&l.file), dst.join(&l.file));
        create_parent(&to)?;
        if opts.half {
            let rgb = read_rgb(&from, w, h)?;
            write_intensity_png(&to, &half_gray(&rgb, w, h), w / 2, h / 2)?;
        } else if opts.gray {
            read_intensity_png(&from, w, h, &mut gray)?;
            write_intensity_png(&to, &gray, w, h)?;
        } else {
            fs::copy(&from, &to).map_err(|e| Error::io(&from, e))?;
        }
    }
    let mut raw = Vec::new();
    for l in &depth_kept {
        let (from, to) = (src.join(&l.file), dst.join(&l.file));
        create_parent(&to)?;
        if opts.half {
            read_depth_png(&from, w, h, &mut raw)?;
            write_depth_png(&to, &half_depth(&raw, w, h), w / 2, h / 2)?;
        } else {
            fs::copy(&from, &to).map_err(|e| Error::io(&from, e))?;
        }
    }
    write_list(&dst.join("rgb.txt"), &rgb_comments, &rgb_kept)?;
    write_list(&dst.join("depth.txt"), &depth_comments, &depth_kept)?;
    let gt = src.join("groundtruth.txt");
    if gt.is_file() {
        let to = dst.join("groundtruth.txt");
        fs::copy(&gt, &to).map_err(|e| Error::io(&gt, e))?;
    }
    save_camera_json(dst.join("camera.json"), &out_camera)?;
    Ok(DeriveReport {
        rgb: rgb_kept.len(),
        depth: depth_kept.len(),
        width: out_camera.width,
        height: out_camera.height,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_gray_is_the_rounded_block_mean() {
        // Gray pixels (R = G = B) 1, 2, 3, 4: 2.5 -> 2 (ties to even); 10, 10, 10, 11:
        // 10.25 -> 10; 3, 4, 4, 4: 3.75 -> 4.
        let g = |v: &[u8]| v.iter().flat_map(|&p| [p, p, p]).collect::<Vec<u8>>();
        assert_eq!(
            half_gray(&g(&[1, 2, 10, 10, 3, 4, 10, 11]), 4, 2),
            vec![2, 10]
        );
        assert_eq!(half_gray(&g(&[3, 4, 4, 4]), 2, 2), vec![4]);
        // Colour: the unrounded gray is averaged. Pure red 255: 76.245 each.
        assert_eq!(half_gray(&[255, 0, 0].repeat(4), 2, 2), vec![76]);
        // An odd last column and row are left out.
        assert_eq!(half_gray(&g(&[5, 5, 9, 5, 5, 9, 9, 9, 9]), 3, 3), vec![5]);
    }

    #[test]
    fn half_depth_needs_four_valid_values_within_3_percent() {
        let block = |a: u16, b: u16, c: u16, d: u16| half_depth(&[a, b, c, d], 2, 2)[0];
        assert_eq!(block(5000, 5000, 5000, 5001), 5000); // 5000.25 -> 5000
        assert_eq!(block(5000, 5000, 5001, 5001), 5000); // 5000.5 -> 5000 (ties to even)
        assert_eq!(block(5001, 5001, 5002, 5002), 5002); // 5001.5 -> 5002 (ties to even)
        assert_eq!(block(5000, 5150, 5000, 5000), 5038); // 3.0 %: kept, 5037.5 -> 5038
        assert_eq!(block(5000, 5151, 5000, 5000), 0); // 3.02 %: not the same surface
        assert_eq!(block(0, 5000, 5000, 5000), 0); // one invalid pixel
        assert_eq!(block(65535, 65535, 65535, 65535), 65535); // no overflow
    }
}
