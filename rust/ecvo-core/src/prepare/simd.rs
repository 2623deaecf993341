//! Run-time choice of the instruction set for the per-pixel kernels.
//!
//! The kernels are plain Rust written so that the compiler vectorises them: SSE2 on
//! x86_64 (4 lanes), NEON on aarch64 (4 lanes), both in the baseline of their
//! targets. On x86_64 [`multiversion!`] compiles a kernel twice more, with AVX2
//! enabled (8 lanes) and with AVX-512 (F, VL, BW, DQ: 16 lanes and 32 vector
//! registers), and calls the widest copy the CPU has. FMA is not enabled and Rust
//! never contracts `a * b + c` on its own, so every copy performs the same IEEE
//! operations on every pixel and gives the same bits.
//!
//! Why this and not a SIMD crate: the kernels stay plain, portable Rust (the same
//! source is the NEON build), there is no new dependency, and the bits cannot
//! depend on the path. Measured with `cargo bench -p ecvo-bench --bench stages`,
//! `ECVO_NO_AVX2=1` against the default on the same machine, the AVX2 copies of the
//! bilateral filter and the normals make the whole preparation about 1.5x faster;
//! `ECVO_NO_AVX512=1` against the default on an AVX-512 CPU (AMD EPYC, Zen 4), the
//! AVX-512 copies make `prepare/320x180` about 1.5x faster again (`docs/profile-passes.md`).

/// The widest copies this CPU may run: 0 the baseline, 1 AVX2 (the CPU has it and
/// `ECVO_NO_AVX2` is unset), 2 AVX-512 (also F, VL, BW and DQ, and `ECVO_NO_AVX512`
/// unset). The variables measure or test the narrower paths on the same machine.
#[cfg(target_arch = "x86_64")]
fn widest() -> u8 {
    use std::sync::OnceLock;
    static WIDEST_CPU: OnceLock<u8> = OnceLock::new();
    let cpu = *WIDEST_CPU.get_or_init(|| {
        let off = |v: &str| std::env::var_os(v).is_some();
        let avx2 = !off("ECVO_NO_AVX2") && std::arch::is_x86_feature_detected!("avx2");
        let avx512 = avx2
            && !off("ECVO_NO_AVX512")
            && std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512dq");
        avx2 as u8 + avx512 as u8
    });
    #[cfg(test)]
    let cpu = cpu.min(WIDEST.load(std::sync::atomic::Ordering::Relaxed));
    cpu
}

/// Whether the AVX2 copies may run ([`widest`]).
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx2() -> bool {
    widest() >= 1
}

/// Whether the AVX-512 copies may run ([`widest`]).
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx512() -> bool {
    widest() >= 2
}

/// The instruction set of the widest kernel copies this process runs: `"avx512"`,
/// `"avx2"` or `"sse2"` on x86_64 (after `ECVO_NO_AVX512` and `ECVO_NO_AVX2`),
/// `"neon"` on aarch64, `"portable"` elsewhere. Every path gives the same poses; this
/// says which one a timing measured.
pub fn path_name() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        ["sse2", "avx2", "avx512"][widest() as usize]
    }
    #[cfg(target_arch = "aarch64")]
    {
        "neon"
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        "portable"
    }
}

/// Tests lower this to run the narrower copies: 0 the baseline only, 1 at most AVX2,
/// 2 (the default) any. Every copy gives the same bits, so tests running meanwhile
/// are not affected.
#[cfg(test)]
pub(crate) static WIDEST: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(2);

/// Runs `f(name)` with each copy in turn as the widest allowed (the CPU may lack the
/// wider ones: then the widest it has runs), then allows them all again.
#[cfg(test)]
pub(crate) fn on_each_path(mut f: impl FnMut(&str)) {
    use std::sync::atomic::Ordering;
    for (k, name) in ["baseline", "avx2", "avx512"].into_iter().enumerate() {
        WIDEST.store(k as u8, Ordering::Relaxed);
        f(name);
    }
    WIDEST.store(2, Ordering::Relaxed);
}

/// Defines `pub(crate) fn $name($args) -> $ret` that calls `$body`'s
/// `#[inline(always)]` kernel `$kernel`, through an AVX-512 or AVX2 copy when the CPU
/// has it.
macro_rules! multiversion {
    ($(#[$m:meta])* fn $name:ident($($a:ident: $t:ty),* $(,)?) $(-> $ret:ty)? = $kernel:ident;) => {
        $(#[$m])*
        pub(crate) fn $name($($a: $t),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                unsafe fn avx2($($a: $t),*) $(-> $ret)? {
                    $kernel($($a),*)
                }
                #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
                unsafe fn avx512($($a: $t),*) $(-> $ret)? {
                    $kernel($($a),*)
                }
                if $crate::prepare::simd::avx512() {
                    // SAFETY: the CPU has these features (checked at run time).
                    return unsafe { avx512($($a),*) };
                }
                if $crate::prepare::simd::avx2() {
                    // SAFETY: the CPU has AVX2 (checked at run time just above).
                    return unsafe { avx2($($a),*) };
                }
            }
            $kernel($($a),*)
        }
    };
}
pub(crate) use multiversion;
