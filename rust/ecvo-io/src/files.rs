//! Opening input files defensively: only regular files (or symlinks to one), read
//! with a size limit, and, for the files a sequence's lists name, only inside the
//! sequence folder. Paths in messages are escaped and shortened ([`shown`]).

use std::fmt::Write as _;
use std::fs::File;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};

/// Largest list, trajectory or `associations.txt` file read (16 MiB: about 200,000
/// lines, an hour and a half of frames at 30 per second).
pub const MAX_TEXT_BYTES: u64 = 16 << 20;

/// Largest `camera.json` read (1 MiB; a real one is about 150 bytes).
pub const MAX_CAMERA_BYTES: u64 = 1 << 20;

/// Longest path or field shown whole in a message (in characters); longer ones keep
/// their start and end around an ellipsis.
pub const MAX_SHOWN_CHARS: usize = 160;

/// A path or a field of a file as a message shows it: control characters escaped
/// (`\0`, `\n`, `\u{1b}`), and at most [`MAX_SHOWN_CHARS`] characters, long ones cut
/// in the middle with the number of characters left out.
pub fn shown(text: &str) -> String {
    let escaped: String = text
        .chars()
        .map(|c| {
            if c.is_control() || c == '\u{feff}' {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect();
    let n = escaped.chars().count();
    if n <= MAX_SHOWN_CHARS {
        return escaped;
    }
    let keep = MAX_SHOWN_CHARS / 2 - 8;
    let head: String = escaped.chars().take(keep).collect();
    let tail: String = escaped.chars().skip(n - keep).collect();
    let mut out = head;
    let _ = write!(out, "…[{} characters]…", n - 2 * keep);
    out.push_str(&tail);
    out
}

/// [`shown`] for a path.
pub fn shown_path(path: &Path) -> String {
    shown(&path.to_string_lossy())
}

/// What a non-regular file is, for the error message.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let ft = meta.file_type();
    if ft.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

/// Checks that `path` is a regular file (following symlinks) before it is opened, so
/// that a named pipe or a device cannot block or feed the reader forever; returns
/// its size in bytes.
pub fn check_regular(path: &Path) -> Result<u64> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::NotRegularFile {
            path: path.to_path_buf(),
            kind: kind_of(&meta),
        });
    }
    Ok(meta.len())
}

/// Opens a regular file of at most `limit` bytes.
pub fn open_regular(path: &Path, limit: u64) -> Result<File> {
    let len = check_regular(path)?;
    if len > limit {
        return Err(Error::TooLarge {
            path: path.to_path_buf(),
            limit,
        });
    }
    File::open(path).map_err(|e| Error::io(path, e))
}

/// Reads a regular file of at most `limit` bytes whole (the limit holds even if the
/// file grows while it is read).
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let file = open_regular(path, limit)?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(Error::TooLarge {
            path: path.to_path_buf(),
            limit,
        });
    }
    Ok(bytes)
}

/// Reads a UTF-8 text file of at most `limit` bytes; a leading byte-order mark is
/// dropped.
pub fn read_text_limited(path: &Path, limit: u64) -> Result<String> {
    let bytes = read_limited(path, limit)?;
    let mut text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        Error::InvalidInput(format!(
            "{}: not UTF-8 text (invalid byte at offset {at})",
            shown_path(path)
        ))
    })?;
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// `entry`, a file name read from a list in `dir`, joined to `dir`; refused unless
/// `allow_outside` if it is absolute or climbs out with `..` (symlinks are checked
/// when the file is read, [`check_inside`]).
pub fn join_entry(
    dir: &Path,
    list: &Path,
    line: usize,
    entry: &str,
    allow_outside: bool,
) -> Result<PathBuf> {
    let rel = Path::new(entry);
    if !allow_outside {
        let mut depth = 0usize;
        for c in rel.components() {
            match c {
                Component::Prefix(_) | Component::RootDir => {
                    return Err(Error::parse(
                        list,
                        line,
                        format!(
                            "`{}` is an absolute path; list entries must be inside the \
                             sequence folder (--allow-outside to read it anyway)",
                            shown(entry)
                        ),
                    ));
                }
                Component::ParentDir if depth == 0 => {
                    return Err(Error::parse(
                        list,
                        line,
                        format!(
                            "`{}` leads out of the sequence folder; list entries must be \
                             inside it (--allow-outside to read it anyway)",
                            shown(entry)
                        ),
                    ));
                }
                Component::ParentDir => depth -= 1,
                Component::Normal(_) => depth += 1,
                Component::CurDir => {}
            }
        }
    }
    Ok(dir.join(rel))
}

/// Checks, unless `root` is `None`, that `path` resolves (symlinks followed) to a
/// file inside the canonical folder `root`.
pub fn check_inside(path: &Path, root: Option<&Path>) -> Result<()> {
    let Some(root) = root else {
        return Ok(());
    };
    let real = path.canonicalize().map_err(|e| Error::io(path, e))?;
    if !real.starts_with(root) {
        return Err(Error::OutsideSequence {
            path: path.to_path_buf(),
            dir: root.to_path_buf(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_escapes_and_shortens() {
        assert_eq!(shown("a\0b\nc\u{1b}"), "a\\u{0}b\\nc\\u{1b}");
        assert_eq!(shown("\u{feff}#"), "\\u{feff}#");
        let long = "x".repeat(10_000_000);
        let s = shown(&long);
        assert!(s.chars().count() < MAX_SHOWN_CHARS + 40, "{}", s.len());
        assert!(s.contains("characters]"), "{s}");
        assert_eq!(shown("rgb/1.png"), "rgb/1.png");
    }

    #[test]
    fn entries_stay_inside() {
        let dir = Path::new("/seq");
        let list = Path::new("/seq/rgb.txt");
        assert_eq!(
            join_entry(dir, list, 1, "rgb/./1.png", false).unwrap(),
            Path::new("/seq/rgb/./1.png")
        );
        join_entry(dir, list, 1, "rgb/../depth/1.png", false).unwrap();
        for bad in ["../outside.png", "/etc/passwd", "rgb/../../x.png"] {
            let e = join_entry(dir, list, 3, bad, false)
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("/seq/rgb.txt:3:"), "{e}");
            assert!(e.contains("--allow-outside"), "{e}");
            join_entry(dir, list, 3, bad, true).unwrap();
        }
    }
}
