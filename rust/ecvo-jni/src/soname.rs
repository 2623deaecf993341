//! Whether the loaded `libecvo_jni.so` carries a `DT_SONAME`, read from its own ELF
//! headers in memory (`JNI_OnLoad` warns in logcat when it does not: Android's linker
//! identifies a library by it). Linux and Android only.

use std::ffi::{c_char, c_int, c_void};

#[repr(C)]
struct DlInfo {
    dli_fname: *const c_char,
    dli_fbase: *mut c_void,
    dli_sname: *const c_char,
    dli_saddr: *mut c_void,
}

unsafe extern "C" {
    // bionic's libdl (every API level), glibc's libc.
    fn dladdr(addr: *const c_void, info: *mut DlInfo) -> c_int;
}

const PT_DYNAMIC: u32 = 2;
const DT_NULL: usize = 0;
const DT_SONAME: usize = 14;
/// Dynamic entries read at most (a real table has a few dozen).
const MAX_DYNAMIC_ENTRIES: usize = 4096;

/// Whether the object that holds `addr` (a function of it) has a `DT_SONAME`; `None` when it
/// cannot be told (no object found, not an ELF image of this word size).
pub(crate) fn object_has_soname(addr: *const c_void) -> Option<bool> {
    let mut info = DlInfo {
        dli_fname: std::ptr::null(),
        dli_fbase: std::ptr::null_mut(),
        dli_sname: std::ptr::null(),
        dli_saddr: std::ptr::null_mut(),
    };
    // SAFETY: dladdr only writes `info`; a zero return means no object holds `addr`.
    if unsafe { dladdr(addr, &mut info) } == 0 || info.dli_fbase.is_null() {
        return None;
    }
    // SAFETY: `dli_fbase` is the load address of a mapped ELF object: its ELF header and
    // program headers are mapped (the first LOAD segment starts at file offset 0), and its
    // dynamic section is mapped at `base + p_vaddr` (shared objects and PIEs link at 0).
    unsafe { dynamic_has_soname(info.dli_fbase as *const u8) }
}

/// Walks the ELF header at `base`, finds `PT_DYNAMIC` and looks for `DT_SONAME` in it.
///
/// # Safety
///
/// `base` must be the load address of a mapped ELF object of this process.
unsafe fn dynamic_has_soname(base: *const u8) -> Option<bool> {
    // SAFETY (all reads): within the mapped headers and dynamic section, per the caller.
    unsafe {
        if std::slice::from_raw_parts(base, 4) != b"\x7fELF" {
            return None;
        }
        let wide = cfg!(target_pointer_width = "64");
        if *base.add(4) != if wide { 2 } else { 1 } {
            return None; // ELFCLASS64 / ELFCLASS32 must match this build
        }
        let read_word = |p: *const u8| -> usize {
            if wide {
                (p as *const u64).read_unaligned() as usize
            } else {
                (p as *const u32).read_unaligned() as usize
            }
        };
        let (phoff, phentsize, phnum) = if wide {
            (
                read_word(base.add(0x20)),
                (base.add(0x36) as *const u16).read_unaligned(),
                (base.add(0x38) as *const u16).read_unaligned(),
            )
        } else {
            (
                read_word(base.add(0x1c)),
                (base.add(0x2a) as *const u16).read_unaligned(),
                (base.add(0x2c) as *const u16).read_unaligned(),
            )
        };
        for i in 0..phnum as usize {
            let ph = base.add(phoff + i * phentsize as usize);
            if (ph as *const u32).read_unaligned() != PT_DYNAMIC {
                continue;
            }
            let vaddr = read_word(ph.add(if wide { 0x10 } else { 0x08 }));
            let dynamic = base.add(vaddr);
            let entry = if wide { 16 } else { 8 };
            for k in 0..MAX_DYNAMIC_ENTRIES {
                let tag = read_word(dynamic.add(k * entry));
                if tag == DT_NULL {
                    return Some(false);
                }
                if tag == DT_SONAME {
                    return Some(true);
                }
            }
            return None;
        }
        Some(false) // no dynamic section at all
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    unsafe extern "C" {
        fn malloc(size: usize) -> *mut c_void;
    }

    #[test]
    fn the_c_library_has_a_soname_and_this_test_executable_does_not() {
        // glibc's libc.so.6 is linked with -soname; an executable (PIE) never is.
        assert_eq!(object_has_soname(malloc as *const c_void), Some(true));
        assert_eq!(
            object_has_soname(object_has_soname as *const c_void),
            Some(false)
        );
    }
}
