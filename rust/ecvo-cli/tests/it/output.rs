//! What a user reads: numbers in error messages as written or with an exponent, a
//! quiet exit on a closed stdout, a warning said once, `run --help` in groups.

use std::fs;

use crate::common::{fails, mini_sequence, run, run_ok, run_seq, temp_dir, testdata_stream};

/// Longest run of digits in `text`.
fn longest_digit_run(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// A refused value of 1e300 (or 1e-300) is printed as such: the message stays one short
/// line, with no 300-digit decimal.
#[test]
fn huge_numbers_in_errors_are_printed_as_written() {
    let dir = temp_dir("numbers");
    let seq = mini_sequence(&dir, 3);
    let out = dir.join("out");
    let cam = seq.join("camera.json");
    let good = fs::read_to_string(&cam).unwrap();
    for (from, to, shown) in [
        ("\"fx\": 250.0", "\"fx\": 1e300", "1e300"),
        ("\"cx\": 159.5", "\"cx\": -1e300", "-1e300"),
        ("\"depth_scale\": 1000.0", "\"depth_scale\": 1e300", "1e300"),
        (
            "\"depth_scale\": 1000.0",
            "\"depth_scale\": 1e-300",
            "1e-300",
        ),
    ] {
        fs::write(&cam, good.replace(from, to)).unwrap();
        let e = fails(&run_seq(&seq, &out, &[]), &["camera.json", shown]);
        assert!(longest_digit_run(&e) < 20, "{e}");
        assert!(e.len() < 400, "{} characters: {e}", e.len());
    }
    fs::write(&cam, &good).unwrap();
    // Ground truth, through `run` and `eval`: a position and a timestamp.
    let gt = seq.join("groundtruth.txt");
    let text = fs::read_to_string(&gt).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let data: Vec<usize> = (0..lines.len())
        .filter(|&i| !lines[i].starts_with('#'))
        .collect();
    let tx = lines[data[1]].split_whitespace().nth(1).unwrap();
    for bad in [
        text.replacen(tx, "1e300", 1),
        // A timestamp of 1e300 followed by a smaller one: not increasing.
        text.replacen(
            &format!("\n{}", lines[data[1]].split_whitespace().next().unwrap()),
            "\n1e300",
            1,
        ),
    ] {
        fs::write(&gt, &bad).unwrap();
        for o in [
            run_seq(&seq, &out, &[]),
            run(&["eval", gt.to_str().unwrap(), gt.to_str().unwrap()]),
        ] {
            let e = fails(&o, &["groundtruth.txt", "1e300"]);
            assert!(longest_digit_run(&e) < 20, "{e}");
            assert!(e.len() < 400, "{} characters: {e}", e.len());
        }
    }
}

/// `ecvo eval GT EST | head -1`: stdout closed before ecvo writes; a quiet exit with
/// status 0, no panic.
#[test]
fn eval_into_a_closed_pipe_exits_quietly() {
    let gt = testdata_stream().join("groundtruth.txt");
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = crate::common::ecvo()
        .args(["eval", gt.to_str().unwrap(), gt.to_str().unwrap()])
        .stdout(writer)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{:?}: {stderr}", o.status);
    assert!(stderr.is_empty(), "{stderr}");
    // The same command into an open pipe prints its three lines.
    let o = run_ok(&["eval", gt.to_str().unwrap(), gt.to_str().unwrap()]);
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 3);
}

/// `ecvo table` tracks each sequence once per cell; a warning of its reader (colour
/// entries without a depth partner) is said once, not once per cell.
#[test]
fn table_says_a_warning_once() {
    let dir = temp_dir("table-once");
    let seq = mini_sequence(&dir, 12);
    // A colour entry 0.5 s after the last one: no depth image within 0.02 s.
    let rgb = seq.join("rgb.txt");
    let (t, f) = crate::common::entry(&rgb, 11);
    let late = format!("{:.6}", t.parse::<f64>().unwrap() + 0.5);
    let mut text = fs::read_to_string(&rgb).unwrap();
    text.push_str(&format!("{late} {f}\n"));
    fs::write(&rgb, text).unwrap();
    let o = run_ok(&["table", seq.to_str().unwrap(), "--frame-steps", "1,2"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    let said = stderr
        .lines()
        .filter(|l| l.contains("have no depth image"))
        .count();
    assert_eq!(said, 1, "{stderr}");
    // Six cells were tracked: 2 frame steps x naive, L1, L2.
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("| 1 |")).count(),
        3,
        "{stdout}"
    );
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("| 2 |")).count(),
        3,
        "{stdout}"
    );
}

/// `ecvo run --help` groups its options under headings, in this order, the most used
/// first in each.
#[test]
fn run_help_is_grouped() {
    let o = run_ok(&["run", "--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    // The option lines (`      --camera <CAMERA>`) and headings (`Input:`), in order.
    let lines: Vec<&str> = help
        .lines()
        .filter(|l| l.ends_with(':') && !l.starts_with(' ') || l.trim_start().starts_with("--"))
        .map(|l| {
            let l = l.trim_start();
            l.split([' ', '\n']).next().unwrap_or(l)
        })
        .collect();
    let at = |name: &str| {
        lines
            .iter()
            .position(|l| *l == name)
            .unwrap_or_else(|| panic!("`{name}` not in:\n{help}"))
    };
    let groups: [(&str, &[&str]); 5] = [
        ("Input:", &["--camera", "--max-frames", "--frame-step"]),
        ("Method:", &["--preset", "--mode", "--levels", "--tracking"]),
        (
            "Tuning:",
            &["--depth-noise", "--weighting", "--no-bilateral"],
        ),
        ("Output:", &["--out", "--plot-plane"]),
        ("Limits:", &["--threads", "--max-memory"]),
    ];
    // The headings in this order, each option under its heading, the listed ones in
    // this order.
    let mut last = 0;
    for (k, (heading, options)) in groups.iter().enumerate() {
        let h = at(heading);
        assert!(h >= last, "{heading} out of order:\n{help}");
        let end = groups.get(k + 1).map_or(lines.len(), |(next, _)| at(next));
        last = h;
        for opt in *options {
            let p = at(opt);
            assert!(
                p > last && p < end,
                "{opt} not in order under {heading}:\n{help}"
            );
            last = p;
        }
    }
}
