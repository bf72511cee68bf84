//! Board: QEMU `mps2-an386` (ARM AN386, Cortex-M4F with FPU, 25 MHz).
//!
//! Hand-written minimal drivers for the CMSDK APB UART and SysTick: there is no
//! maintained PAC/HAL for this emulated FPGA board, and the firmware needs only
//! ~10 registers. Register layout: ARM CMSDK (DDI 0479), as QEMU models it
//! (`hw/char/cmsdk-apb-uart.c`).
//!
//! Wiring of the HIL setup (see `docs/hil-protocol.md`):
//! - UART0 (0x4000_4000, IRQ 0 RX / 1 TX): sensor records from the host (IMU + airspeed).
//! - UART1 (0x4000_5000, IRQ 2 RX / 3 TX): GPS receiver bytes (UBX or NMEA).
//! - UART2 (0x4000_6000, IRQ 4 RX / 5 TX): MAVLink v2 telemetry out.
//! - IRQ 12: combined UART overrun. IRQ 30 / 31 (not wired on AN386): software-pended
//!   "IMU data ready" task and telemetry task.
//!
//! QEMU's CMSDK UART has no FIFO (one byte each way) and no baud-rate timing: bytes
//! move as fast as the guest reads/writes them. A full host socket sets TXFULL, which
//! is how telemetry back-pressure shows up.
#![allow(clippy::missing_safety_doc)]

use core::ptr::{read_volatile, write_volatile};
use cortex_m::peripheral::{syst::SystClkSource, NVIC, SYST};

/// Core clock, Hz (QEMU mps2 `SYSCLK_FRQ`).
pub const CORE_HZ: u32 = 25_000_000;
/// Under `-icount shift=0` QEMU runs one instruction per ns of virtual time, so one
/// SysTick tick at 25 MHz (40 ns) is 40 instructions. These are instructions, not cycles.
pub const INSTRUCTIONS_PER_TICK: u32 = 1_000_000_000 / CORE_HZ;

/// AN386 external interrupts used by the firmware (names match the handlers).
#[allow(non_camel_case_types, clippy::upper_case_acronyms)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
#[allow(dead_code)] // the full AN386 map the firmware may use
pub enum interrupt {
    /// UART0 RX: sensor records (HIL); named for its job, as on every board.
    SENSOR_DATA = 0,
    /// UART0 TX (unused).
    UART0TX = 1,
    /// UART1 RX: GPS bytes.
    GPS_RX = 2,
    /// UART1 TX (unused).
    UART1TX = 3,
    /// UART2 RX (unused: telemetry uplink is ignored).
    UART2RX = 4,
    /// UART2 TX: telemetry ring drain.
    TELEMETRY_TX = 5,
    /// CMSDK TIMER0.
    TIMER0 = 8,
    /// Combined UART 0–2 overrun.
    UART_OVF = 12,
    /// Software-pended IMU processing (the "data ready" line of a real IMU).
    IMU_TASK = 30,
    /// Software-pended telemetry encoder (lowest priority).
    TELEMETRY_TASK = 31,
}

// SAFETY: the discriminants are valid AN386 external interrupt numbers (< 32).
unsafe impl cortex_m::interrupt::InterruptNumber for interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

/// The interrupt vector table (32 external IRQs on AN386); handlers not defined by
/// the firmware resolve to `DefaultHandler` through `qemu_device.x`.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
pub static __INTERRUPTS: [Vector; 32] = {
    extern "C" {
        fn SENSOR_DATA();
        fn UART0TX();
        fn GPS_RX();
        fn UART1TX();
        fn UART2RX();
        fn TELEMETRY_TX();
        fn TIMER0();
        fn UART_OVF();
        fn IMU_TASK();
        fn TELEMETRY_TASK();
    }
    const R: Vector = Vector { reserved: 0 };
    [
        Vector { handler: SENSOR_DATA },
        Vector { handler: UART0TX },
        Vector { handler: GPS_RX },
        Vector { handler: UART1TX },
        Vector { handler: UART2RX },
        Vector { handler: TELEMETRY_TX },
        R,
        R,
        Vector { handler: TIMER0 },
        R,
        R,
        R,
        Vector { handler: UART_OVF },
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        R,
        Vector { handler: IMU_TASK },
        Vector { handler: TELEMETRY_TASK },
    ]
};

/// One vector table entry.
#[derive(Clone, Copy)]
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: usize,
}

/// Interrupt priorities (lower value = more urgent; M4 implements the top 3 bits
/// on AN386, so use multiples of 0x20). RX byte handlers are most urgent: a CMSDK
/// UART holds a single byte. GPS RX outranks sensor RX: at equal priority the lower
/// IRQ number (UART0) would always win and a busy sensor line could starve GPS.
pub mod prio {
    /// GPS RX.
    pub const GPS_RX: u8 = 0x20;
    /// Sensor-record RX.
    pub const RX: u8 = 0x40;
    /// IMU processing (predict + update).
    pub const IMU: u8 = 0x60;
    /// Telemetry TX drain.
    pub const TX: u8 = 0x80;
    /// Telemetry encoding: lowest.
    pub const TELEMETRY: u8 = 0xE0;
}

const UART0: usize = 0x4000_4000;
const UART1: usize = 0x4000_5000;
const UART2: usize = 0x4000_6000;

// CMSDK APB UART register offsets and bits.
const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTSTATUS: usize = 0x0C; // write 1 to clear (INTCLEAR)
const BAUDDIV: usize = 0x10;
const STATE_TXFULL: u32 = 1 << 0;
const STATE_RXFULL: u32 = 1 << 1;
const STATE_RXOVR: u32 = 1 << 3;
const CTRL_TXEN: u32 = 1 << 0;
const CTRL_RXEN: u32 = 1 << 1;
const CTRL_TXIE: u32 = 1 << 2;
const CTRL_RXIE: u32 = 1 << 3;
const INT_TX: u32 = 1 << 0;
const INT_RX: u32 = 1 << 1;
const INT_RXOVR: u32 = 1 << 3;

/// A CMSDK APB UART. Owning a `Uart` is the right to touch its registers; each
/// instance is moved into exactly one interrupt context.
pub struct Uart {
    base: usize,
}

impl Uart {
    fn reg(&self, off: usize) -> *mut u32 {
        (self.base + off) as *mut u32
    }
    fn read(&self, off: usize) -> u32 {
        // SAFETY: `base` is a CMSDK UART of this board; registers are 32-bit aligned MMIO.
        unsafe { read_volatile(self.reg(off)) }
    }
    fn write(&self, off: usize, v: u32) {
        // SAFETY: as above.
        unsafe { write_volatile(self.reg(off), v) }
    }
    fn init(base: usize, ctrl: u32) -> Self {
        let u = Uart { base };
        u.write(CTRL, 0);
        u.write(BAUDDIV, 16); // minimum legal divider; QEMU ignores timing
        u.write(INTSTATUS, INT_TX | INT_RX | INT_RXOVR | (1 << 2));
        u.write(CTRL, ctrl);
        u
    }

    /// The received byte, if one is waiting. Clears the RX interrupt.
    #[inline]
    pub fn read_byte(&mut self) -> Option<u8> {
        self.write(INTSTATUS, INT_RX);
        if self.read(STATE) & STATE_RXFULL != 0 {
            Some(self.read(DATA) as u8)
        } else {
            None
        }
    }

    /// Whether a receive overrun happened since the last call (clears it).
    #[inline]
    pub fn take_overrun(&mut self) -> bool {
        let s = self.read(STATE);
        if s & STATE_RXOVR != 0 {
            self.write(STATE, STATE_RXOVR);
            self.write(INTSTATUS, INT_RXOVR);
            true
        } else {
            false
        }
    }

    /// Writes `b` if the transmitter can take it; `false` when TX is full.
    #[inline]
    pub fn try_write(&mut self, b: u8) -> bool {
        if self.read(STATE) & STATE_TXFULL != 0 {
            return false;
        }
        self.write(DATA, b as u32);
        true
    }

    /// Acknowledges the TX-empty interrupt.
    #[inline]
    pub fn clear_tx_irq(&mut self) {
        self.write(INTSTATUS, INT_TX);
    }
}

/// The board's peripherals, handed out once by [`init`].
pub struct Board {
    /// Sensor input (HIL records: IMU + airspeed).
    pub sensor: Uart,
    /// GPS receiver.
    pub gps: Uart,
    /// Telemetry out.
    pub telemetry: Uart,
}

/// Sets up the UARTs, SysTick (the instruction stopwatch) and NVIC priorities.
/// Interrupts are left masked in the NVIC until [`start`].
pub fn init(mut core: cortex_m::Peripherals) -> Board {
    core.SYST.set_clock_source(SystClkSource::Core);
    core.SYST.set_reload(0x00FF_FFFF);
    core.SYST.clear_current();
    core.SYST.enable_counter();
    // SAFETY: priorities are set before any of these interrupts is unmasked.
    unsafe {
        core.NVIC.set_priority(interrupt::SENSOR_DATA, prio::RX);
        core.NVIC.set_priority(interrupt::GPS_RX, prio::GPS_RX);
        core.NVIC.set_priority(interrupt::UART_OVF, prio::RX);
        core.NVIC.set_priority(interrupt::IMU_TASK, prio::IMU);
        core.NVIC.set_priority(interrupt::TELEMETRY_TX, prio::TX);
        core.NVIC.set_priority(interrupt::TELEMETRY_TASK, prio::TELEMETRY);
    }
    Board {
        sensor: Uart::init(UART0, CTRL_RXEN | CTRL_RXIE),
        gps: Uart::init(UART1, CTRL_RXEN | CTRL_RXIE),
        telemetry: Uart::init(UART2, CTRL_TXEN | CTRL_TXIE),
    }
}

/// Unmasks the firmware's interrupts. Call after every handler's context is in place.
pub fn start() {
    for irq in [
        interrupt::SENSOR_DATA,
        interrupt::GPS_RX,
        interrupt::UART_OVF,
        interrupt::IMU_TASK,
        interrupt::TELEMETRY_TX,
        interrupt::TELEMETRY_TASK,
    ] {
        // SAFETY: all handler contexts were installed by the caller (see main.rs).
        unsafe { NVIC::unmask(irq) };
    }
}

/// Free-running stopwatch in instructions (QEMU `-icount shift=0`; SysTick at 25 MHz,
/// 24-bit, wraps every 0.67 s of virtual time). Not cycles.
#[inline]
pub fn stopwatch() -> u32 {
    SYST::get_current()
}

/// Instructions elapsed since `start` (a [`stopwatch`] reading); valid for < 0.67 s.
#[inline]
pub fn elapsed(start: u32) -> u32 {
    (start.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF) * INSTRUCTIONS_PER_TICK
}

/// The defined state after a panic: interrupts off, UARTs quiet, then tell QEMU to
/// exit with a failure code (a real board resets through its watchdog instead).
pub fn fail_safe() -> ! {
    cortex_m::interrupt::disable();
    for base in [UART0, UART1, UART2] {
        // SAFETY: plain MMIO writes to this board's UART control registers.
        unsafe { write_volatile((base + CTRL) as *mut u32, 0) };
    }
    semihosting::process::exit(101)
}

/// Ends the emulation with `code` (tests and benches; a real board never exits).
pub fn exit(code: i32) -> ! {
    semihosting::process::exit(code)
}
