//! PLY output: header and binary body.

use crate::common;

use common::TempDir;
use ecvo_io::write_ply;

#[test]
fn ply_header_and_body() {
    let tmp = TempDir::new("ply");
    let p = tmp.path().join("cloud.ply");
    let pts = [[1.0f32, 2.0, 3.0], [-0.5, 0.25, 8.0]];
    let nrm = [[0.0f32, 0.0, -1.0], [1.0, 0.0, 0.0]];
    write_ply(&p, &pts, Some(&nrm), Some(&[10, 200])).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    let end = b"end_header\n";
    let pos = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&bytes[..pos]).unwrap();
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    assert!(header.contains("element vertex 2\n"));
    assert!(header.contains("property float nx\n"));
    assert!(header.contains("property uchar red\nproperty uchar green\nproperty uchar blue\n"));
    let body = &bytes[pos..];
    assert_eq!(body.len(), 2 * (6 * 4 + 3));
    let f = |o: usize| f32::from_le_bytes(body[o..o + 4].try_into().unwrap());
    assert_eq!((f(0), f(4), f(8)), (1.0, 2.0, 3.0));
    assert_eq!(f(20), -1.0);
    assert_eq!(&body[24..27], &[10, 10, 10]);
    assert_eq!(f(27), -0.5);
    assert_eq!(&body[51..54], &[200, 200, 200]);

    write_ply(&p, &pts, None, None).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    let header = String::from_utf8_lossy(&bytes[..100]);
    assert!(!header.contains("nx") && !header.contains("red"));
    let pos = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    assert_eq!(bytes.len() - pos, 24);

    assert!(write_ply(&p, &pts, Some(&nrm[..1]), None).is_err());
    assert!(write_ply(&p, &pts, None, Some(&[1])).is_err());
}
