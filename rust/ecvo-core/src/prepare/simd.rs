//! Run-time choice of the instruction set for the per-pixel kernels.
//!
//! The kernels are plain Rust written so that the compiler vectorises them: SSE2 on
//! x86_64 (4 lanes), NEON on aarch64 (4 lanes), both in the baseline of their
//! targets. On x86_64 [`multiversion!`] compiles a kernel a second time with AVX2
//! enabled (8 lanes) and calls that copy when the CPU has AVX2. FMA is not enabled
//! and Rust never contracts `a * b + c` on its own, so both copies perform the same
//! IEEE operations on every pixel and give the same bits.
//!
//! Why this and not a SIMD crate: the kernels stay plain, portable Rust (the same
//! source is the NEON build), there is no new dependency, and the bits cannot
//! depend on the path. Measured with `cargo bench -p ecvo-core --bench stages`,
//! `ECVO_NO_AVX2=1` against the default on the same machine, the AVX2 copies of the
//! bilateral filter and the normals make the whole preparation about 1.5x faster
//! (`docs/profile.md`); the other passes are memory-bound and are not duplicated.

/// Whether the AVX2 copies may run: the CPU has AVX2, and `ECVO_NO_AVX2` is unset
/// (to measure or test the baseline path on the same machine).
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx2() -> bool {
    use std::sync::OnceLock;
    static AVX2: OnceLock<bool> = OnceLock::new();
    #[cfg(test)]
    if BASELINE_ONLY.load(std::sync::atomic::Ordering::Relaxed) {
        return false;
    }
    *AVX2.get_or_init(|| {
        std::env::var_os("ECVO_NO_AVX2").is_none() && std::arch::is_x86_feature_detected!("avx2")
    })
}

/// Tests set this to run the baseline copies (every copy gives the same bits, so
/// tests running meanwhile are not affected).
#[cfg(test)]
pub(crate) static BASELINE_ONLY: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// Defines `pub(crate) fn $name($args) -> $ret` that calls `$body`'s
/// `#[inline(always)]` kernel `$kernel`, through an AVX2 copy when the CPU has it.
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
