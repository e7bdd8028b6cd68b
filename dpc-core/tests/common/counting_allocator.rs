//! A global allocator that counts the allocations of each thread, for the tests that prove a
//! path allocation-free (`dpc-core/tests/bdf_alloc.rs`, `tests/dpc_allocations.rs`). The count
//! is per thread: the test harness and other tests allocate on their own threads at the same
//! time (the harness's main thread did, 4 allocations in a CI run under load), so a global
//! count is not a test's count. It also keeps the largest single allocation of each thread, for
//! the tests that prove a path free of dense `n x n` matrices (`dpc-core/tests/sparse_setup.rs`).
#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    /// Allocations (and reallocations) made by this thread.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    /// The largest allocation (or reallocation) this thread has made, in bytes.
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

/// The largest single allocation, in bytes, this thread has made since the last
/// [`reset_largest_allocation`].
pub fn largest_allocation() -> usize {
    LARGEST.with(|c| c.get())
}

/// Forget the largest allocation so far (the next [`largest_allocation`] reads from here on).
pub fn reset_largest_allocation() {
    LARGEST.with(|c| c.set(0));
}

/// Allocations this thread has made so far.
pub fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

fn count_one(size: usize) {
    // During thread teardown the slot may be gone: such allocations are not a test's.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    let _ = LARGEST.try_with(|c| c.set(c.get().max(size)));
}

// SAFETY: forwards to the system allocator and only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one(layout.size());
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one(new_size);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;
