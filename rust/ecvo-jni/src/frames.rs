//! Frames from Java: direct buffers (packed or with padded rows) and primitive arrays.

use jni::Env;
use jni::objects::JByteBuffer;

use crate::error::{Failure, bad};

/// Where a `width x height` plane's rows lie in a buffer: row `y` starts at byte
/// `y * row_stride` and holds `width * bytes_per_pixel` bytes (pixels packed within a
/// row, as the Y plane of `YUV_420_888` and `DEPTH16` planes are).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlaneLayout {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Bytes per pixel: 2 for depth, 1 for intensity.
    pub bytes_per_pixel: usize,
    /// Bytes from the start of one row to the next, at least a row's bytes.
    pub row_stride: usize,
}

impl PlaneLayout {
    /// A plane without padding.
    pub fn packed(width: usize, height: usize, bytes_per_pixel: usize) -> PlaneLayout {
        PlaneLayout {
            width,
            height,
            bytes_per_pixel,
            row_stride: width * bytes_per_pixel,
        }
    }

    /// Bytes in one row's pixels.
    pub fn row_bytes(&self) -> usize {
        self.width * self.bytes_per_pixel
    }

    /// The smallest buffer holding the plane: the last row need not be padded (Android's
    /// `Image` planes end right after the last row's pixels).
    pub fn min_len(&self) -> usize {
        if self.height == 0 {
            0
        } else {
            (self.height - 1) * self.row_stride + self.row_bytes()
        }
    }

    /// Checks the stride against the row and a buffer of `len` bytes; the error names
    /// the buffer `name`.
    pub fn check(&self, name: &str, len: usize) -> Result<(), Failure> {
        if self.row_stride < self.row_bytes() {
            return Err(bad(format!(
                "{name}: row stride {} is less than a row of {} bytes",
                self.row_stride,
                self.row_bytes()
            )));
        }
        if len < self.min_len() {
            return Err(bad(format!(
                "{name}: buffer holds {len} bytes, the frame needs {} (row stride {})",
                self.min_len(),
                self.row_stride
            )));
        }
        Ok(())
    }
}

/// Copies the rows of a plane laid out as `layout` in `src` into `dst`, packed
/// (`dst.len()` must be `width * height * bytes_per_pixel`; `layout.check` first).
pub fn copy_plane(src: &[u8], layout: PlaneLayout, dst: &mut [u8]) {
    let row = layout.row_bytes();
    if row == 0 {
        return;
    }
    for (y, out) in dst.chunks_exact_mut(row).enumerate().take(layout.height) {
        let start = y * layout.row_stride;
        out.copy_from_slice(&src[start..start + row]);
    }
}

/// The bytes of a direct buffer, checked against `layout`.
///
/// The slice borrows memory the JVM owns: the caller must not keep it past the native
/// call, during which the local reference `buf` keeps the buffer alive.
pub fn direct<'b>(
    env: &Env<'_>,
    buf: &'b JByteBuffer<'_>,
    name: &str,
    layout: PlaneLayout,
) -> Result<&'b [u8], Failure> {
    if buf.is_null() {
        return Err(bad(format!("{name}: buffer is null")));
    }
    let cap = env
        .get_direct_buffer_capacity(buf)
        .map_err(|_| bad(format!("{name}: buffer is not direct")))?;
    let ptr = env
        .get_direct_buffer_address(buf)
        .map_err(|_| bad(format!("{name}: buffer is not direct")))?;
    if ptr.is_null() {
        return Err(bad(format!("{name}: buffer is not direct")));
    }
    layout.check(name, cap)?;
    // SAFETY: `ptr` is the address of a direct buffer of `cap` bytes (JNI's
    // GetDirectBufferAddress/Capacity), which the local reference `buf` keeps alive for
    // the rest of this native call; the slice borrows `buf`, so it cannot outlive it.
    // Java code may write the buffer concurrently (an `Image` plane is only recycled
    // after `Image.close()`, which the caller does after the push returns); we only read
    // bytes, so a concurrent write gives wrong pixels, never undefined memory access.
    Ok(unsafe { std::slice::from_raw_parts(ptr, cap) })
}

/// Checks a Java array's length against the frame's.
pub fn array_len(len: jni::errors::Result<usize>, name: &str, need: usize) -> Result<(), Failure> {
    let len = len.map_err(|_| bad(format!("{name}: array is null")))?;
    if len != need {
        return Err(bad(format!(
            "{name}: array has {len} values, the frame needs {need}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn padded_rows_are_packed() {
        // 3x2 depth (2 bytes per pixel) with rows 8 bytes apart; the last row unpadded.
        let layout = PlaneLayout {
            width: 3,
            height: 2,
            bytes_per_pixel: 2,
            row_stride: 8,
        };
        let src = [1, 2, 3, 4, 5, 6, 0xEE, 0xEE, 7, 8, 9, 10, 11, 12];
        assert_eq!(layout.min_len(), 14);
        assert!(layout.check("depth", src.len()).is_ok());
        let mut dst = [0u8; 12];
        copy_plane(&src, layout, &mut dst);
        assert_eq!(dst, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]);
    }

    #[test]
    fn bad_strides_and_short_buffers_name_the_buffer() {
        let short = PlaneLayout {
            width: 4,
            height: 2,
            bytes_per_pixel: 1,
            row_stride: 3,
        };
        match short.check("intensity", 100) {
            Err(Failure::IllegalArgument(m)) => {
                assert!(m.contains("intensity") && m.contains("row stride 3"), "{m}")
            }
            other => panic!("{other:?}"),
        }
        let padded = PlaneLayout {
            row_stride: 16,
            ..short
        };
        assert!(padded.check("intensity", 20).is_ok());
        match padded.check("intensity", 19) {
            Err(Failure::IllegalArgument(m)) => assert!(m.contains("needs 20"), "{m}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(PlaneLayout::packed(4, 2, 2).min_len(), 16);
    }
}
