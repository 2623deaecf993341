//! A PNG whose colour profile (iCCP) inflates to 256 MiB: the binary tracks the
//! sequence without inflating it. Alone in its test binary, so that the children's
//! peak RSS that `getrusage` reports is this run's.

#[path = "it/common/mod.rs"]
mod common;

use std::fs;

use common::png::{iccp_bomb, insert_after_ihdr};
use common::{entry, mini_sequence, run_within, temp_dir};

#[test]
fn an_iccp_bomb_is_not_inflated() {
    let dir = temp_dir("iccp");
    let seq = mini_sequence(&dir, 3);
    let (_, rgb) = entry(&seq.join("rgb.txt"), 1);
    let png = fs::read(seq.join(&rgb)).unwrap();
    let bomb = iccp_bomb(256 << 20);
    assert!(
        bomb.len() < 1 << 20,
        "the bomb is small: {} bytes",
        bomb.len()
    );
    fs::write(seq.join(&rgb), insert_after_ihdr(&png, &bomb)).unwrap();
    let out = dir.join("out");
    let o = run_within(
        &["run", seq.to_str().unwrap(), "--out", out.to_str().unwrap()],
        30,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // SAFETY: getrusage writes the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) },
        0
    );
    let peak_mb = usage.ru_maxrss / 1024; // kilobytes on Linux
    assert!(
        peak_mb < 128,
        "peak RSS {peak_mb} MB: the profile was inflated"
    );
}
