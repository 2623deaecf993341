//! Recording RGB-D streams in the TUM layout plus `camera.json`, which
//! [`crate::Sequence::open`] reads back bit-exactly.
//!
//! Layout: `camera.json`, `rgb.txt`, `depth.txt` (`timestamp filename`, TUM-style
//! `#` headers), `rgb/<ts>.png` (8-bit gray), `depth/<ts>.png` (16-bit gray), and
//! optionally `groundtruth.txt`; timestamps are written as `{:.6}` seconds.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use ecvo_core::Camera;

use crate::camera::{CAMERA_FILE, save_camera_json};
use crate::error::{Error, Result};
use crate::png::{write_depth_png, write_intensity_png};
use crate::trajectory::Trajectory;

/// Writes a recorded stream frame by frame into a new sequence folder.
///
/// List files are flushed after every frame, so a recording cut short is still a
/// readable sequence up to the last complete frame.
pub struct SequenceWriter {
    dir: PathBuf,
    camera: Camera,
    rgb_list: BufWriter<File>,
    depth_list: BufWriter<File>,
    last_stamp: Option<f64>,
    frames: usize,
}

fn open_list(path: &Path, header: &str) -> Result<BufWriter<File>> {
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .map_err(|e| Error::io(path, e))?;
    let mut w = BufWriter::new(file);
    w.write_all(header.as_bytes())
        .and_then(|()| w.flush())
        .map_err(|e| Error::io(path, e))?;
    Ok(w)
}

impl SequenceWriter {
    /// Creates `dir` (and parents) with `camera.json`, `rgb/`, `depth/` and the list
    /// headers. Fails if `dir` already holds an `rgb.txt` or `depth.txt`, so that an
    /// existing sequence is never overwritten.
    pub fn create(dir: impl AsRef<Path>, camera: &Camera) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        camera
            .validate()
            .map_err(|e| Error::InvalidInput(format!("camera for {}: {e}", dir.display())))?;
        for name in ["rgb.txt", "depth.txt"] {
            let p = dir.join(name);
            if p.exists() {
                return Err(Error::io(
                    &p,
                    std::io::Error::new(
                        std::io::ErrorKind::AlreadyExists,
                        "already exists; refusing to overwrite a sequence",
                    ),
                ));
            }
        }
        for sub in [dir.clone(), dir.join("rgb"), dir.join("depth")] {
            std::fs::create_dir_all(&sub).map_err(|e| Error::io(&sub, e))?;
        }
        save_camera_json(dir.join(CAMERA_FILE), camera)?;
        let rgb_list = open_list(
            &dir.join("rgb.txt"),
            "# color images (8-bit gray)\n# file: 'ecvo recording'\n# timestamp filename\n",
        )?;
        let depth_list = open_list(
            &dir.join("depth.txt"),
            "# depth maps\n# file: 'ecvo recording'\n# timestamp filename\n",
        )?;
        Ok(SequenceWriter {
            dir,
            camera: *camera,
            rgb_list,
            depth_list,
            last_stamp: None,
            frames: 0,
        })
    }

    /// The folder being written.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Number of frames written so far.
    pub fn frames_written(&self) -> usize {
        self.frames
    }

    /// Writes one frame: `rgb/<ts>.png`, `depth/<ts>.png` and a line in each list.
    ///
    /// `timestamp` must be finite and, once formatted as `{:.6}`, after the previous
    /// frame's; both buffers must hold `width * height` values.
    pub fn write_frame(&mut self, timestamp: f64, intensity: &[u8], depth: &[u16]) -> Result<()> {
        self.write_frame_stamped(timestamp, timestamp, intensity, depth)
    }

    /// [`Self::write_frame`] with the depth image stamped `depth_timestamp` (in
    /// `depth.txt` and its file name), taken at another time than the intensity, as a
    /// Kinect's two streams are. The order check is on `timestamp`.
    pub fn write_frame_stamped(
        &mut self,
        timestamp: f64,
        depth_timestamp: f64,
        intensity: &[u8],
        depth: &[u16],
    ) -> Result<()> {
        let name = format!("{timestamp:.6}");
        let depth_name = format!("{depth_timestamp:.6}");
        if !depth_name
            .parse::<f64>()
            .is_ok_and(|d| d.is_finite() && d >= 0.0)
        {
            return Err(Error::InvalidInput(format!(
                "{}: depth timestamp {depth_timestamp} must be finite and not negative",
                self.dir.display()
            )));
        }
        let stamp: f64 = name.parse().unwrap_or(f64::NAN);
        if !stamp.is_finite() || stamp < 0.0 {
            return Err(Error::InvalidInput(format!(
                "{}: timestamp {timestamp} must be finite and not negative",
                self.dir.display()
            )));
        }
        if let Some(prev) = self.last_stamp
            && stamp <= prev
        {
            return Err(Error::InvalidInput(format!(
                "{}: timestamp {name} is not after the previous frame's ({prev:.6})",
                self.dir.display()
            )));
        }
        let (w, h) = (self.camera.width, self.camera.height);
        let rgb_rel = format!("rgb/{name}.png");
        let depth_rel = format!("depth/{depth_name}.png");
        write_intensity_png(self.dir.join(&rgb_rel), intensity, w, h)?;
        write_depth_png(self.dir.join(&depth_rel), depth, w, h)?;
        let rgb_path = self.dir.join("rgb.txt");
        writeln!(self.rgb_list, "{name} {rgb_rel}")
            .and_then(|()| self.rgb_list.flush())
            .map_err(|e| Error::io(&rgb_path, e))?;
        let depth_path = self.dir.join("depth.txt");
        writeln!(self.depth_list, "{depth_name} {depth_rel}")
            .and_then(|()| self.depth_list.flush())
            .map_err(|e| Error::io(&depth_path, e))?;
        self.last_stamp = Some(stamp);
        self.frames += 1;
        Ok(())
    }

    /// Writes `groundtruth.txt` (TUM trajectory format with a TUM-style header).
    pub fn write_groundtruth(&mut self, groundtruth: &Trajectory) -> Result<()> {
        groundtruth.write_tum(self.dir.join("groundtruth.txt"))
    }

    /// Flushes and syncs the list files; returns the number of frames written.
    pub fn finish(mut self) -> Result<usize> {
        for (list, name) in [
            (&mut self.rgb_list, "rgb.txt"),
            (&mut self.depth_list, "depth.txt"),
        ] {
            let path = self.dir.join(name);
            list.flush()
                .and_then(|()| list.get_ref().sync_all())
                .map_err(|e| Error::io(&path, e))?;
        }
        Ok(self.frames)
    }
}
