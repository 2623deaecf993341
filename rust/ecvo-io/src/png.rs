//! Reading and writing the PNGs of RGB-D sequences: 8-bit intensity (gray, or RGB /
//! RGBA converted to gray) and 16-bit gray depth.

use std::cell::RefCell;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Cursor, Seek, Write};
use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngDecoder, PngEncoder};
use image::{ColorType, ExtendedColorType, ImageDecoder, ImageEncoder};

use crate::error::{Error, Result};

thread_local! {
    /// Per-thread scratch bytes for colour and 16-bit decoding, so that decoding into
    /// reused frame buffers does not allocate.
    static SCRATCH: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

fn describe(c: ColorType) -> &'static str {
    match c {
        ColorType::L8 => "8-bit gray",
        ColorType::La8 => "8-bit gray with alpha",
        ColorType::Rgb8 => "8-bit RGB",
        ColorType::Rgba8 => "8-bit RGBA",
        ColorType::L16 => "16-bit gray",
        ColorType::La16 => "16-bit gray with alpha",
        ColorType::Rgb16 => "16-bit RGB",
        ColorType::Rgba16 => "16-bit RGBA",
        _ => "an unsupported colour type",
    }
}

fn open(path: &Path) -> Result<PngDecoder<BufReader<File>>> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    decoder(BufReader::new(file), path)
}

fn decoder<R: BufRead + Seek>(reader: R, path: &Path) -> Result<PngDecoder<R>> {
    PngDecoder::new(reader).map_err(|e| Error::image(path, format!("cannot decode PNG: {e}")))
}

fn check_size<R: BufRead + Seek>(
    path: &Path,
    dec: &PngDecoder<R>,
    w: usize,
    h: usize,
) -> Result<()> {
    let (fw, fh) = dec.dimensions();
    if (fw as usize, fh as usize) != (w, h) {
        return Err(Error::ImageSize {
            path: path.to_path_buf(),
            width: fw as usize,
            height: fh as usize,
            expected_width: w,
            expected_height: h,
        });
    }
    Ok(())
}

/// Width and height of a PNG, from its header only.
pub fn png_size(path: impl AsRef<Path>) -> Result<(usize, usize)> {
    let path = path.as_ref();
    let (w, h) = open(path)?.dimensions();
    Ok((w as usize, h as usize))
}

/// Width and height of a PNG held in memory, from its header only; `path` is only
/// used in error messages.
pub fn png_size_of(bytes: &[u8], path: &Path) -> Result<(usize, usize)> {
    let (w, h) = decoder(Cursor::new(bytes), path)?.dimensions();
    Ok((w as usize, h as usize))
}

/// Gray value of an RGB pixel: `0.299 R + 0.587 G + 0.114 B`, rounded to nearest
/// (ties up), computed exactly in integers.
#[inline]
pub fn rgb_to_gray(r: u8, g: u8, b: u8) -> u8 {
    ((299 * r as u32 + 587 * g as u32 + 114 * b as u32 + 500) / 1000) as u8
}

/// Decodes an intensity PNG of exactly `width` x `height` into `out` (resized,
/// allocation reused). 8-bit gray is copied; 8-bit RGB/RGBA is converted with
/// [`rgb_to_gray`] (8-bit gray+alpha keeps the gray); anything else is an error
/// naming the file.
pub fn read_intensity_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    out: &mut Vec<u8>,
) -> Result<()> {
    let path = path.as_ref();
    intensity_from(open(path)?, path, width, height, out)
}

/// [`read_intensity_png`] on the bytes of a PNG file held in memory; `path` is only
/// used in error messages.
pub fn decode_intensity_png(
    bytes: &[u8],
    path: &Path,
    width: usize,
    height: usize,
    out: &mut Vec<u8>,
) -> Result<()> {
    intensity_from(decoder(Cursor::new(bytes), path)?, path, width, height, out)
}

fn intensity_from<R: BufRead + Seek>(
    dec: PngDecoder<R>,
    path: &Path,
    width: usize,
    height: usize,
    out: &mut Vec<u8>,
) -> Result<()> {
    check_size(path, &dec, width, height)?;
    let n = width * height;
    let ct = dec.color_type();
    let decode_err = |e: image::ImageError| Error::image(path, format!("cannot decode PNG: {e}"));
    match ct {
        ColorType::L8 => {
            out.resize(n, 0);
            dec.read_image(out).map_err(decode_err)
        }
        ColorType::La8 | ColorType::Rgb8 | ColorType::Rgba8 => SCRATCH.with(|s| {
            let mut s = s.borrow_mut();
            let ch = ct.channel_count() as usize;
            s.resize(n * ch, 0);
            dec.read_image(&mut s).map_err(decode_err)?;
            out.clear();
            if ch == 2 {
                out.extend(s.chunks_exact(2).map(|p| p[0]));
            } else {
                out.extend(s.chunks_exact(ch).map(|p| rgb_to_gray(p[0], p[1], p[2])));
            }
            Ok(())
        }),
        other => Err(Error::image(
            path,
            format!(
                "intensity PNG is {}; expected 8-bit gray, RGB or RGBA",
                describe(other)
            ),
        )),
    }
}

/// Decodes a depth PNG, which must be 16-bit gray of exactly `width` x `height`,
/// into `out` (resized, allocation reused); anything else is an error naming the file.
pub fn read_depth_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    out: &mut Vec<u16>,
) -> Result<()> {
    let path = path.as_ref();
    depth_from(open(path)?, path, width, height, out)
}

/// [`read_depth_png`] on the bytes of a PNG file held in memory; `path` is only used
/// in error messages.
pub fn decode_depth_png(
    bytes: &[u8],
    path: &Path,
    width: usize,
    height: usize,
    out: &mut Vec<u16>,
) -> Result<()> {
    depth_from(decoder(Cursor::new(bytes), path)?, path, width, height, out)
}

fn depth_from<R: BufRead + Seek>(
    dec: PngDecoder<R>,
    path: &Path,
    width: usize,
    height: usize,
    out: &mut Vec<u16>,
) -> Result<()> {
    check_size(path, &dec, width, height)?;
    let ct = dec.color_type();
    if ct != ColorType::L16 {
        return Err(Error::image(
            path,
            format!("depth PNG is {}; expected 16-bit gray", describe(ct)),
        ));
    }
    let n = width * height;
    SCRATCH.with(|s| {
        let mut s = s.borrow_mut();
        s.resize(2 * n, 0);
        dec.read_image(&mut s)
            .map_err(|e| Error::image(path, format!("cannot decode PNG: {e}")))?;
        out.clear();
        // The decoder hands out native-endian samples.
        out.extend(s.chunks_exact(2).map(|b| u16::from_ne_bytes([b[0], b[1]])));
        Ok(())
    })
}

fn write_png(
    path: &Path,
    bytes: &[u8],
    width: usize,
    height: usize,
    ct: ExtendedColorType,
) -> Result<()> {
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => {
            return Err(Error::image(
                path,
                format!("{width}x{height} is too large for a PNG"),
            ));
        }
    };
    let file = File::create(path).map_err(|e| Error::io(path, e))?;
    let mut writer = BufWriter::new(file);
    PngEncoder::new_with_quality(&mut writer, CompressionType::Fast, FilterType::Adaptive)
        .write_image(bytes, w, h, ct)
        .map_err(|e| Error::image(path, format!("cannot encode PNG: {e}")))?;
    writer.flush().map_err(|e| Error::io(path, e))
}

fn check_len(path: &Path, what: &str, len: usize, width: usize, height: usize) -> Result<()> {
    if len != width * height {
        return Err(Error::InvalidInput(format!(
            "{}: {what} has {len} values, expected {} ({width}x{height})",
            path.display(),
            width * height
        )));
    }
    Ok(())
}

/// Writes `intensity` (`width * height`, row-major) as an 8-bit gray PNG.
pub fn write_intensity_png(
    path: impl AsRef<Path>,
    intensity: &[u8],
    width: usize,
    height: usize,
) -> Result<()> {
    let path = path.as_ref();
    check_len(path, "intensity", intensity.len(), width, height)?;
    write_png(path, intensity, width, height, ExtendedColorType::L8)
}

/// Writes `depth` (`width * height`, row-major) as a 16-bit gray PNG.
pub fn write_depth_png(
    path: impl AsRef<Path>,
    depth: &[u16],
    width: usize,
    height: usize,
) -> Result<()> {
    let path = path.as_ref();
    check_len(path, "depth", depth.len(), width, height)?;
    let bytes: Vec<u8> = depth.iter().flat_map(|d| d.to_ne_bytes()).collect();
    write_png(path, &bytes, width, height, ExtendedColorType::L16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gray_conversion_rounds() {
        assert_eq!(rgb_to_gray(0, 0, 0), 0);
        assert_eq!(rgb_to_gray(255, 255, 255), 255);
        assert_eq!(rgb_to_gray(255, 0, 0), 76); // 76.245
        assert_eq!(rgb_to_gray(0, 255, 0), 150); // 149.685
        assert_eq!(rgb_to_gray(0, 0, 255), 29); // 29.07
        assert_eq!(rgb_to_gray(10, 20, 30), 18); // 2.99 + 11.74 + 3.42 = 18.15
    }
}
