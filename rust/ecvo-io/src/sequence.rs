//! RGB-D sequences on disk: TUM RGB-D folders, ICL-NUIM folders in the TUM-style
//! layout, and streams recorded with [`crate::SequenceWriter`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use ecvo_core::{Camera, FrameView};

use crate::camera::{CAMERA_FILE, load_camera_json};
use crate::error::{Error, Result};
use crate::files::{check_inside, join_entry, shown_path};
use crate::list::{Monotonic, associate_stamps, parse_f64, read_image_list, read_text, records};
use crate::png::{png_size, read_depth_png, read_intensity_png};
use crate::reader::FrameReader;
use crate::trajectory::Trajectory;

/// Largest time difference (seconds, exclusive) between the depth and colour images
/// of one frame, as in TUM's `associate.py`.
pub const MAX_RGB_DEPTH_DT: f64 = 0.02;

/// How a sequence folder is organised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// TUM RGB-D: `rgb.txt`, `depth.txt`, optional `groundtruth.txt` (also the layout
    /// of recorded streams, which add `camera.json`).
    Tum,
    /// ICL-NUIM, TUM-style: `associations.txt` (`id depth/id.png id rgb/id.png`) and
    /// ground truth in a `*.gt.freiburg` file whose timestamps are the frame ids.
    IclNuim,
}

/// Where one frame's images are and when it was taken.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInfo {
    /// Time of the frame in seconds: the colour image's timestamp for TUM (as the TUM
    /// tools use it), the frame id for ICL-NUIM.
    pub timestamp: f64,
    /// Timestamp of the depth image (equal to `timestamp` for ICL-NUIM).
    pub depth_timestamp: f64,
    /// Path of the intensity (colour or gray) PNG.
    pub rgb: PathBuf,
    /// Path of the 16-bit depth PNG.
    pub depth: PathBuf,
}

/// One decoded RGB-D frame owning its buffers (`width * height`, row-major).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Position of the frame in its sequence.
    pub index: usize,
    /// Time of the frame in seconds.
    pub timestamp: f64,
    /// Time of its depth image in seconds ([`FrameInfo::depth_timestamp`]; equal to
    /// `timestamp` when the two images are taken together).
    pub depth_timestamp: f64,
    /// 8-bit gray intensity.
    pub intensity: Vec<u8>,
    /// Raw 16-bit depth (camera `depth_scale` units per metre, 0 = no measurement).
    pub depth: Vec<u16>,
}

impl Frame {
    /// Borrows the frame as the tracker's input type.
    pub fn view(&self) -> FrameView<'_> {
        FrameView {
            timestamp: self.timestamp,
            intensity: &self.intensity,
            depth: &self.depth,
        }
    }
}

/// How [`Sequence::open_with`] reads a sequence folder.
#[derive(Clone, Debug, Default)]
#[non_exhaustive]
pub struct OpenOptions {
    /// Read list entries that lead outside the sequence folder (absolute paths, `..`,
    /// symlinks out). Off by default: a downloaded sequence cannot make the reader
    /// open other files.
    pub allow_outside: bool,
}

impl OpenOptions {
    /// The defaults: reads stay inside the sequence folder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets [`OpenOptions::allow_outside`].
    pub fn allow_outside(mut self, allow: bool) -> Self {
        self.allow_outside = allow;
        self
    }
}

/// What the lists of a sequence held and how much of it became frames.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Listing {
    /// Entries of `rgb.txt` (TUM) or lines of `associations.txt` (ICL-NUIM).
    pub rgb_listed: usize,
    /// Entries of `depth.txt` (TUM) or lines of `associations.txt` (ICL-NUIM).
    pub depth_listed: usize,
    /// Colour/depth pairs: the frames of the sequence.
    pub paired: usize,
    /// Colour entries with no depth entry within [`MAX_RGB_DEPTH_DT`] (not read).
    pub unpaired_rgb: usize,
    /// Depth entries with no colour entry within [`MAX_RGB_DEPTH_DT`] (not read).
    pub unpaired_depth: usize,
    /// Frames left out by [`Sequence::every_nth`].
    pub stepped_over: usize,
}

/// An opened RGB-D sequence: its camera, frame list and optional ground truth. Frames
/// are decoded on demand ([`Sequence::load_frame`]) or streamed ([`Sequence::reader`]).
#[derive(Clone, Debug)]
pub struct Sequence {
    dir: PathBuf,
    /// The canonical folder every frame file must resolve into (`None` with
    /// [`OpenOptions::allow_outside`]).
    root: Option<PathBuf>,
    layout: Layout,
    camera: Camera,
    frames: Arc<[FrameInfo]>,
    groundtruth: Option<Trajectory>,
    listing: Listing,
}

impl Sequence {
    /// Opens the sequence in `dir`, detecting its layout: TUM (`rgb.txt` and
    /// `depth.txt`) or ICL-NUIM (`associations.txt`).
    ///
    /// The camera is `camera_override` if given, else `dir/camera.json`, else an error
    /// asking for one; the first frame's PNG sizes are checked against it. TUM colour
    /// and depth images are paired one-to-one by nearest timestamp within
    /// [`MAX_RGB_DEPTH_DT`] as `associate.py` does. Ground truth (`groundtruth.txt`, or
    /// `*.gt.freiburg` for ICL-NUIM) is optional but must parse if present.
    ///
    /// Reads stay inside the folder (see [`OpenOptions`]); every file read is a
    /// regular file within a size limit ([`crate::files`]).
    pub fn open(dir: impl AsRef<Path>, camera_override: Option<Camera>) -> Result<Sequence> {
        Self::open_with(dir, camera_override, &OpenOptions::default())
    }

    /// [`Sequence::open`] with options.
    pub fn open_with(
        dir: impl AsRef<Path>,
        camera_override: Option<Camera>,
        options: &OpenOptions,
    ) -> Result<Sequence> {
        let dir = dir.as_ref().to_path_buf();
        let allow = options.allow_outside;
        if !dir.is_dir() {
            let source = if dir.exists() {
                std::io::Error::other("not a folder")
            } else {
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such folder")
            };
            return Err(Error::io(&dir, source));
        }
        let root = if allow {
            None
        } else {
            Some(dir.canonicalize().map_err(|e| Error::io(&dir, e))?)
        };
        // `exists`, not `is_file`: a named pipe in place of a list is then refused by
        // name rather than read as "not a sequence folder".
        let (layout, frames, groundtruth, listing) =
            if dir.join("rgb.txt").exists() || dir.join("depth.txt").exists() {
                let (frames, gt, listing) = open_tum(&dir, allow)?;
                (Layout::Tum, frames, gt, listing)
            } else if dir.join("associations.txt").exists() {
                let (frames, gt, listing) = open_icl(&dir, allow)?;
                (Layout::IclNuim, frames, gt, listing)
            } else {
                return Err(Error::UnknownLayout { dir });
            };

        let camera = match camera_override {
            Some(c) => {
                c.validate().map_err(|e| {
                    Error::InvalidInput(format!("camera given for {}: {e}", dir.display()))
                })?;
                c
            }
            None => {
                let file = dir.join(CAMERA_FILE);
                if !file.exists() {
                    return Err(Error::MissingCamera { dir });
                }
                load_camera_json(&file)?
            }
        };

        let first = frames.first().ok_or_else(|| Error::EmptySequence {
            dir: dir.clone(),
            msg: match layout {
                Layout::Tum => format!(
                    "no colour/depth image pair within {MAX_RGB_DEPTH_DT} s in rgb.txt and depth.txt"
                ),
                Layout::IclNuim => "associations.txt lists no frame".to_string(),
            },
        })?;
        for path in [&first.rgb, &first.depth] {
            check_inside(path, root.as_deref())?;
            let (w, h) = png_size(path)?;
            if (w, h) != (camera.width, camera.height) {
                return Err(Error::ImageSize {
                    path: path.clone(),
                    width: w,
                    height: h,
                    expected_width: camera.width,
                    expected_height: camera.height,
                });
            }
        }

        Ok(Sequence {
            dir,
            root,
            layout,
            camera,
            frames: frames.into(),
            groundtruth,
            listing,
        })
    }

    /// What the lists held and how much of it became frames.
    pub fn listing(&self) -> &Listing {
        &self.listing
    }

    /// The sequence folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The detected layout.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The camera the frames are decoded for.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Number of frames (associated colour/depth pairs).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the sequence has no frame (never true for an opened sequence).
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The frames in time order: timestamps and image paths.
    pub fn frames(&self) -> &[FrameInfo] {
        &self.frames
    }

    /// Timestamps of all frames, in order.
    pub fn timestamps(&self) -> Vec<f64> {
        self.frames.iter().map(|f| f.timestamp).collect()
    }

    /// The ground-truth trajectory, if the folder has one.
    pub fn groundtruth(&self) -> Option<&Trajectory> {
        self.groundtruth.as_ref()
    }

    /// The same sequence with only every `step`-th frame (frames `0, step, 2·step, …`),
    /// the standard way to test fast motion on recorded data: each kept frame is
    /// `step` times further from the previous one. `step` 0 or 1 keeps every frame.
    pub fn every_nth(&self, step: usize) -> Sequence {
        let step = step.max(1);
        let frames: Vec<FrameInfo> = self.frames.iter().step_by(step).cloned().collect();
        let mut listing = self.listing.clone();
        listing.stepped_over += self.frames.len() - frames.len();
        Sequence {
            frames: frames.into(),
            listing,
            ..self.clone()
        }
    }

    /// Decodes frame `index` into a new [`Frame`].
    pub fn load_frame(&self, index: usize) -> Result<Frame> {
        let mut frame = Frame::default();
        self.load_frame_into(index, &mut frame)?;
        Ok(frame)
    }

    /// Decodes frame `index` into `frame`, reusing its buffers' allocations.
    pub fn load_frame_into(&self, index: usize, frame: &mut Frame) -> Result<()> {
        let info = self.frames.get(index).ok_or(Error::FrameIndex {
            index,
            len: self.frames.len(),
        })?;
        load_into(&self.camera, self.root.as_deref(), info, index, frame)
    }

    /// Decodes frame `index` with its colour: `(timestamp, rgb, depth)`, `rgb` being
    /// `width * height * 3` bytes ([`crate::png::read_colour_png`]; the frame's
    /// intensity is their gray).
    pub fn load_colour_frame(&self, index: usize) -> Result<(f64, Vec<u8>, Vec<u16>)> {
        let info = self.frames.get(index).ok_or(Error::FrameIndex {
            index,
            len: self.frames.len(),
        })?;
        let root = self.root.as_deref();
        check_inside(&info.rgb, root)?;
        check_inside(&info.depth, root)?;
        let (w, h) = (self.camera.width, self.camera.height);
        let (mut rgb, mut depth) = (Vec::new(), Vec::new());
        crate::png::read_colour_png(&info.rgb, w, h, &mut rgb)?;
        read_depth_png(&info.depth, w, h, &mut depth)?;
        Ok((info.timestamp, rgb, depth))
    }

    /// Streams the first `max_frames` frames (all if `None`), decoded ahead on a
    /// background thread with at most `prefetch` (at least 1) decoded frames waiting.
    /// See [`FrameReader`].
    pub fn reader(&self, max_frames: Option<usize>, prefetch: usize) -> FrameReader {
        let n = max_frames.map_or(self.len(), |m| m.min(self.len()));
        FrameReader::spawn(
            self.camera,
            self.root.clone(),
            self.frames.clone(),
            n,
            prefetch,
        )
    }
}

/// Decodes one frame described by `info` into `frame`; with a `root`, its files must
/// resolve inside it.
pub(crate) fn load_into(
    camera: &Camera,
    root: Option<&Path>,
    info: &FrameInfo,
    index: usize,
    frame: &mut Frame,
) -> Result<()> {
    check_inside(&info.rgb, root)?;
    check_inside(&info.depth, root)?;
    read_intensity_png(&info.rgb, camera.width, camera.height, &mut frame.intensity)?;
    read_depth_png(&info.depth, camera.width, camera.height, &mut frame.depth)?;
    frame.index = index;
    frame.timestamp = info.timestamp;
    frame.depth_timestamp = info.depth_timestamp;
    Ok(())
}

type Opened = (Vec<FrameInfo>, Option<Trajectory>, Listing);

fn open_tum(dir: &Path, allow_outside: bool) -> Result<Opened> {
    let rgb_path = dir.join("rgb.txt");
    let depth_path = dir.join("depth.txt");
    let rgb = read_image_list(&rgb_path, allow_outside)?;
    let depth = read_image_list(&depth_path, allow_outside)?;
    let rgb_t: Vec<f64> = rgb.iter().map(|e| e.timestamp).collect();
    let depth_t: Vec<f64> = depth.iter().map(|e| e.timestamp).collect();
    let pairs = associate_stamps(&rgb_t, &depth_t, MAX_RGB_DEPTH_DT);
    let listing = Listing {
        rgb_listed: rgb.len(),
        depth_listed: depth.len(),
        paired: pairs.len(),
        unpaired_rgb: rgb.len() - pairs.len(),
        unpaired_depth: depth.len() - pairs.len(),
        stepped_over: 0,
    };
    for (n, list, other) in [
        (listing.unpaired_rgb, &rgb_path, "depth"),
        (listing.unpaired_depth, &depth_path, "colour"),
    ] {
        if n > 0 {
            log::warn!(
                "{}: {n} of its {} entries have no {other} image within {MAX_RGB_DEPTH_DT} s \
                 and are skipped",
                shown_path(list),
                if other == "depth" {
                    rgb.len()
                } else {
                    depth.len()
                },
            );
        }
    }
    let frames = pairs
        .into_iter()
        .map(|(i, j)| FrameInfo {
            timestamp: rgb[i].timestamp,
            depth_timestamp: depth[j].timestamp,
            rgb: dir.join(&rgb[i].file),
            depth: dir.join(&depth[j].file),
        })
        .collect();
    let gt_path = dir.join("groundtruth.txt");
    let gt = if gt_path.exists() {
        Some(Trajectory::read_tum(&gt_path)?)
    } else {
        None
    };
    Ok((frames, gt, listing))
}

fn open_icl(dir: &Path, allow_outside: bool) -> Result<Opened> {
    let path = dir.join("associations.txt");
    let frames = parse_associations_with(&read_text(&path)?, &path, dir, allow_outside)?;
    let listing = Listing {
        rgb_listed: frames.len(),
        depth_listed: frames.len(),
        paired: frames.len(),
        ..Listing::default()
    };
    let mut gts: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.ends_with(".gt.freiburg"))
        })
        .collect();
    gts.sort();
    if gts.len() > 1 {
        log::warn!(
            "{}: several *.gt.freiburg files, using {}",
            dir.display(),
            gts[0].display()
        );
    }
    let gt = match gts.first() {
        Some(p) => Some(Trajectory::read_tum(p)?),
        None => None,
    };
    Ok((frames, gt, listing))
}

/// Parses an ICL-NUIM `associations.txt` (`id depth/id.png id rgb/id.png` per line,
/// ids strictly increasing) into frames whose files are in `dir`; `path` is only used
/// in error messages. A file name that is absolute or climbs out of `dir` with `..`
/// is an error naming the line.
pub fn parse_associations(text: &str, path: &Path, dir: &Path) -> Result<Vec<FrameInfo>> {
    parse_associations_with(text, path, dir, false)
}

/// [`parse_associations`], accepting file names outside `dir` if `allow_outside`.
pub fn parse_associations_with(
    text: &str,
    path: &Path,
    dir: &Path,
    allow_outside: bool,
) -> Result<Vec<FrameInfo>> {
    let path = path.to_path_buf();
    let mut frames = Vec::new();
    let mut mono = Monotonic::default();
    for r in records(text) {
        if r.fields.len() != 4 {
            return Err(Error::parse(
                &path,
                r.line,
                format!(
                    "expected `id depth/id.png id rgb/id.png`, found {} field(s)",
                    r.fields.len()
                ),
            ));
        }
        let t = parse_f64(&path, r.line, "depth id", r.fields[0])?;
        let t_rgb = parse_f64(&path, r.line, "rgb id", r.fields[2])?;
        mono.check(&path, r.line, t)?;
        frames.push(FrameInfo {
            timestamp: t,
            depth_timestamp: t,
            rgb: join_entry(dir, &path, r.line, r.fields[3], allow_outside)?,
            depth: join_entry(dir, &path, r.line, r.fields[1], allow_outside)?,
        });
        if t_rgb != t {
            log::debug!(
                "{}:{}: depth id {t} and rgb id {t_rgb} differ; using the depth id",
                path.display(),
                r.line
            );
        }
    }
    Ok(frames)
}
