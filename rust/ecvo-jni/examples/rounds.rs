//! Native memory after release, without a JVM: ROUNDS rounds of TRACKERS trackers
//! (`nativeInit`'s path with the app's settings: phone preset, L2, live, 2 threads,
//! point cloud), one frame pushed into each, all released; after each round the
//! process's RSS and where it is, from `/proc/self/smaps`:
//!
//! ```text
//! cargo run --release -p ecvo-jni --example rounds -- [TRACKERS=10] [ROUNDS=30] [WIDTH=320] [HEIGHT=240]
//! ```
//!
//! Columns: RSS; the anonymous memory in mappings of at most 8 MiB + 4 KiB (thread
//! stacks and their guard pages, malloc's per-thread arenas, 64 MiB reservations) and in
//! larger ones; `[heap]` (brk); the number of mappings; the process's threads. `TRIM=1`
//! calls glibc's `malloc_trim(0)` after each round on top of what release does.

use ecvo_jni::InitArgs;
use ecvo_jni::handles::{flush, open, push, release};

fn status_kb(key: &str) -> usize {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// (anon RSS kB in mappings up to 8 MiB + 4 KiB, in larger ones, [heap] RSS kB, mappings)
fn smaps() -> (usize, usize, usize, usize) {
    let text = std::fs::read_to_string("/proc/self/smaps").unwrap_or_default();
    let (mut small, mut large, mut heap, mut maps) = (0, 0, 0, 0);
    let (mut size_kb, mut name) = (0usize, String::new());
    for line in text.lines() {
        let mut f = line.split_whitespace();
        let first = f.next().unwrap_or("");
        if first.contains('-') && !first.ends_with(':') {
            maps += 1;
            let (a, b) = first.split_once('-').unwrap();
            let (a, b) = (
                usize::from_str_radix(a, 16).unwrap_or(0),
                usize::from_str_radix(b, 16).unwrap_or(0),
            );
            size_kb = (b - a) >> 10;
            name = f.nth(4).unwrap_or("").to_string();
        } else if first == "Rss:" {
            let kb: usize = f.next().and_then(|v| v.parse().ok()).unwrap_or(0);
            if name == "[heap]" {
                heap += kb;
            } else if name.is_empty() {
                if size_kb <= 8196 {
                    small += kb;
                } else {
                    large += kb;
                }
            }
        }
    }
    (small, large, heap, maps)
}

#[cfg(target_env = "gnu")]
unsafe extern "C" {
    /// glibc: gives free heap memory back to the system (all arenas, also inside them).
    fn malloc_trim(pad: usize) -> i32;
}

fn main() {
    let trim = std::env::var("TRIM").is_ok_and(|v| v == "1");
    let mut a = std::env::args()
        .skip(1)
        .map(|v| v.parse::<usize>().expect("a number"));
    let trackers = a.next().unwrap_or(10);
    let rounds = a.next().unwrap_or(30);
    let (w, h) = (a.next().unwrap_or(320), a.next().unwrap_or(240));
    let args = InitArgs::app(w as i32, h as i32);
    let n = w * h;
    let depth: Vec<u16> = (0..n).map(|i| 900 + ((i * 7) % 300) as u16).collect();
    let gray: Vec<u8> = (0..n).map(|i| ((i * 13) % 251) as u8).collect();
    let mb = |kb: usize| kb as f64 / 1024.0;
    println!("round  rss_MB  anon_small_MB  anon_large_MB  heap_MB  mappings  threads");
    let (s, l, hp, m) = smaps();
    println!(
        "{:>5}  {:>6.1}  {:>13.1}  {:>13.1}  {:>7.1}  {:>8}  {:>7}",
        0,
        mb(status_kb("VmRSS:")),
        mb(s),
        mb(l),
        mb(hp),
        m,
        status_kb("Threads:")
    );
    for round in 1..=rounds {
        let handles: Vec<i64> = (0..trackers).map(|_| open(&args).expect("init")).collect();
        for &hd in &handles {
            push(hd, 1_000_000 + round as i64 * 33_000_000, &depth, &gray).expect("frame");
            flush(hd).expect("flush");
        }
        for hd in handles {
            release(hd);
        }
        #[cfg(target_env = "gnu")]
        if trim {
            // SAFETY: malloc_trim only walks glibc's own arenas.
            unsafe { malloc_trim(0) };
        }
        let (s, l, hp, m) = smaps();
        println!(
            "{:>5}  {:>6.1}  {:>13.1}  {:>13.1}  {:>7.1}  {:>8}  {:>7}",
            round,
            mb(status_kb("VmRSS:")),
            mb(s),
            mb(l),
            mb(hp),
            m,
            status_kb("Threads:")
        );
    }
}
