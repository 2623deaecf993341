//! Point clouds as binary little-endian PLY files, readable by MeshLab, CloudCompare
//! and Open3D.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, Result};

/// Writes `points` (metres) as a binary little-endian PLY file with `float x y z`,
/// optional `float nx ny nz` normals and optional intensity, stored as equal
/// `uchar red green blue` so that viewers show it as gray. `normals` and
/// `intensity`, when given, must have one entry per point.
pub fn write_ply(
    path: impl AsRef<Path>,
    points: &[[f32; 3]],
    normals: Option<&[[f32; 3]]>,
    intensity: Option<&[u8]>,
) -> Result<()> {
    let path = path.as_ref();
    let n = points.len();
    if let Some(nr) = normals
        && nr.len() != n
    {
        return Err(Error::InvalidInput(format!(
            "{}: {} normals for {n} points",
            path.display(),
            nr.len()
        )));
    }
    if let Some(it) = intensity
        && it.len() != n
    {
        return Err(Error::InvalidInput(format!(
            "{}: {} intensities for {n} points",
            path.display(),
            it.len()
        )));
    }
    let mut header =
        String::from("ply\nformat binary_little_endian 1.0\ncomment written by ecvo\n");
    header.push_str(&format!("element vertex {n}\n"));
    header.push_str("property float x\nproperty float y\nproperty float z\n");
    if normals.is_some() {
        header.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if intensity.is_some() {
        header.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    header.push_str("end_header\n");

    let write = || -> std::io::Result<()> {
        let mut w = BufWriter::new(File::create(path)?);
        w.write_all(header.as_bytes())?;
        for (k, p) in points.iter().enumerate() {
            for v in p {
                w.write_all(&v.to_le_bytes())?;
            }
            if let Some(nr) = normals {
                for v in &nr[k] {
                    w.write_all(&v.to_le_bytes())?;
                }
            }
            if let Some(it) = intensity {
                w.write_all(&[it[k]; 3])?;
            }
        }
        w.flush()
    };
    write().map_err(|e| Error::io(path, e))
}
