//! The library's global allocator: every allocation of at least [`LARGE`] bytes (frames,
//! frame pools, scratch planes, clouds) is an anonymous mapping of its own, unmapped when
//! it is freed; smaller ones go to the C library's `malloc` ([`System`]).
//!
//! Why: a tracker's memory is mostly a few hundred blocks of 10 kB to 1 MB, allocated on
//! its stage and compute threads. glibc serves them from per-thread arenas and, once a
//! large block has been freed, raises its mmap threshold (up to 32 MiB), so later frames
//! come from the arenas too; what a released tracker freed there stays resident (the top
//! of each arena is not trimmed, even by `malloc_trim`). `--example rounds` (10 trackers
//! x 30 rounds, one frame each, released each round) measured RSS growing from 6 MB after
//! round 1 to 39-46 MB after round 30, in 15 arenas of 2-3.5 MB each; with a fixed
//! threshold (`MALLOC_MMAP_THRESHOLD_`) it stayed at 5-6 MB. Mapping the large blocks
//! here gives the same result with any C library (Android's bionic included), without
//! changing the `malloc` settings of the process the library is loaded into.
//!
//! The bytes outstanding and their peak are counted ([`outstanding`], [`peak`]) for the
//! memory tests: a test binary cannot install a counting allocator of its own beside
//! this one.
//! Unix only (`mmap`); elsewhere the library keeps the default allocator.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Allocations of at least this many bytes (and an alignment of at most 4 KiB) are
/// mappings of their own: glibc's own default mmap threshold, before it adapts.
pub const LARGE: usize = 128 << 10;

/// The smallest page size of the targets (larger pages are multiples of it, and the
/// kernel rounds lengths up to the real page size).
const PAGE: usize = 4096;

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// Bytes allocated through the library's allocator and not yet freed.
pub fn outstanding() -> usize {
    CURRENT.load(Ordering::Relaxed)
}

/// The highest [`outstanding`] since the last [`reset_peak`].
pub fn peak() -> usize {
    PEAK.load(Ordering::Relaxed)
}

/// Starts a new [`peak`] from the bytes outstanding now.
pub fn reset_peak() {
    PEAK.store(outstanding(), Ordering::Relaxed);
}

fn grow(n: usize) {
    let now = CURRENT.fetch_add(n, Ordering::Relaxed) + n;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

fn shrink(n: usize) {
    CURRENT.fetch_sub(n, Ordering::Relaxed);
}

/// Large blocks mapped, small ones from `malloc`; see the module's documentation.
pub struct Blocks;

fn mapped(size: usize, align: usize) -> bool {
    size >= LARGE && align <= PAGE
}

fn map(size: usize) -> *mut u8 {
    // SAFETY: a new private anonymous mapping; no existing memory is touched.
    let p = unsafe {
        libc::mmap(
            std::ptr::null_mut(),
            size,
            libc::PROT_READ | libc::PROT_WRITE,
            libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
            -1,
            0,
        )
    };
    if p == libc::MAP_FAILED {
        std::ptr::null_mut()
    } else {
        p.cast()
    }
}

/// # Safety
///
/// `p` and `size` are a block that [`map`] returned (or [`remap`] resized).
unsafe fn unmap(p: *mut u8, size: usize) {
    // SAFETY: the caller passes a whole mapping of ours.
    unsafe { libc::munmap(p.cast(), size) };
}

// SAFETY: small layouts are passed unchanged to `System`, which upholds the contract;
// large ones are fresh private mappings (page-aligned, so any alignment up to 4 KiB
// holds, and zeroed), unmapped with the size of the layout they were made for. Whether
// a block is mapped depends only on its layout, which the caller must pass back
// unchanged, so each block is freed by the allocator that made it. The counters are
// atomics and do not allocate.
unsafe impl GlobalAlloc for Blocks {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = if mapped(layout.size(), layout.align()) {
            map(layout.size())
        } else {
            // SAFETY: the caller's layout contract, passed on.
            unsafe { System.alloc(layout) }
        };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = if mapped(layout.size(), layout.align()) {
            // New anonymous mappings are zero-filled.
            map(layout.size())
        } else {
            // SAFETY: as for `alloc`.
            unsafe { System.alloc_zeroed(layout) }
        };
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if mapped(layout.size(), layout.align()) {
            // SAFETY: a large layout: `ptr` is a mapping of `layout.size()` bytes.
            unsafe { unmap(ptr, layout.size()) };
        } else {
            // SAFETY: a small layout: `ptr` came from `System` with it.
            unsafe { System.dealloc(ptr, layout) };
        }
        shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let (old_mapped, new_mapped) = (
            mapped(layout.size(), layout.align()),
            mapped(new_size, layout.align()),
        );
        let p = if !old_mapped && !new_mapped {
            // SAFETY: both small: `System`'s block, resized by `System`.
            unsafe { System.realloc(ptr, layout, new_size) }
        } else {
            // Linux only: the libc crate does not declare `mremap` for Android (bionic
            // has it; Android takes the copy below).
            #[cfg(target_os = "linux")]
            if old_mapped && new_mapped {
                // SAFETY: both large: `ptr` is our mapping of `layout.size()` bytes,
                // moved or resized whole.
                let q = unsafe {
                    libc::mremap(ptr.cast(), layout.size(), new_size, libc::MREMAP_MAYMOVE)
                };
                return if q == libc::MAP_FAILED {
                    std::ptr::null_mut()
                } else {
                    shrink(layout.size());
                    grow(new_size);
                    q.cast()
                };
            }
            // One side mapped and the other not: a new block, the bytes copied, the old
            // block freed (what `GlobalAlloc::realloc` does by default).
            // SAFETY: `new_size` is non-zero and, rounded to the alignment, does not
            // overflow (the caller's contract); the layouts match the blocks.
            unsafe {
                let new_layout = Layout::from_size_align_unchecked(new_size, layout.align());
                let q = self.alloc(new_layout);
                if !q.is_null() {
                    std::ptr::copy_nonoverlapping(ptr, q, layout.size().min(new_size));
                    self.dealloc(ptr, layout);
                }
                return q;
            }
        };
        if !p.is_null() {
            shrink(layout.size());
            grow(new_size);
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn large_blocks_are_mapped_zeroed_and_resized_with_their_bytes() {
        // Installed as this test binary's allocator too (lib.rs), so these go through
        // `Blocks` either way; called directly here to see each path.
        let a = Blocks;
        let big = Layout::from_size_align(LARGE, 64).unwrap();
        // SAFETY: non-zero layouts; every block is freed with the layout it has.
        unsafe {
            let p = a.alloc_zeroed(big);
            assert!(!p.is_null());
            assert_eq!(p as usize % PAGE, 0, "a mapping is page-aligned");
            assert!(std::slice::from_raw_parts(p, LARGE).iter().all(|&b| b == 0));
            for i in 0..LARGE {
                *p.add(i) = (i % 251) as u8;
            }
            // Large to larger (mremap), to small (copy into malloc), to large again.
            let p = a.realloc(p, big, 3 * LARGE);
            assert!((0..LARGE).all(|i| *p.add(i) == (i % 251) as u8));
            let big3 = Layout::from_size_align(3 * LARGE, 64).unwrap();
            let p = a.realloc(p, big3, 1000);
            assert!((0..1000).all(|i| *p.add(i) == (i % 251) as u8));
            let small = Layout::from_size_align(1000, 64).unwrap();
            let p = a.realloc(p, small, LARGE + 1);
            assert!((0..1000).all(|i| *p.add(i) == (i % 251) as u8));
            a.dealloc(p, Layout::from_size_align(LARGE + 1, 64).unwrap());
        }
    }

    #[test]
    fn alignments_above_a_page_go_to_malloc() {
        assert!(mapped(LARGE, PAGE));
        assert!(!mapped(LARGE, 2 * PAGE));
        assert!(!mapped(LARGE - 1, 8));
        let l = Layout::from_size_align(LARGE, 2 * PAGE).unwrap();
        // SAFETY: a non-zero layout, freed with itself.
        unsafe {
            let p = Blocks.alloc(l);
            assert_eq!(p as usize % (2 * PAGE), 0);
            Blocks.dealloc(p, l);
        }
    }
}
