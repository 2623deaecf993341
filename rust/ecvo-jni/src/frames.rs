//! Frames from Java: direct buffers (packed or with padded rows) and primitive arrays.

use std::sync::OnceLock;

use jni::objects::{Global, JByteBuffer, JMethodID, JObject};
use jni::signature::{Primitive, ReturnType};
use jni::{Env, jni_sig, jni_str};

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

    /// Checks the stride against the row; the error names the buffer `name`.
    pub fn check_stride(&self, name: &str) -> Result<(), Failure> {
        if self.row_stride < self.row_bytes() {
            return Err(bad(format!(
                "{name}: row stride {} is less than a row of {} bytes",
                self.row_stride,
                self.row_bytes()
            )));
        }
        Ok(())
    }

    /// Checks the stride against the row and a buffer of `len` bytes; the error names
    /// the buffer `name`.
    pub fn check(&self, name: &str, len: usize) -> Result<(), Failure> {
        self.check_stride(name)?;
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

/// The method IDs and the `ByteOrder.LITTLE_ENDIAN` object [`direct`] needs, looked up
/// once per process (they stay valid: `java.nio` classes are never unloaded), so that a
/// push costs three plain method calls per buffer, not three lookups.
struct BufferIds {
    position: JMethodID,
    limit: JMethodID,
    order: JMethodID,
    little_endian: Global<JObject<'static>>,
}

static BUFFER_IDS: OnceLock<BufferIds> = OnceLock::new();

fn buffer_ids(env: &mut Env<'_>) -> Result<&'static BufferIds, Failure> {
    if let Some(ids) = BUFFER_IDS.get() {
        return Ok(ids);
    }
    let position = env.get_method_id(
        jni_str!("java/nio/Buffer"),
        jni_str!("position"),
        jni_sig!("()I"),
    )?;
    let limit = env.get_method_id(
        jni_str!("java/nio/Buffer"),
        jni_str!("limit"),
        jni_sig!("()I"),
    )?;
    let order = env.get_method_id(
        jni_str!("java/nio/ByteBuffer"),
        jni_str!("order"),
        jni_sig!("()Ljava/nio/ByteOrder;"),
    )?;
    let le = env
        .get_static_field(
            jni_str!("java/nio/ByteOrder"),
            jni_str!("LITTLE_ENDIAN"),
            jni_sig!("Ljava/nio/ByteOrder;"),
        )?
        .l()?;
    let little_endian = env.new_global_ref(&le)?;
    env.delete_local_ref(le);
    // Two threads may both look up; one set wins and the other's global is dropped
    // here, on an attached thread.
    Ok(BUFFER_IDS.get_or_init(|| BufferIds {
        position,
        limit,
        order,
        little_endian,
    }))
}

/// The frame bytes of a direct buffer: from its `position()` to its `limit()`,
/// checked against `layout` (bytes after the frame are ignored). A plane of more than
/// one byte per pixel (depth) is read little-endian, so a buffer whose `order()` is not
/// `LITTLE_ENDIAN` (`ByteBuffer.allocateDirect`'s default is big-endian) is refused:
/// its samples were most likely written big-endian by `putShort`. Android's `Image`
/// planes are in native order, little-endian on every Android ABI.
///
/// The slice borrows memory the JVM owns: the caller must not keep it past the native
/// call, during which the local reference `buf` keeps the buffer alive.
pub fn direct<'b>(
    env: &mut Env<'_>,
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
    let ids = buffer_ids(env)?;
    let int = ReturnType::Primitive(Primitive::Int);
    // SAFETY: `buf` is a non-null java.nio.ByteBuffer, and `position`/`limit` are the
    // IDs of java.nio.Buffer's `int position()` / `int limit()`, called without
    // arguments and read as the int they return.
    let (position, limit) = unsafe {
        (
            env.call_method_unchecked(buf, ids.position, int, &[])?
                .i()?,
            env.call_method_unchecked(buf, ids.limit, int, &[])?.i()?,
        )
    };
    let (position, limit) = match (usize::try_from(position), usize::try_from(limit)) {
        (Ok(p), Ok(l)) if p <= l && l <= cap => (p, l),
        _ => {
            return Err(bad(format!(
                "{name}: position {position} and limit {limit} do not lie in the buffer's {cap} bytes"
            )));
        }
    };
    layout.check_stride(name)?;
    if limit - position < layout.min_len() {
        return Err(bad(format!(
            "{name}: buffer holds {} bytes from position {position} to limit {limit}, the frame needs {} (row stride {}); after writing it with relative puts, call flip() or rewind()",
            limit - position,
            layout.min_len(),
            layout.row_stride
        )));
    }
    if layout.bytes_per_pixel > 1 {
        // SAFETY: `order` is the ID of java.nio.ByteBuffer's `ByteOrder order()`, called
        // on a ByteBuffer without arguments and read as the object it returns.
        let order = unsafe {
            env.call_method_unchecked(buf, ids.order, ReturnType::Object, &[])?
                .l()?
        };
        let little = env.is_same_object(&order, &ids.little_endian)?;
        env.delete_local_ref(order);
        if !little {
            return Err(bad(format!(
                "{name}: the buffer's order() is BIG_ENDIAN (ByteBuffer.allocateDirect's default); {}-byte samples are read little-endian: call order(ByteOrder.LITTLE_ENDIAN) before writing them",
                layout.bytes_per_pixel
            )));
        }
    }
    // SAFETY: `ptr` is the address of a direct buffer of `cap` bytes (JNI's
    // GetDirectBufferAddress/Capacity), which the local reference `buf` keeps alive for
    // the rest of this native call, and `position <= limit <= cap`; the slice borrows
    // `buf`, so it cannot outlive it. Java code may write the buffer concurrently (an
    // `Image` plane is only recycled after `Image.close()`, which the caller does after
    // the push returns); we only read bytes, so a concurrent write gives wrong pixels,
    // never undefined memory access.
    Ok(unsafe { std::slice::from_raw_parts(ptr.add(position), limit - position) })
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
