//! Board: STM32F405RG flight controller with an MPU-6000 on SPI1 — the Matek
//! F405-Wing / F405-SE / F405-WTE pin map (docs/board-f405.md gives the sources:
//! ArduPilot `hwdef/MatekF405-Wing/hwdef.dat`, INAV `target/MATEKF405SE/target.h`).
//!
//! Same names as `../qemu.rs` so `main.rs` is board-neutral. Wiring:
//! - MPU-6000: SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI), CS PA4, INT (data ready) PC4 →
//!   EXTI4, which is the sensor context's vector (`SENSOR_DATA`; on QEMU the same name
//!   is the UART0 RX vector of the HIL sensor records): at 100 Hz it reads the sample over SPI ([`Imu::read`])
//!   and raises `IMU_TASK` (CAN2_RX0, software-pended) exactly as a completed HIL
//!   record does on QEMU.
//! - GPS: UART4 (PA0 TX, PA1 RX) = ArduPilot SERIAL3, its default GPS port; RX
//!   interrupt → `UART1RX` (the QEMU board's GPS vector name).
//! - MAVLink telemetry: USART1 (PA9 TX, PA10 RX) = ArduPilot SERIAL1 (TELEM1);
//!   transmit-complete interrupt → `UART2TX`.
//! - `IMU_TASK` / `TELEMETRY_TASK`: CAN2_RX0 / CAN2_RX1 (no CAN transceiver on
//!   this board), software-pended.
//! - Sample clock: TIM2 (32-bit) at 1 MHz, extended to 64 bits per sample.
//! - LED: blue on PA14, which is also SWCLK — used only when no debugger is
//!   attached, so RTT/defmt over SWD keeps working on the bench.
//! - Independent watchdog (~250 ms), fed by each good IMU sample: a panic, a hung
//!   ISR or a dead IMU ends in a watchdog reset; the next boot logs it.
//!
//! Logs: defmt over RTT (`probe-rs run` shows them). Not tried on hardware — see
//! docs/board-f405.md for the bring-up checklist.

use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m::peripheral::{DCB, DWT, NVIC};
use defmt_rtt as _;
use embedded_hal_bus::spi::{ExclusiveDevice, NoDelay};
use embedded_hal_nb::serial::{Read, Write};
use stm32f4xx_hal::nb;
use stm32f4xx_hal::{
    gpio::{Edge, ExtiPin, Input, Output, PushPull, Speed, PA14, PA4, PC4},
    pac,
    prelude::*,
    rcc::Config as ClockConfig,
    serial::{self, Rx, Tx},
    spi::{Mode, Phase, Polarity, Spi},
    timer::CounterUs,
    watchdog::IndependentWatchdog,
};
use wing_ahrs::drivers::{AxisMap, ImuSample, Mpu6000, Mpu6000Config};

/// Core clock, Hz (HSE 8 MHz crystal → PLL → 168 MHz; APB2 84 MHz, APB1 42 MHz).
pub const CORE_HZ: u32 = 168_000_000;
/// GPS UART baud rate (configure the receiver to UBX NAV-PVT at this rate).
pub const GPS_BAUD: u32 = 115_200;
/// Telemetry baud rate: the default MAVLink stream (ATTITUDE 50 Hz + raw IMU
/// 100 Hz + status) needs more than 115200 can carry.
pub const TELEMETRY_BAUD: u32 = 460_800;
/// Watchdog period, ms (LSI is 17–47 kHz, so the real timeout is 0.5–1.9× this).
pub const WATCHDOG_MS: u32 = 250;
/// SPI1 clock for MPU-6000 register writes: APB2 / 128 = 656 kHz (the part allows ≤ 1 MHz).
const SPI_SLOW_HZ: u32 = 656_250;
/// SPI1 baud-rate divider for sensor reads: APB2 / 8 = 10.5 MHz (the part allows ≤ 20 MHz).
const SPI_BR_DIV8: u8 = 0b010;

/// STM32F405 IRQ numbers (RM0090 table 61) under the firmware's board-neutral
/// handler names. The PAC's vector table (stm32f4 `rt`) calls the device names
/// (`EXTI4`, `UART4`, …); `memory.x` aliases the four wired ones to these names.
/// Unwired names sit on IRQs of peripherals this board leaves off (CAN, TIM2), so
/// they exist for `#[interrupt]` but never fire.
#[allow(non_camel_case_types, clippy::upper_case_acronyms, dead_code)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
pub enum interrupt {
    /// EXTI4: MPU-6000 data ready on PC4 (the sensor context).
    SENSOR_DATA = 10,
    /// CAN1_SCE — unused.
    UART0TX = 22,
    /// UART4: GPS receive (RXNE and overrun share the vector).
    UART1RX = 52,
    /// CAN2_TX — unused.
    UART1TX = 63,
    /// CAN1_RX1 — unused (telemetry uplink ignored).
    UART2RX = 21,
    /// USART1: telemetry transmit complete.
    UART2TX = 37,
    /// TIM2 — the sample clock; its interrupt stays off.
    TIMER0 = 28,
    /// CAN2_SCE — unused (overruns arrive on the UART vector).
    UART_OVF = 66,
    /// CAN2_RX0: software-pended IMU processing (predict + update).
    IMU_TASK = 64,
    /// CAN2_RX1: software-pended telemetry encoder.
    TELEMETRY_TASK = 65,
}

// SAFETY: every discriminant is a valid STM32F405 IRQ number (< 82).
unsafe impl cortex_m::interrupt::InterruptNumber for interrupt {
    fn number(self) -> u16 {
        self as u16
    }
}

/// Interrupt priorities (lower = more urgent; the F405 implements the top 4 bits).
/// Same order as the QEMU board.
pub mod prio {
    /// GPS RX (a UART holds one byte: must not wait behind the estimator).
    pub const RX: u8 = 0x20;
    /// IMU data ready: SPI read + predict (+ update).
    pub const IMU: u8 = 0x40;
    /// Telemetry TX drain.
    pub const TX: u8 = 0x60;
    /// Telemetry encoding: lowest.
    pub const TELEMETRY: u8 = 0xE0;
}

type ImuSpi = ExclusiveDevice<Spi<pac::SPI1>, PA4<Output<PushPull>>, NoDelay>;

/// TIM2 counts 0..=ARR with ARR = u32::MAX − 1, so it wraps modulo 2³² − 1.
const TIM2_MODULUS: u64 = u32::MAX as u64;

/// The MPU-6000 with its data-ready line, the sample clock, the watchdog it feeds,
/// and the status LED.
pub struct Imu {
    mpu: Mpu6000<ImuSpi>,
    drdy: PC4<Input>,
    clock: CounterUs<pac::TIM2>,
    last_ticks: u32,
    t_us: u64,
    watchdog: IndependentWatchdog,
    led: Option<PA14<Output<PushPull>>>,
    samples: u32,
    errors: u32,
}

impl Imu {
    /// Reads the sample that raised the data-ready interrupt (≈ 12 µs of SPI at
    /// 10.5 MHz): its time (µs since boot, taken at interrupt entry) and the sample in
    /// rad/s and m/s², body FRD. Acknowledges the EXTI line and feeds the watchdog.
    /// `None` after an SPI error (counted).
    pub fn read(&mut self) -> Option<(u64, ImuSample)> {
        let now = self.clock.now().ticks();
        // Called at 100 Hz, far inside the 71-minute wrap of the 32-bit counter.
        let dt = (now as u64 + TIM2_MODULUS - self.last_ticks as u64) % TIM2_MODULUS;
        self.last_ticks = now;
        self.t_us += dt;
        self.drdy.clear_interrupt_pending_bit();
        match self.mpu.read() {
            Ok(s) => {
                self.watchdog.feed();
                self.samples = self.samples.wrapping_add(1);
                if let Some(led) = self.led.as_mut() {
                    // 0.5 Hz blink at 100 Hz: the IMU loop is alive.
                    if self.samples % 100 == 0 {
                        led.toggle();
                    }
                }
                Some((self.t_us, s))
            }
            Err(_) => {
                self.errors = self.errors.wrapping_add(1);
                None
            }
        }
    }

    /// SPI errors since boot.
    pub fn errors(&self) -> u32 {
        self.errors
    }
}

/// A UART in one of the two roles the firmware uses. One type (like the QEMU
/// board's `Uart`) so the firmware's contexts are board-neutral; the methods of
/// the other role are no-ops.
pub enum Uart {
    /// GPS receiver: UART4 RX, RXNE interrupt.
    Gps {
        /// The HAL receiver.
        rx: Rx<pac::UART4>,
        /// An overrun not yet reported.
        overrun: bool,
    },
    /// Telemetry transmitter: USART1 TX, transmission-complete interrupt.
    ///
    /// TC (not TXE) is the interrupt source because it can be acknowledged like the
    /// QEMU UART's TX interrupt: it fires once after the last byte written has left,
    /// and [`Uart::clear_tx_irq`] clears it, so an empty ring means a quiet line.
    Telemetry(Tx<pac::USART1>),
}

impl Uart {
    /// The received byte, if one is waiting. Line errors (overrun, framing, noise)
    /// consume the data register, so that byte is lost; overruns are remembered for
    /// [`Uart::take_overrun`], the GPS parser's checksums catch the gap.
    #[inline]
    pub fn read_byte(&mut self) -> Option<u8> {
        let Uart::Gps { rx, overrun } = self else { return None };
        // Bounded: each error read clears the flags, the next read is data or WouldBlock.
        for _ in 0..2 {
            match rx.read() {
                Ok(b) => return Some(b),
                Err(nb::Error::WouldBlock) => return None,
                Err(nb::Error::Other(serial::Error::Overrun)) => *overrun = true,
                Err(nb::Error::Other(_)) => {}
            }
        }
        None
    }

    /// Whether a receive overrun happened since the last call (clears it).
    #[inline]
    pub fn take_overrun(&mut self) -> bool {
        match self {
            Uart::Gps { overrun, .. } => core::mem::replace(overrun, false),
            Uart::Telemetry(_) => false,
        }
    }

    /// Writes `b` if the transmitter can take it; `false` when its data register is full.
    #[inline]
    pub fn try_write(&mut self, b: u8) -> bool {
        match self {
            Uart::Telemetry(tx) => tx.write(b).is_ok(),
            Uart::Gps { .. } => false,
        }
    }

    /// Acknowledges the transmit-complete interrupt.
    #[inline]
    pub fn clear_tx_irq(&mut self) {
        if let Uart::Telemetry(_) = self {
            // SAFETY: USART1 belongs to this `Uart` (moved into one interrupt context);
            // SR.TC is rc_w0: writing 0 to TC and 1 to the other defined bits (0..=9;
            // the rest are reserved and stay 0) clears only TC.
            let usart = unsafe { &*pac::USART1::ptr() };
            usart.sr().write(|w| unsafe { w.bits(0x3FF & !(1 << 6)) });
        }
    }
}

/// The board's peripherals, handed out once by [`init`].
pub struct Board {
    /// The IMU (data ready on EXTI4 → `SENSOR_DATA`, the sensor context).
    pub sensor: Imu,
    /// GPS receiver (UART4 RX → `UART1RX`).
    pub gps: Uart,
    /// Telemetry out (USART1 TX → `UART2TX`).
    pub telemetry: Uart,
}

static WATCHDOG_RESET: AtomicBool = AtomicBool::new(false);
static WATCHDOG_STARTED: AtomicBool = AtomicBool::new(false);

/// Whether the last reset came from the watchdog (a panic or a stalled IMU loop).
#[allow(dead_code)] // logged at boot; exposed for telemetry
pub fn reset_by_watchdog() -> bool {
    WATCHDOG_RESET.load(Ordering::Relaxed)
}

/// Clocks, GPIO, SPI1 + MPU-6000, UARTs, EXTI, DWT stopwatch, NVIC priorities and
/// the watchdog. Interrupts stay masked in the NVIC until [`start`]. Blocks ~0.2 s
/// for the IMU reset; an IMU that does not answer ends in [`fail_safe`] (reset loop,
/// with the reason on RTT).
pub fn init(mut core: cortex_m::Peripherals) -> Board {
    let Some(dp) = pac::Peripherals::take() else { fail_safe() };
    note_reset_cause(&dp.RCC);

    let mut rcc = dp.RCC.freeze(
        ClockConfig::hse(8.MHz())
            .sysclk(CORE_HZ.Hz())
            .hclk(CORE_HZ.Hz())
            .pclk1(42.MHz())
            .pclk2(84.MHz()),
    );
    let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
    let mut exti = dp.EXTI;
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpioc = dp.GPIOC.split(&mut rcc);

    // Cycle counter: the on-board cost stopwatch.
    core.DCB.enable_trace();
    core.DWT.enable_cycle_counter();

    // MPU-6000 on SPI1, mode 3 (ArduPilot's SPIDEV mpu6000 … MODE3). Writes at ≤ 1 MHz.
    let cs = gpioa.pa4.into_push_pull_output_in_state(true.into());
    let sck = gpioa.pa5.into_alternate().speed(Speed::VeryHigh);
    let miso = gpioa.pa6.into_alternate().speed(Speed::VeryHigh);
    let mosi = gpioa.pa7.into_alternate().speed(Speed::VeryHigh);
    let mode = Mode { polarity: Polarity::IdleHigh, phase: Phase::CaptureOnSecondTransition };
    let spi =
        Spi::new(dp.SPI1, (Some(sck), Some(miso), Some(mosi)), mode, SPI_SLOW_HZ.Hz(), &mut rcc);
    let Ok(dev) = ExclusiveDevice::new_no_delay(spi, cs);
    let mut delay = core.SYST.delay(&rcc.clocks);
    let mpu = mpu_up(dev, &mut delay);

    // Sample clock: TIM2 free-running at 1 MHz (DWT's cycle counter stops in WFI sleep).
    let mut clock = dp.TIM2.counter_us(&mut rcc);
    if clock.start(u32::MAX.micros()).is_err() {
        fail_safe();
    }
    let last_ticks = clock.now().ticks();

    // Data-ready: PC4 rising edge → EXTI4.
    let mut drdy = gpioc.pc4.into_pull_down_input();
    drdy.make_interrupt_source(&mut syscfg);
    drdy.trigger_on_edge(&mut exti, Edge::Rising);
    drdy.enable_interrupt(&mut exti);

    // GPS: UART4 RX on PA1 (TX PA0 left free: the receiver is configured beforehand).
    let Ok(mut gps_rx) = dp.UART4.rx::<u8>(gpioa.pa1, GPS_BAUD.bps(), &mut rcc) else {
        fail_safe()
    };
    gps_rx.listen();

    // Telemetry: USART1 TX on PA9, transmission-complete interrupt.
    let Ok(tel_tx) = dp.USART1.tx::<u8>(gpioa.pa9, TELEMETRY_BAUD.bps(), &mut rcc) else {
        fail_safe()
    };
    // SAFETY: USART1 was just configured by the HAL and is owned by `tel_tx`; only CR1.TCIE changes.
    unsafe { &*pac::USART1::ptr() }.cr1().modify(|_, w| w.tcie().set_bit());

    // Status LED only without a debugger: PA14 is SWCLK.
    let led =
        if DCB::is_debugger_attached() { None } else { Some(gpioa.pa14.into_push_pull_output()) };

    set_priorities(&mut core.NVIC);

    // Watchdog last: from here a missing IMU sample for WATCHDOG_MS resets the board.
    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    watchdog.stop_on_debug(&dp.DBGMCU, true);
    watchdog.start(WATCHDOG_MS.millis());
    WATCHDOG_STARTED.store(true, Ordering::Relaxed);

    Board {
        sensor: Imu { mpu, drdy, clock, last_ticks, t_us: 0, watchdog, led, samples: 0, errors: 0 },
        gps: Uart::Gps { rx: gps_rx, overrun: false },
        telemetry: Uart::Telemetry(tel_tx),
    }
}

/// Why did we boot? Reads and clears the reset flags (before anything else).
fn note_reset_cause(rcc: &pac::RCC) {
    let csr = rcc.csr().read();
    if csr.wdgrstf().bit_is_set() || csr.wwdgrstf().bit_is_set() {
        WATCHDOG_RESET.store(true, Ordering::Relaxed);
        defmt::warn!("reset by watchdog (panic or stalled IMU loop before this boot)");
    }
    rcc.csr().modify(|_, w| w.rmvf().set_bit());
}

/// The MPU-6000 configured (three attempts, then [`fail_safe`]), and SPI1 switched to
/// the fast clock its sensor reads allow.
fn mpu_up(dev: ImuSpi, delay: &mut impl embedded_hal::delay::DelayNs) -> Mpu6000<ImuSpi> {
    let mut mpu = Mpu6000::new(dev, AxisMap::MATEK_F405_WING);
    let cfg = Mpu6000Config::default();
    let mut ok = false;
    for attempt in 1..=3 {
        match mpu.init(delay, &cfg) {
            Ok(()) => {
                ok = true;
                break;
            }
            Err(e) => {
                defmt::error!("MPU-6000 init attempt {}: {}", attempt, defmt::Debug2Format(&e))
            }
        }
    }
    if !ok {
        fail_safe();
    }
    // Sensor registers may be read at up to 20 MHz: switch SPI1 to APB2/8 between transactions.
    // SAFETY: SPI1 is idle (CS high) and owned by `mpu`; only CR1.BR changes, with SPE off.
    let spi1 = unsafe { &*pac::SPI1::ptr() };
    spi1.cr1().modify(|_, w| w.spe().clear_bit());
    spi1.cr1().modify(|_, w| w.br().set(SPI_BR_DIV8));
    spi1.cr1().modify(|_, w| w.spe().set_bit());
    defmt::info!("MPU-6000 ready: {} Hz data ready, ±2000 dps, ±16 g", cfg.sample_rate_hz());
    mpu
}

/// The NVIC priorities of the firmware's interrupts (`prio`).
fn set_priorities(nvic: &mut NVIC) {
    // SAFETY: priorities are set before any of these interrupts is unmasked.
    unsafe {
        nvic.set_priority(interrupt::UART1RX, prio::RX);
        nvic.set_priority(interrupt::SENSOR_DATA, prio::RX);
        nvic.set_priority(interrupt::IMU_TASK, prio::IMU);
        nvic.set_priority(interrupt::UART2TX, prio::TX);
        nvic.set_priority(interrupt::TELEMETRY_TASK, prio::TELEMETRY);
    }
}

/// Unmasks the firmware's interrupts. Call after every handler's context is in place.
pub fn start() {
    for irq in [
        interrupt::SENSOR_DATA,
        interrupt::UART1RX,
        interrupt::IMU_TASK,
        interrupt::UART2TX,
        interrupt::TELEMETRY_TASK,
    ] {
        // SAFETY: all handler contexts were installed by the caller (see main.rs).
        unsafe { NVIC::unmask(irq) };
    }
}

/// Free-running stopwatch: the DWT cycle counter (168 MHz, wraps every 25.6 s).
#[inline]
pub fn stopwatch() -> u32 {
    DWT::cycle_count()
}

/// CPU **cycles** since `start` (a [`stopwatch`] reading), including flash wait states —
/// not the instruction count the QEMU board's `elapsed` reports.
#[inline]
pub fn elapsed(start: u32) -> u32 {
    DWT::cycle_count().wrapping_sub(start)
}

/// The defined state after a panic: interrupts off, then spin without feeding the
/// watchdog, which resets the board within ~`WATCHDOG_MS` (the next boot logs
/// "reset by watchdog"). If the watchdog was not started yet (panic during init),
/// reset through the SCB after a short spin so RTT can flush.
pub fn fail_safe() -> ! {
    cortex_m::interrupt::disable();
    if !WATCHDOG_STARTED.load(Ordering::Relaxed) {
        cortex_m::asm::delay(CORE_HZ / 4);
        cortex_m::peripheral::SCB::sys_reset();
    }
    loop {
        cortex_m::asm::nop();
    }
}

/// A real board never exits: treated as [`fail_safe`] (watchdog reset).
pub fn exit(_code: i32) -> ! {
    fail_safe()
}
