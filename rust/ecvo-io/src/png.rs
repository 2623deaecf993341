//! Reading and writing the PNGs of RGB-D sequences: 8-bit intensity (gray, or RGB /
//! RGBA converted to gray) and 16-bit gray depth.

use std::cell::RefCell;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Cursor, Seek, Write};
use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};

use crate::error::{Error, Result};
use crate::files::open_regular;

thread_local! {
    /// Per-thread scratch bytes for colour and 16-bit decoding, so that decoding into
    /// reused frame buffers does not allocate.
    static SCRATCH: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// What the PNG decoder may allocate besides the frame itself (which is sized from
/// the camera, checked against the header first): the chunks it keeps (palette,
/// transparency, `eXIf`) and its row buffers. Colour profiles (`iCCP`) and text
/// chunks (`tEXt`, `zTXt`, `iTXt`) are never inflated, so a compressed bomb in them
/// costs nothing.
pub const MAX_PNG_CHUNK_BYTES: usize = 1 << 20;

/// Largest PNG file read for a `width` x `height` frame: 16 MiB plus 10 bytes a pixel
/// (an uncompressed 16-bit RGBA frame with its filter bytes fits), so that a file
/// padded with gigabytes of skipped chunks is refused instead of read through.
pub fn max_png_file_bytes(width: usize, height: usize) -> u64 {
    (16u64 << 20).saturating_add(
        (width as u64)
            .saturating_mul(height as u64)
            .saturating_mul(10),
    )
}

type Reader<R> = png::Reader<R>;

fn describe(ct: png::ColorType, bits: png::BitDepth) -> String {
    let bits = match bits {
        png::BitDepth::One => 1,
        png::BitDepth::Two => 2,
        png::BitDepth::Four => 4,
        png::BitDepth::Eight => 8,
        png::BitDepth::Sixteen => 16,
    };
    let what = match ct {
        png::ColorType::Grayscale => "gray",
        png::ColorType::GrayscaleAlpha => "gray with alpha",
        png::ColorType::Rgb => "RGB",
        png::ColorType::Rgba => "RGBA",
        png::ColorType::Indexed => "indexed colour",
    };
    format!("{bits}-bit {what}")
}

fn decode_err(path: &Path, e: png::DecodingError) -> Error {
    match e {
        png::DecodingError::LimitsExceeded => Error::image(
            path,
            format!(
                "cannot decode PNG: it needs more than the decoder's limit of \
                 {MAX_PNG_CHUNK_BYTES} bytes besides the frame (an oversized chunk?)"
            ),
        ),
        e => Error::image(path, format!("cannot decode PNG: {e}")),
    }
}

/// A decoder with the limits above, not yet past the header.
fn decoder<R: BufRead + Seek>(reader: R, width_hint: usize) -> png::Decoder<R> {
    // Two rows of the widest sample layout (16-bit RGBA plus the filter byte) for the
    // row buffers, on top of the chunk allowance.
    let rows = 2usize.saturating_mul(width_hint.saturating_mul(8).saturating_add(1));
    let mut dec = png::Decoder::new_with_limits(
        reader,
        png::Limits {
            bytes: MAX_PNG_CHUNK_BYTES.saturating_add(rows),
        },
    );
    dec.set_ignore_iccp_chunk(true);
    dec.set_ignore_text_chunk(true);
    dec.set_transformations(png::Transformations::EXPAND);
    dec
}

fn open_file(path: &Path, limit: u64) -> Result<BufReader<File>> {
    Ok(BufReader::new(open_regular(path, limit)?))
}

/// Width and height from the header, without reading further.
fn header_size<R: BufRead + Seek>(reader: R, path: &Path) -> Result<(usize, usize)> {
    let mut dec = decoder(reader, 0);
    let info = dec.read_header_info().map_err(|e| decode_err(path, e))?;
    Ok((info.width as usize, info.height as usize))
}

/// Checks the header's size against the camera's, then reads up to the image data.
fn start<R: BufRead + Seek>(reader: R, path: &Path, w: usize, h: usize) -> Result<Reader<R>> {
    let mut dec = decoder(reader, w);
    let info = dec.read_header_info().map_err(|e| decode_err(path, e))?;
    let (fw, fh) = (info.width as usize, info.height as usize);
    if (fw, fh) != (w, h) {
        return Err(Error::ImageSize {
            path: path.to_path_buf(),
            width: fw,
            height: fh,
            expected_width: w,
            expected_height: h,
        });
    }
    dec.read_info().map_err(|e| decode_err(path, e))
}

/// Width and height of a PNG, from its header only.
pub fn png_size(path: impl AsRef<Path>) -> Result<(usize, usize)> {
    let path = path.as_ref();
    header_size(open_file(path, u64::MAX)?, path)
}

/// Width and height of a PNG held in memory, from its header only; `path` is only
/// used in error messages.
pub fn png_size_of(bytes: &[u8], path: &Path) -> Result<(usize, usize)> {
    header_size(Cursor::new(bytes), path)
}

/// Gray value of an RGB pixel: `0.299 R + 0.587 G + 0.114 B`, rounded to nearest
/// (ties up), computed exactly in integers.
#[inline]
pub fn rgb_to_gray(r: u8, g: u8, b: u8) -> u8 {
    ((299 * r as u32 + 587 * g as u32 + 114 * b as u32 + 500) / 1000) as u8
}

/// Decodes an intensity PNG of exactly `width` x `height` into `out` (resized,
/// allocation reused). 8-bit gray is copied; 8-bit RGB/RGBA is converted with
/// [`rgb_to_gray`] (8-bit gray+alpha keeps the gray; palettes and gray below 8 bits
/// are expanded first); anything else is an error naming the file.
///
/// The file must be a regular file of at most [`max_png_file_bytes`]; the decoder
/// allocates the frame (sized from `width` x `height`, checked against the header
/// before) and at most [`MAX_PNG_CHUNK_BYTES`] more.
pub fn read_intensity_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    out: &mut Vec<u8>,
) -> Result<()> {
    let path = path.as_ref();
    let file = open_file(path, max_png_file_bytes(width, height))?;
    intensity_from(start(file, path, width, height)?, path, width, height, out)
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
    let reader = start(Cursor::new(bytes), path, width, height)?;
    intensity_from(reader, path, width, height, out)
}

/// Decodes the frame into `buf` (resized to the decoder's output size, which the
/// caller has checked).
fn frame_into<R: BufRead + Seek>(
    reader: &mut Reader<R>,
    path: &Path,
    expected: usize,
    buf: &mut Vec<u8>,
) -> Result<()> {
    let size = reader.output_buffer_size();
    if size != Some(expected) {
        return Err(Error::image(
            path,
            format!("cannot decode PNG: unexpected output size {size:?}, expected {expected}"),
        ));
    }
    buf.resize(expected, 0);
    reader.next_frame(buf).map_err(|e| decode_err(path, e))?;
    Ok(())
}

fn intensity_from<R: BufRead + Seek>(
    mut reader: Reader<R>,
    path: &Path,
    width: usize,
    height: usize,
    out: &mut Vec<u8>,
) -> Result<()> {
    let n = width * height;
    let (ct, bits) = reader.output_color_type();
    if bits != png::BitDepth::Eight {
        return Err(Error::image(
            path,
            format!(
                "intensity PNG is {}; expected 8-bit gray, RGB or RGBA",
                describe(ct, bits)
            ),
        ));
    }
    match ct {
        png::ColorType::Grayscale => frame_into(&mut reader, path, n, out),
        png::ColorType::GrayscaleAlpha | png::ColorType::Rgb | png::ColorType::Rgba => SCRATCH
            .with(|s| {
                let mut s = s.borrow_mut();
                let ch = ct.samples();
                frame_into(&mut reader, path, n * ch, &mut s)?;
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
                describe(other, bits)
            ),
        )),
    }
}

/// Reads an 8-bit intensity PNG as colour: `width * height * 3` RGB bytes into `out`
/// (resized, allocation reused); gray is replicated to the three channels, alpha
/// dropped. The same files and limits as [`read_intensity_png`], whose gray is
/// [`rgb_to_gray`] of these channels.
pub fn read_colour_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    out: &mut Vec<u8>,
) -> Result<()> {
    let path = path.as_ref();
    let file = open_file(path, max_png_file_bytes(width, height))?;
    let mut reader = start(file, path, width, height)?;
    let n = width * height;
    let (ct, bits) = reader.output_color_type();
    let unsupported = || {
        Error::image(
            path,
            format!(
                "intensity PNG is {}; expected 8-bit gray, RGB or RGBA",
                describe(ct, bits)
            ),
        )
    };
    if bits != png::BitDepth::Eight {
        return Err(unsupported());
    }
    match ct {
        png::ColorType::Rgb => frame_into(&mut reader, path, n * 3, out),
        png::ColorType::Grayscale | png::ColorType::GrayscaleAlpha | png::ColorType::Rgba => {
            let ch = ct.samples();
            let mut s = Vec::new();
            frame_into(&mut reader, path, n * ch, &mut s)?;
            out.clear();
            out.reserve(n * 3);
            for p in s.chunks_exact(ch) {
                if ch <= 2 {
                    out.extend_from_slice(&[p[0], p[0], p[0]]);
                } else {
                    out.extend_from_slice(&p[..3]);
                }
            }
            Ok(())
        }
        _ => Err(unsupported()),
    }
}

/// Decodes a depth PNG, which must be 16-bit gray of exactly `width` x `height`,
/// into `out` (resized, allocation reused); anything else is an error naming the file.
/// The file and memory limits are those of [`read_intensity_png`].
pub fn read_depth_png(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    out: &mut Vec<u16>,
) -> Result<()> {
    let path = path.as_ref();
    let file = open_file(path, max_png_file_bytes(width, height))?;
    depth_from(start(file, path, width, height)?, path, width, height, out)
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
    let reader = start(Cursor::new(bytes), path, width, height)?;
    depth_from(reader, path, width, height, out)
}

fn depth_from<R: BufRead + Seek>(
    mut reader: Reader<R>,
    path: &Path,
    width: usize,
    height: usize,
    out: &mut Vec<u16>,
) -> Result<()> {
    let (ct, bits) = reader.output_color_type();
    if (ct, bits) != (png::ColorType::Grayscale, png::BitDepth::Sixteen) {
        return Err(Error::image(
            path,
            format!("depth PNG is {}; expected 16-bit gray", describe(ct, bits)),
        ));
    }
    let n = width * height;
    SCRATCH.with(|s| {
        let mut s = s.borrow_mut();
        frame_into(&mut reader, path, 2 * n, &mut s)?;
        out.clear();
        // PNG samples are big-endian.
        out.extend(s.chunks_exact(2).map(|b| u16::from_be_bytes([b[0], b[1]])));
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
