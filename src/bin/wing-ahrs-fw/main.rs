//! wing-ahrs firmware: the estimator in the 100 Hz IMU interrupt of a Cortex-M4F board.
#![no_std]
#![no_main]

mod board;

use board::interrupt;
use cortex_m_rt::{entry, interrupt};
use defmt_semihosting as _;

#[entry]
fn main() -> ! {
    let core = cortex_m::Peripherals::take().unwrap();
    let _b = board::init(core);
    defmt::info!("wing-ahrs-fw: boot");
    board::start();
    board::exit(0)
}

#[interrupt]
fn UART0RX() {}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    board::fail_safe()
}
