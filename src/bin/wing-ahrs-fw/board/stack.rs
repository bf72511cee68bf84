//! Stack high-water accounting (both boards): paint, fly, read back.
//!
//! cortex-m-rt (`paint-stack`) fills the stack region with `STACK_PAINT_VALUE` at
//! reset; the deepest word no longer holding it marks the high-water mark. The
//! firmware splits the figure in two (see `main.rs`):
//! - **boot**: read once after the contexts are built, just before interrupts are
//!   unmasked ([`end_of_boot`]), which then repaints everything below `main`'s
//!   stack pointer;
//! - **flight**: the high-water since that repaint — `main`'s idle frame plus the
//!   deepest nesting of interrupt handlers that actually happened.
//!
//! The whole figure (what must fit the budget) is the larger of the two.

use core::sync::atomic::{AtomicU32, Ordering::Relaxed};
use cortex_m_rt::STACK_PAINT_VALUE;

/// Only the top 64 KiB are scanned (the budget is 4 KiB; QEMU's RAM is 4 MiB).
const SCAN: usize = 64 * 1024;

static BOOT_BYTES: AtomicU32 = AtomicU32::new(0);
static IDLE_BYTES: AtomicU32 = AtomicU32::new(0);

fn bounds() -> (usize, usize) {
    extern "C" {
        static _stack_start: u32;
        static _stack_end: u32;
    }
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let end = core::ptr::addr_of!(_stack_end) as usize;
    (end.max(top - SCAN), top)
}

/// Bytes of stack used since the last paint (reset or [`repaint_below_caller`]).
pub fn high_water() -> usize {
    let (mut a, top) = bounds();
    while a < top {
        // SAFETY: [bottom, top) is this board's stack region (inside its RAM); word-aligned.
        if unsafe { core::ptr::read_volatile(a as *const u32) } != STACK_PAINT_VALUE {
            break;
        }
        a += 4;
    }
    top - a
}

/// Paints the free stack below the caller's frame (everything under the current
/// stack pointer). Interrupts must still be masked: nothing else may use that memory.
#[inline(never)]
pub fn repaint_below_caller() {
    let (bottom, _) = bounds();
    // In assembly: the limit must be the stack pointer *after* this function's
    // prologue, and the loop must not touch the stack itself.
    // SAFETY: [bottom, SP) is unused stack of this board (interrupts masked, single
    // core, no red zone on ARM); word-aligned stores of the paint value harm nothing.
    unsafe {
        core::arch::asm!(
            "mov {end}, sp",
            "2:",
            "cmp {a}, {end}",
            "bhs 3f",
            "str {v}, [{a}], #4",
            "b 2b",
            "3:",
            a = inout(reg) bottom => _,
            end = out(reg) _,
            v = in(reg) STACK_PAINT_VALUE,
            options(nostack),
        );
    }
}

/// End of boot: records the boot high-water and `main`'s idle depth (`main_sp` is
/// `main`'s stack pointer, constant while it idles), then repaints below it so that
/// the flight is measured on its own. Call from `main` with interrupts still masked.
#[inline(always)]
pub fn end_of_boot(main_sp: u32) {
    BOOT_BYTES.store(high_water() as u32, Relaxed);
    let (_, top) = bounds();
    IDLE_BYTES.store((top - main_sp as usize) as u32, Relaxed);
    repaint_below_caller();
}

/// Stack figures, bytes.
#[derive(Clone, Copy, Debug)]
pub struct Usage {
    /// High-water over boot and flight: what must fit.
    pub whole: u32,
    /// Boot alone (reset → interrupts unmasked).
    pub boot: u32,
    /// `main`'s frame while it idles (under every interrupt).
    pub main_idle: u32,
    /// Below `main`'s idle frame during the flight: the interrupt handlers, nested.
    pub isr: u32,
}

/// The figures so far.
pub fn usage() -> Usage {
    let boot = BOOT_BYTES.load(Relaxed);
    let main_idle = IDLE_BYTES.load(Relaxed);
    let flight = high_water() as u32;
    Usage { whole: boot.max(flight), boot, main_idle, isr: flight.saturating_sub(main_idle) }
}
