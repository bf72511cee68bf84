//! Board abstraction: the only code that touches hardware.
//!
//! A board module provides (same names on every board):
//! - `init(cortex_m::Peripherals) -> Board` with fields `sensor` (IMU sample source;
//!   on QEMU the HIL record UART), `gps` and `telemetry` (UARTs with `read_byte`,
//!   `take_overrun`, `try_write`, `clear_tx_irq`), and `start()` to unmask interrupts;
//! - `stopwatch()` / `elapsed(start)` for cost measurement, in the board's unit:
//!   instructions on QEMU (`-icount`), CPU cycles on the F405 (DWT);
//! - `fail_safe() -> !` (the panic state) and `exit(code) -> !`;
//! - (shared, in [`stack`]) stack painting and high-water accounting;
//! - the `interrupt` enum for cortex-m-rt's `#[interrupt]` handler names, with the
//!   same variant names on every board (so the task-raising helpers below are shared):
//!   `SENSOR_DATA` is the sensor context (HIL record UART on QEMU, IMU data ready on
//!   the F405); the other UART names are the QEMU board's, reused by the F405.
//!
//! The estimator and the tasks in `main.rs` never see registers.

#[cfg(all(feature = "board-qemu", feature = "board-f405"))]
compile_error!("choose one board: `board-qemu` or `board-f405`");

#[cfg(not(feature = "board-f405"))]
mod qemu;
#[cfg(not(feature = "board-f405"))]
pub use qemu::*;

// STM32F405 flight controller (docs/board-f405.md): SPI IMU + EXTI data-ready, GPS and
// telemetry USARTs, exposing the same names as `qemu.rs`.
#[cfg(feature = "board-f405")]
mod f405;
#[cfg(feature = "board-f405")]
pub use f405::*;

pub mod stack;

use cortex_m::peripheral::NVIC;

/// Raises the IMU processing interrupt (the data-ready line; a complete HIL record on QEMU).
#[inline]
pub fn pend_imu() {
    NVIC::pend(interrupt::IMU_TASK);
}

/// Raises the telemetry encoder interrupt.
#[inline]
pub fn pend_telemetry() {
    NVIC::pend(interrupt::TELEMETRY_TASK);
}

/// Kicks the telemetry transmitter (its ISR drains the ring).
#[inline]
pub fn pend_telemetry_tx() {
    NVIC::pend(interrupt::TELEMETRY_TX);
}
