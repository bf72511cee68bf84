//! The global allocator EKF2 needs (its C++ allocates through `ekf2_rust_alloc`): an
//! `embedded-alloc` linked-list heap over a static arena, counting its peak use and the
//! allocations made, so the bench can say how much heap EKF2 really takes and whether it
//! allocates after construction.

use core::alloc::{GlobalAlloc, Layout};
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use embedded_alloc::LlffHeap;

/// Arena size, bytes (in .bss; the report subtracts it from static RAM and gives it as
/// the heap). Chosen with margin over the measured peak (`ekf2.heap_peak_bytes`).
pub const ARENA_BYTES: usize = 64 * 1024;

pub struct Counted {
    heap: LlffHeap,
    peak: AtomicUsize,
    allocs: AtomicUsize,
}

#[global_allocator]
static HEAP: Counted =
    Counted { heap: LlffHeap::empty(), peak: AtomicUsize::new(0), allocs: AtomicUsize::new(0) };

// SAFETY: forwards to LlffHeap (a sound GlobalAlloc); only adds relaxed counters.
unsafe impl GlobalAlloc for Counted {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = self.heap.alloc(layout);
        self.allocs.fetch_add(1, Relaxed);
        self.peak.fetch_max(self.heap.used(), Relaxed);
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        self.heap.dealloc(ptr, layout)
    }
}

/// Hands the arena to the heap; call once, before the first allocation.
pub fn init() {
    static mut ARENA: [MaybeUninit<u8>; ARENA_BYTES] = [MaybeUninit::uninit(); ARENA_BYTES];
    // SAFETY: called once at boot; the arena is used by nothing else.
    unsafe { HEAP.heap.init(core::ptr::addr_of_mut!(ARENA) as usize, ARENA_BYTES) }
}

/// Peak bytes in use (allocator's own count, including its bookkeeping).
pub fn peak() -> usize {
    HEAP.peak.load(Relaxed)
}

/// Bytes in use now.
pub fn used() -> usize {
    HEAP.heap.used()
}

/// Allocations made so far.
pub fn allocs() -> usize {
    HEAP.allocs.load(Relaxed)
}
