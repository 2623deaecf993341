//! Peak RSS of one JNI tracker per size: `nativeInit`'s path (`ecvo_jni::handles`)
//! with the app's settings (phone preset, L2, live, 2 threads, point cloud), two
//! pushed frames, then release. One size per process, so that the peaks do not mix:
//!
//! ```text
//! for s in 640x480 1280x720 1920x1080 2560x1440 4096x2160 4096x4096; do
//!   cargo run -q --release -p ecvo-jni --example rss -- ${s%x*} ${s#*x}
//! done
//! ```
//!
//! A third argument sets the budget in MB (e.g. `1280 720 2048`). Prints the size, `nativeMemoryNeeded`, whether init accepted it under the default
//! budget, the peak RSS (`VmHWM`) after two frames and the RSS after release. The
//! allocator is the process's: glibc malloc on a Linux host.

use ecvo_jni::InitArgs;
use ecvo_jni::handles::{flush, open, push, release};

fn status(key: &str) -> usize {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<usize>().ok())
        .map_or(0, |kb| kb << 10)
}

fn main() {
    let mut a = std::env::args()
        .skip(1)
        .map(|v| v.parse::<i32>().expect("WIDTH HEIGHT"));
    let (w, h) = (a.next().expect("WIDTH"), a.next().expect("HEIGHT"));
    // An optional third argument: the budget in MB (`nativeSetMemoryBudget`).
    if let Some(mb) = a.next() {
        ecvo_jni::set_memory_budget(i64::from(mb) << 20).expect("a positive budget");
    }
    let args = InitArgs::app(w, h);
    let mb = |b: usize| b as f64 / (1 << 20) as f64;
    let need = args.memory_needed().expect("valid settings");
    let start = status("VmRSS:");
    match open(&args) {
        Err(e) => println!("{w}x{h}: need {:.1} MB, refused at init: {e:?}", mb(need)),
        Ok(handle) => {
            let n = (w * h) as usize;
            for k in 0..2usize {
                let depth: Vec<u16> = (0..n).map(|i| 900 + ((i * 7 + k) % 300) as u16).collect();
                let gray: Vec<u8> = (0..n).map(|i| ((i * 13 + k * 3) % 251) as u8).collect();
                push(handle, 1_000_000 + k as i64 * 33_000_000, &depth, &gray).expect("frame");
            }
            flush(handle).expect("flush");
            let peak = status("VmHWM:");
            release(handle);
            println!(
                "{w}x{h}: need {:.1} MB, accepted; RSS at start {:.1} MB, peak {:.1} MB after 2 frames, {:.1} MB after release",
                mb(need),
                mb(start),
                mb(peak),
                mb(status("VmRSS:"))
            );
        }
    }
}
