//! `vors-cam CAMERA_JSON ASSOCIATIONS`: runs the visual-odometry-rs tracker (the
//! library behind `vors_track`, unchanged settings: 6 levels, candidate threshold 7,
//! inverse-depth variance 1e-4) with the camera of a camera.json.
//!
//! ASSOCIATIONS has vors_track's format: `depth_stamp depth_path color_stamp color_path`
//! per line (paths relative to the file's folder, or absolute). Prints the TUM
//! trajectory (`stamp tx ty tz qx qy qz qw`, the first frame at the identity, stamps of
//! the depth images as vors_track does) to stdout, and to stderr one line
//! `vors-cam-ms FRAME THREAD_CPU_MS WALL_MS PROCESS_CPU_MS` per tracked frame: the CPU
//! time of the calling thread (`CLOCK_THREAD_CPUTIME_ID`), the wall time and the CPU time
//! of the whole process (`CLOCK_PROCESS_CPUTIME_ID`) of `Tracker::track` (building the
//! pyramids, the optimisation and, when the keyframe changes, its precomputation);
//! reading and decoding the PNGs is not counted. vors is single-threaded: the last line,
//! `vors-cam-threads MAX`, is the most threads `/proc/self/task` listed after any frame,
//! and the thread and process CPU times agree when it is 1.
//!
//! `vors-cam --decode-only CAMERA_JSON ASSOCIATIONS` reads and decodes the same images
//! and tracks nothing: the baseline to subtract from a whole-process count
//! (scripts/profile/insn-aarch64.sh).

use std::error::Error;
use std::path::Path;
use std::time::Instant;

use nalgebra::DMatrix;
use visual_odometry_rs::core::camera::Intrinsics;
use visual_odometry_rs::core::track::inverse_compositional::Config;
use visual_odometry_rs::dataset::tum_rgbd;
use visual_odometry_rs::misc::{helper, interop};

type Res<T> = Result<T, Box<dyn Error>>;

/// CPU time of `clock` (a thread or process CPU clock), milliseconds.
fn cpu_ms(clock: libc::clockid_t) -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec.
    let rc = unsafe { libc::clock_gettime(clock, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime({clock}) failed");
    ts.tv_sec as f64 * 1e3 + ts.tv_nsec as f64 * 1e-6
}

/// CPU time of the calling thread, milliseconds.
fn thread_cpu_ms() -> f64 {
    cpu_ms(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// CPU time of every thread of this process, milliseconds.
fn process_cpu_ms() -> f64 {
    cpu_ms(libc::CLOCK_PROCESS_CPUTIME_ID)
}

/// Threads of this process now (entries of /proc/self/task; 0 where it is missing).
fn thread_count() -> usize {
    std::fs::read_dir("/proc/self/task").map_or(0, |d| d.count())
}

/// Value of a numeric key in a flat JSON object (camera.json has no nesting).
fn json_number(text: &str, key: &str) -> Res<f64> {
    let pat = format!("\"{key}\"");
    let at = text.find(&pat).ok_or(format!("camera.json has no {key}"))?;
    let rest = text[at + pat.len()..].trim_start();
    let rest = rest.strip_prefix(':').ok_or("camera.json: ':' expected")?;
    let end = rest
        .find([',', '}'])
        .ok_or("camera.json: unterminated value")?;
    Ok(rest[..end].trim().parse()?)
}

fn read_images(depth: &Path, color: &Path) -> Res<(DMatrix<u16>, DMatrix<u8>)> {
    let (w, h, d) = helper::read_png_16bits(depth)?;
    let depth = DMatrix::from_row_slice(h, w, &d);
    let img = interop::matrix_from_image(image::open(color)?.to_luma());
    Ok((depth, img))
}

fn main() -> Res<()> {
    let mut args: Vec<String> = std::env::args().collect();
    let decode_only = args.get(1).is_some_and(|a| a == "--decode-only");
    if decode_only {
        args.remove(1);
    }
    if args.len() != 3 {
        return Err("usage: vors-cam [--decode-only] CAMERA_JSON ASSOCIATIONS".into());
    }
    let cam = std::fs::read_to_string(&args[1])?;
    let intrinsics = Intrinsics {
        principal_point: (json_number(&cam, "cx")? as _, json_number(&cam, "cy")? as _),
        focal: (json_number(&cam, "fx")? as _, json_number(&cam, "fy")? as _),
        skew: 0.0,
    };
    let depth_scale = json_number(&cam, "depth_scale")?;
    let assoc_path = Path::new(&args[2]);
    let dir = assoc_path.parent().unwrap_or(Path::new("."));
    let text = std::fs::read_to_string(assoc_path)?;
    let assoc = tum_rgbd::parse::associations(&text)?;
    if assoc.is_empty() {
        return Err("no associations".into());
    }
    let config = Config {
        nb_levels: 6,
        candidates_diff_threshold: 7,
        depth_scale: depth_scale as _,
        intrinsics,
        idepth_variance: 0.0001,
    };
    let (d0, i0) = read_images(
        &dir.join(&assoc[0].depth_file_path),
        &dir.join(&assoc[0].color_file_path),
    )?;
    if decode_only {
        for a in assoc.iter().skip(1) {
            read_images(&dir.join(&a.depth_file_path), &dir.join(&a.color_file_path))?;
        }
        return Ok(());
    }
    let t = Instant::now();
    let mut tracker = config.init(assoc[0].depth_timestamp, &d0, assoc[0].color_timestamp, i0);
    eprintln!("vors-cam-init-ms {:.3}", t.elapsed().as_secs_f64() * 1e3);
    println!("{:.6} 0 0 0 0 0 0 1", assoc[0].depth_timestamp);
    let mut threads = thread_count();
    for (k, a) in assoc.iter().enumerate().skip(1) {
        let (d, i) = read_images(&dir.join(&a.depth_file_path), &dir.join(&a.color_file_path))?;
        let (t, c, p) = (Instant::now(), thread_cpu_ms(), process_cpu_ms());
        tracker.track(a.depth_timestamp, &d, a.color_timestamp, i);
        let (cpu, proc_cpu) = (thread_cpu_ms() - c, process_cpu_ms() - p);
        let wall = t.elapsed().as_secs_f64() * 1e3;
        threads = threads.max(thread_count());
        eprintln!("vors-cam-ms {k} {cpu:.3} {wall:.3} {proc_cpu:.3}");
        let (stamp, pose) = tracker.current_frame();
        let tr = pose.translation.vector;
        let q = pose.rotation.into_inner().coords;
        println!(
            "{stamp:.6} {} {} {} {} {} {} {}",
            tr.x, tr.y, tr.z, q.x, q.y, q.z, q.w
        );
    }
    eprintln!("vors-cam-threads {threads}");
    Ok(())
}
