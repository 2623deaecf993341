//! A derived copy of a TUM-layout sequence (`ecvo_io::derive`), as
//! `scripts/datasets/get-tum.sh` makes them:
//!
//! ```text
//! cargo run --release -p ecvo-io --example derive -- SRC DST [--half] [--gray] [--first N] [--first-pairs N]
//! ```
//!
//! SRC needs its `camera.json`. `--half`: the 320x240 copy of a 640x480 sequence (gray
//! = 2x2 mean, depth = 2x2 mean when all four agree within 3 %, else 0; intrinsics
//! halved as (c + 0.5) / 2 - 0.5). `--gray`: colour written as 8-bit gray. `--first
//! N`: the first N entries of each list; `--first-pairs N`: the first N colour/depth
//! pairs.

use std::path::PathBuf;
use std::process::ExitCode;

use ecvo_io::derive::{DeriveOptions, derive_sequence};

fn main() -> ExitCode {
    let mut paths: Vec<PathBuf> = Vec::new();
    let mut opts = DeriveOptions::default();
    let mut args = std::env::args_os().skip(1);
    while let Some(a) = args.next() {
        match a.to_str() {
            Some("--half") => opts.half = true,
            Some("--gray") => opts.gray = true,
            Some(flag @ ("--first" | "--first-pairs")) => {
                match args.next().and_then(|n| n.to_str()?.parse::<usize>().ok()) {
                    Some(n) if n > 0 && flag == "--first" => opts.first_entries = Some(n),
                    Some(n) if n > 0 => opts.first_pairs = Some(n),
                    _ => {
                        eprintln!("error: {flag} needs a positive number");
                        return ExitCode::from(2);
                    }
                }
            }
            Some(s) if s.starts_with("--") => {
                eprintln!("error: unknown option {s} (--half, --gray, --first N, --first-pairs N)");
                return ExitCode::from(2);
            }
            _ => paths.push(a.into()),
        }
    }
    let [src, dst] = paths.as_slice() else {
        eprintln!("usage: derive SRC DST [--half] [--gray] [--first N] [--first-pairs N]");
        return ExitCode::from(2);
    };
    match derive_sequence(src, dst, &opts) {
        Ok(r) => {
            println!(
                "{}: {} colour and {} depth images, {}x{}",
                dst.display(),
                r.rgb,
                r.depth,
                r.width,
                r.height
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
