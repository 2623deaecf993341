//! Hand-made PNG chunks for the hostile-input tests.

/// CRC-32 of PNG chunks (ISO 3309, as zlib computes it).
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// One chunk: length, type, data, CRC.
pub fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
    let mut out = (data.len() as u32).to_be_bytes().to_vec();
    let mut body = kind.to_vec();
    body.extend_from_slice(data);
    out.extend_from_slice(&body);
    out.extend_from_slice(&crc32(&body).to_be_bytes());
    out
}

/// `png` with `extra` inserted right after its IHDR chunk (signature 8 bytes, IHDR 25).
pub fn insert_after_ihdr(png: &[u8], extra: &[u8]) -> Vec<u8> {
    let mut out = png[..33].to_vec();
    out.extend_from_slice(extra);
    out.extend_from_slice(&png[33..]);
    out
}

/// `png` with the width and height of its IHDR replaced (CRC fixed).
pub fn with_declared_size(png: &[u8], width: u32, height: u32) -> Vec<u8> {
    let mut out = png.to_vec();
    out[16..20].copy_from_slice(&width.to_be_bytes());
    out[20..24].copy_from_slice(&height.to_be_bytes());
    let crc = crc32(&out[12..29]);
    out[29..33].copy_from_slice(&crc.to_be_bytes());
    out
}

/// An iCCP chunk whose profile inflates to `inflated` zero bytes.
pub fn iccp_bomb(inflated: usize) -> Vec<u8> {
    let zeros = vec![0u8; inflated];
    let compressed = miniz_oxide::deflate::compress_to_vec_zlib(&zeros, 6);
    let mut data = b"bomb\0\0".to_vec();
    data.extend_from_slice(&compressed);
    chunk(b"iCCP", &data)
}
