//! The harness's memory limit, part of every fuzz target (and of the library's test of the
//! seeds, `crates/morphkit/tests/fuzz_seeds.rs`): a global allocator that refuses any
//! allocation taking the bytes live at once over [`LIMIT_BYTES`].
//!
//! A refused allocation returns null. A fallible one (`try_reserve`, as the readers use for
//! what a file's counts size) becomes the reader's error; an infallible one aborts the
//! process (`handle_alloc_error`), which libFuzzer reports as a crash ("deadly signal"):
//! a reader that lets a file's counts size an allocation without asking is found whatever the
//! machine's memory. libFuzzer's own `-malloc_limit_mb` needs a sanitizer's malloc hooks and
//! `-rss_limit_mb` a process that lives to be measured, so they are passed too (`run.sh`),
//! but this is the limit that holds with `-s none`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The most bytes live at once: 2 GiB, half of the glTF reader's 4 GiB decoding budget, so
/// that a file the budget lets through still meets the limit when it is near the budget.
pub const LIMIT_BYTES: usize = 2 << 30;

/// Bytes live now.
static LIVE: AtomicUsize = AtomicUsize::new(0);

/// Counts `n` more bytes live, unless that goes over [`LIMIT_BYTES`].
fn take(n: usize) -> bool {
    LIVE.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |live| {
        live.checked_add(n).filter(|&t| t <= LIMIT_BYTES)
    })
    .is_ok()
}

fn give(n: usize) {
    LIVE.fetch_sub(n, Ordering::Relaxed);
}

/// The system allocator within [`LIMIT_BYTES`] (see the [module documentation](self)).
pub struct Limited;

// SAFETY: every call is passed to `System` unchanged, or refused with null before it.
unsafe impl GlobalAlloc for Limited {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !take(layout.size()) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            give(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !take(layout.size()) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            give(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        give(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && !take(new_size - old) {
            return std::ptr::null_mut();
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                give(new_size - old);
            }
        } else if new_size < old {
            give(old - new_size);
        }
        p
    }
}
