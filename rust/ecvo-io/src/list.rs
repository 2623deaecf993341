//! Line-oriented text files (`rgb.txt`, `depth.txt`, `associations.txt`, TUM
//! trajectories) and nearest-timestamp association.

use std::path::Path;

use crate::error::{Error, Result};
use crate::files::{MAX_TEXT_BYTES, join_entry, read_text_limited, shown};

/// One non-empty, non-comment line of a text file.
pub(crate) struct Record<'a> {
    /// 1-based line number.
    pub line: usize,
    /// Whitespace-separated fields.
    pub fields: Vec<&'a str>,
}

/// Reads a whole text file (a regular file of at most [`MAX_TEXT_BYTES`], a leading
/// byte-order mark dropped), naming it in the error.
pub(crate) fn read_text(path: &Path) -> Result<String> {
    read_text_limited(path, MAX_TEXT_BYTES)
}

/// The data lines of `text`: blank lines and lines starting with `#` are skipped; a
/// leading byte-order mark is ignored.
pub(crate) fn records(text: &str) -> impl Iterator<Item = Record<'_>> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    text.lines().enumerate().filter_map(|(i, l)| {
        let t = l.trim();
        if t.is_empty() || t.starts_with('#') {
            None
        } else {
            Some(Record {
                line: i + 1,
                fields: t.split_whitespace().collect(),
            })
        }
    })
}

/// Parses a finite number; `what` names the field in the error.
pub(crate) fn parse_f64(path: &Path, line: usize, what: &str, s: &str) -> Result<f64> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(Error::parse(
            path,
            line,
            format!("{what} `{}` is not finite ({v})", shown(s)),
        )),
        Err(_) => Err(Error::parse(
            path,
            line,
            format!("{what} `{}` is not a number", shown(s)),
        )),
    }
}

/// Checks that timestamps are strictly increasing, line after line.
#[derive(Default)]
pub(crate) struct Monotonic {
    prev: Option<f64>,
}

impl Monotonic {
    /// Accepts `t` if it is after the previous timestamp.
    pub fn check(&mut self, path: &Path, line: usize, t: f64) -> Result<()> {
        if let Some(prev) = self.prev
            && t <= prev
        {
            return Err(Error::NonMonotonic {
                path: path.to_path_buf(),
                line,
                timestamp: t,
                previous: prev,
            });
        }
        self.prev = Some(t);
        Ok(())
    }
}

/// One entry of a TUM image list: `timestamp filename`.
#[derive(Clone, Debug, PartialEq)]
pub struct ListEntry {
    /// Timestamp in seconds.
    pub timestamp: f64,
    /// File name, relative to the list's folder.
    pub file: String,
}

/// Reads a TUM image list (`rgb.txt`, `depth.txt`): `timestamp filename` per line,
/// `#` comments and blank lines allowed, timestamps strictly increasing; file names
/// inside the list's folder unless `allow_outside`.
pub(crate) fn read_image_list(path: &Path, allow_outside: bool) -> Result<Vec<ListEntry>> {
    parse_image_list_with(&read_text(path)?, path, allow_outside)
}

/// Parses the text of a TUM image list (see `read_image_list`); `path` is only used
/// in error messages. A file name that is absolute or climbs out of the list's
/// folder with `..` is an error naming the line.
pub fn parse_image_list(text: &str, path: &Path) -> Result<Vec<ListEntry>> {
    parse_image_list_with(text, path, false)
}

/// [`parse_image_list`], accepting file names outside the list's folder if
/// `allow_outside`.
pub fn parse_image_list_with(
    text: &str,
    path: &Path,
    allow_outside: bool,
) -> Result<Vec<ListEntry>> {
    let mut out = Vec::new();
    let mut mono = Monotonic::default();
    for r in records(text) {
        if r.fields.len() != 2 {
            return Err(Error::parse(
                path,
                r.line,
                format!(
                    "expected `timestamp filename`, found {} field(s)",
                    r.fields.len()
                ),
            ));
        }
        let timestamp = parse_f64(path, r.line, "timestamp", r.fields[0])?;
        mono.check(path, r.line, timestamp)?;
        join_entry(Path::new(""), path, r.line, r.fields[1], allow_outside)?;
        out.push(ListEntry {
            timestamp,
            file: r.fields[1].to_string(),
        });
    }
    Ok(out)
}

/// Candidates a timestamp of `first` considers on each side of its position among the
/// timestamps of `second` (see [`associate_stamps`]).
pub const MAX_CANDIDATES_PER_SIDE: usize = 8;

/// Pairs timestamps of `first` and `second` one-to-one, the way TUM's `associate.py`
/// does: every pair with `|a - b| < max_dt` is a candidate, candidates are taken
/// greedily by increasing `|a - b|` (ties by index), each index at most once, and
/// the result is sorted by the index into `first`.
///
/// Unlike `associate.py`, a timestamp of `first` considers only the
/// `MAX_CANDIDATES_PER_SIDE` nearest timestamps of `second` on each side of it (real
/// streams have one or two within `max_dt`), so that hostile lists with thousands of
/// timestamps within `max_dt` cost linear memory instead of quadratic.
pub fn associate_stamps(first: &[f64], second: &[f64], max_dt: f64) -> Vec<(usize, usize)> {
    let mut order: Vec<usize> = (0..second.len())
        .filter(|&j| second[j].is_finite())
        .collect();
    order.sort_by(|&a, &b| second[a].total_cmp(&second[b]).then(a.cmp(&b)));
    let sorted: Vec<f64> = order.iter().map(|&j| second[j]).collect();

    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
    for (i, &a) in first.iter().enumerate() {
        if !a.is_finite() {
            continue;
        }
        let start = sorted.partition_point(|&b| b <= a - max_dt);
        let mid = sorted.partition_point(|&b| b < a).max(start);
        let from = start.max(mid.saturating_sub(MAX_CANDIDATES_PER_SIDE));
        let to = (mid + MAX_CANDIDATES_PER_SIDE).min(sorted.len());
        for (k, &b) in sorted.iter().enumerate().take(to).skip(from) {
            let d = (a - b).abs();
            if b - a >= max_dt {
                break;
            }
            if d < max_dt {
                candidates.push((d, i, order[k]));
            }
        }
    }
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));

    let mut used_first = vec![false; first.len()];
    let mut used_second = vec![false; second.len()];
    let mut pairs = Vec::new();
    for (_, i, j) in candidates {
        if !used_first[i] && !used_second[j] {
            used_first[i] = true;
            used_second[j] = true;
            pairs.push((i, j));
        }
    }
    pairs.sort_by(|x, y| first[x.0].total_cmp(&first[y.0]).then(x.cmp(y)));
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn association_is_one_to_one_and_greedy() {
        // 1.0 is closest to 1.005; 1.012 must then take 1.02 rather than 1.005.
        let a = [1.0, 1.012, 2.0, 5.0];
        let b = [1.005, 1.02, 1.99, 3.0];
        let p = associate_stamps(&a, &b, 0.02);
        assert_eq!(p, vec![(0, 0), (1, 1), (2, 2)]);
        // Strict bound: exactly max_dt apart is not a match.
        assert!(associate_stamps(&[1.0], &[1.5], 0.5).is_empty());
        assert_eq!(associate_stamps(&[1.0], &[1.25], 0.5), vec![(0, 0)]);
        // Unsorted second list.
        assert_eq!(
            associate_stamps(&[1.0, 2.0], &[2.001, 0.999], 0.02),
            vec![(0, 1), (1, 0)]
        );
    }

    #[test]
    fn monotonic_names_file_and_line() {
        let mut m = Monotonic::default();
        let p = Path::new("x/rgb.txt");
        m.check(p, 3, 1.0).unwrap();
        let e = m.check(p, 4, 1.0).unwrap_err().to_string();
        assert!(e.starts_with("x/rgb.txt:4:"), "{e}");
    }
}
