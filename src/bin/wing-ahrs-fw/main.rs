//! wing-ahrs firmware: the estimator in the 100 Hz IMU interrupt of a Cortex-M4F board.
//!
//! # Concurrency: plain cortex-m-rt handlers, not RTIC 2
//! RTIC 2 needs a PAC-shaped device crate for its dispatchers; the QEMU board has
//! none (see `board/qemu.rs`) and four fixed-priority contexts need no scheduler.
//! Race freedom is by construction instead:
//! - every context's state is built in place in its own static cell at boot
//!   (`static_cell`: a `&'static mut` handed out once), and that unique reference is
//!   moved into exactly one handler-local `static mut` (cortex-m-rt turns it into a
//!   `&mut` only that handler sees) through a [`Handoff`] cell filled by `main`
//!   before interrupts are unmasked;
//! - contexts talk only through single-producer/single-consumer `heapless::spsc`
//!   queues whose two ends live in two different contexts, and through atomics;
//! - nothing blocks: a full queue drops (and counts) the new item.
//!
//! | context (priority) | owns | produces → |
//! |---|---|---|
//! | sensor `SENSOR_DATA` (high; HIL UART on QEMU, IMU data ready on F405) | record decoder / SPI IMU | records → IMU task |
//! | GPS RX `UART1RX` (high) | GPS parser | fixes → IMU task |
//! | IMU task `IMU_TASK` (mid, the data-ready interrupt) | `Ahrs`, cost stats | samples → telemetry |
//! | TX drain `UART2TX` (mid-low) | telemetry UART | — |
//! | telemetry `TELEMETRY_TASK` (lowest) | MAVLink encoder | bytes → TX ring |
//!
//! # Stack
//! Nothing large lives on a stack: the estimator, parsers, queues and the MAVLink
//! frame buffer are statics built in place, `main` only sets up and idles, and a
//! handler passes big items by reference. Boot and flight stack are measured
//! separately (`board::stack`, reported as `STACK`, `STACK_BOOT`, `STACK_MAIN`,
//! `STACK_ISR`); `docs/firmware-stack.md` has the nested-interrupt worst case.
#![no_std]
#![no_main]

mod board;
mod costs;
mod doubt;
mod telemetry;

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
use cortex_m_rt::{entry, interrupt};
use critical_section::Mutex;
// defmt transport: semihosting on QEMU; the F405 board links defmt-rtt itself.
#[cfg(not(feature = "board-f405"))]
use defmt_semihosting as _;
use heapless::spsc::{Consumer, Producer, Queue};
use static_cell::{ConstStaticCell, StaticCell};

use board::{interrupt, Uart};
use telemetry::{Costs, LinkCounters, Out, Sample, Telemetry, RING};
use wing_ahrs::gps::GpsParser;
// The HIL record decoder is QEMU-only; the F405 board reuses just its record types.
use wing_ahrs::hil_record::{ImuRecord, Record};
use wing_ahrs::{Ahrs, Config, GpsFix, GpsOutcome};

const RECORD_Q: usize = 8;
const FIX_Q: usize = 8;
const OUT_Q: usize = 16;
/// Status (health + costs) every this many samples (1 Hz at 100 Hz).
const STATUS_EVERY: u32 = 100;

/// A value moved from `main` into exactly one interrupt context.
struct Handoff<T>(Mutex<RefCell<Option<T>>>);

impl<T> Handoff<T> {
    const fn new() -> Self {
        Handoff(Mutex::new(RefCell::new(None)))
    }
    fn put(&self, v: T) {
        critical_section::with(|cs| *self.0.borrow_ref_mut(cs) = Some(v));
    }
    fn take(&self) -> Option<T> {
        critical_section::with(|cs| self.0.borrow_ref_mut(cs).take())
    }
}

// Counters written by one context, read by telemetry.
static RECORD_ERRORS: AtomicU32 = AtomicU32::new(0);
static RECORD_OVERFLOWS: AtomicU32 = AtomicU32::new(0);
static GPS_ERRORS: AtomicU32 = AtomicU32::new(0);
static GPS_Q_OVERFLOWS: AtomicU32 = AtomicU32::new(0);
static UART_OVERRUNS: AtomicU32 = AtomicU32::new(0);
static OUT_DROPPED: AtomicU32 = AtomicU32::new(0);
static GPS_LATE: AtomicU32 = AtomicU32::new(0);
/// Set by telemetry after the final report; the TX drain exits when the ring is empty.
static STOPPING: AtomicBool = AtomicBool::new(false);

#[cfg(not(feature = "board-f405"))]
struct SensorRx {
    uart: Uart,
    dec: wing_ahrs::hil_record::Decoder,
    records: Producer<'static, Record, RECORD_Q>,
}

/// Real board: the IMU's data-ready interrupt is the sensor context; it reads one
/// sample and queues it as the same record the HIL link delivers.
#[cfg(feature = "board-f405")]
struct SensorRx {
    imu: board::Imu,
    records: Producer<'static, Record, RECORD_Q>,
}

/// GPS fixes queued so far (real board: an IMU sample takes every fix that arrived before it).
#[cfg(feature = "board-f405")]
static GPS_FIXES: AtomicU32 = AtomicU32::new(0);

struct GpsRx {
    uart: Uart,
    parser: GpsParser,
    fixes: Producer<'static, GpsFix, FIX_Q>,
}

struct ImuTask {
    ahrs: Ahrs,
    records: Consumer<'static, Record, RECORD_Q>,
    fixes: Consumer<'static, GpsFix, FIX_Q>,
    out: Producer<'static, Out, OUT_Q>,
    /// Fixes accounted for: consumed by the estimator or lost to a full fix queue.
    consumed: u32,
    overflows_seen: u32,
    costs: Costs,
    since_status: u32,
    last_update_seq: u32,
}

struct TelemetryTask {
    tele: Telemetry,
    out: Consumer<'static, Out, OUT_Q>,
}

struct TxDrain {
    uart: Uart,
    ring: Consumer<'static, u8, RING>,
}

// Each context's state: built in place at boot (never on a stack), then owned by one handler.
static SENSOR_RX: Handoff<&'static mut SensorRx> = Handoff::new();
static GPS_RX: Handoff<&'static mut GpsRx> = Handoff::new();
static IMU: Handoff<&'static mut ImuTask> = Handoff::new();
static TELEMETRY: Handoff<&'static mut TelemetryTask> = Handoff::new();
static TX: Handoff<&'static mut TxDrain> = Handoff::new();
static SENSOR_RX_STATE: StaticCell<SensorRx> = StaticCell::new();
static GPS_RX_STATE: StaticCell<GpsRx> = StaticCell::new();
static IMU_STATE: StaticCell<ImuTask> = StaticCell::new();
static TELEMETRY_STATE: StaticCell<TelemetryTask> = StaticCell::new();
static TX_STATE: StaticCell<TxDrain> = StaticCell::new();
// Queues: constant-initialised statics (a `singleton!` would build them on the stack first).
static RECORDS: ConstStaticCell<Queue<Record, RECORD_Q>> = ConstStaticCell::new(Queue::new());
static FIXES: ConstStaticCell<Queue<GpsFix, FIX_Q>> = ConstStaticCell::new(Queue::new());
static OUTS: ConstStaticCell<Queue<Out, OUT_Q>> = ConstStaticCell::new(Queue::new());
static TX_RING: ConstStaticCell<Queue<u8, RING>> = ConstStaticCell::new(Queue::new());

#[entry]
fn main() -> ! {
    let b = board_up();
    // The boot micro-benchmarks (bench build only; they need the board's stopwatch)
    // are not part of the shipped firmware: their stack is repainted so the figures
    // below are the firmware's.
    #[cfg(feature = "boot-bench")]
    let breakdown = {
        let k = costs::measure();
        board::stack::repaint_below_caller();
        k
    };
    #[cfg(not(feature = "boot-bench"))]
    let breakdown = costs::Breakdown::default();
    init(b, breakdown);
    // Boot ends here: record its stack, repaint, and measure the flight on its own.
    board::stack::end_of_boot(cortex_m::register::msp::read());
    board::start();
    loop {
        cortex_m::asm::wfi();
    }
}

/// Board bring-up (interrupts stay masked). Not inlined: keeps `main`'s idle frame small.
#[inline(never)]
fn board_up() -> board::Board {
    let core = cortex_m::Peripherals::take().unwrap();
    board::init(core)
}

/// Boot: queues and every context's state, built in place in their statics. Not
/// inlined, so its frame is gone before the interrupts (which run below `main`'s
/// small idle frame) start.
#[inline(never)]
fn init(b: board::Board, breakdown: costs::Breakdown) {
    let (rec_p, rec_c) = RECORDS.take().split();
    let (fix_p, fix_c) = FIXES.take().split();
    let (out_p, out_c) = OUTS.take().split();
    let (ring_p, ring_c) = TX_RING.take().split();

    #[cfg(not(feature = "board-f405"))]
    SENSOR_RX.put(SENSOR_RX_STATE.init_with(|| SensorRx {
        uart: b.sensor,
        dec: wing_ahrs::hil_record::Decoder::new(),
        records: rec_p,
    }));
    #[cfg(feature = "board-f405")]
    SENSOR_RX.put(SENSOR_RX_STATE.init_with(|| SensorRx { imu: b.sensor, records: rec_p }));
    GPS_RX.put(GPS_RX_STATE.init_with(|| GpsRx {
        uart: b.gps,
        parser: GpsParser::new(),
        fixes: fix_p,
    }));
    // Once at boot, never per sample. The built-in configuration validates (a host test
    // checks `Config::default()`); were it edited out of range, every error is logged and
    // the board stops before any estimate goes out.
    let cfg = match Config::default().validated() {
        Ok(cfg) => cfg,
        Err(errors) => {
            for e in errors.iter() {
                defmt::error!(
                    "config: {=str} = {=f32}: must be {=str}",
                    e.field,
                    e.value,
                    e.allowed
                );
            }
            panic!("configuration out of range");
        }
    };
    let gates = doubt::Gates::of(cfg.config());
    IMU.put(IMU_STATE.init_with(|| ImuTask {
        ahrs: Ahrs::new(cfg),
        records: rec_c,
        fixes: fix_c,
        out: out_p,
        consumed: 0,
        overflows_seen: 0,
        costs: Costs::default(),
        since_status: 0,
        last_update_seq: 0,
    }));
    TELEMETRY.put(TELEMETRY_STATE.init_with(|| TelemetryTask {
        tele: Telemetry::new(ring_p, breakdown, gates),
        out: out_c,
    }));
    TX.put(TX_STATE.init_with(|| TxDrain { uart: b.telemetry, ring: ring_c }));
    defmt::info!("wing-ahrs-fw: boot, Ahrs state {=usize} bytes", core::mem::size_of::<Ahrs>());
}

/// The board's monotonic µs clock for stamping GPS bytes: the time of the newest sensor
/// sample (QEMU: the HIL record's `t_us`, the emulated board's time base under `-icount`;
/// F405: TIM2's 1 MHz count at the latest data-ready). One sample of resolution is ample
/// for the parser's 2 s NMEA-after-UBX rule, which with a constant 0 never expired.
static SAMPLE_CLOCK_US: Mutex<core::cell::Cell<u64>> = Mutex::new(core::cell::Cell::new(0));

/// Moves the sample clock forward (never back).
fn advance_sample_clock(t_us: u64) {
    critical_section::with(|cs| {
        let c = SAMPLE_CLOCK_US.borrow(cs);
        if t_us > c.get() {
            c.set(t_us);
        }
    });
}

fn sample_clock_us() -> u64 {
    critical_section::with(|cs| SAMPLE_CLOCK_US.borrow(cs).get())
}

/// Sensor records (HIL): bytes → decoder → record queue; a complete IMU record
/// raises the IMU task, as a data-ready line would.
#[cfg(not(feature = "board-f405"))]
#[interrupt]
fn SENSOR_DATA() {
    static mut CTX: Option<&'static mut SensorRx> = None;
    let Some(c) = ctx(CTX, &SENSOR_RX) else {
        return;
    };
    while let Some(byte) = c.uart.read_byte() {
        if let Some(rec) = c.dec.push(byte) {
            if let Record::Imu(r) = &rec {
                advance_sample_clock(r.sample.t_us);
            }
            if c.records.enqueue(rec).is_err() {
                RECORD_OVERFLOWS.fetch_add(1, Relaxed);
            }
            board::pend_imu();
        }
    }
    if c.uart.take_overrun() {
        UART_OVERRUNS.fetch_add(1, Relaxed);
    }
    RECORD_ERRORS.store(c.dec.errors, Relaxed);
}

/// Real board (`SENSOR_DATA` is the IMU data-ready vector there): SPI read → record queue
/// → IMU task, which applies every GPS fix queued before this sample.
#[cfg(feature = "board-f405")]
#[interrupt]
fn SENSOR_DATA() {
    static mut CTX: Option<&'static mut SensorRx> = None;
    let Some(c) = ctx(CTX, &SENSOR_RX) else {
        return;
    };
    match c.imu.read() {
        Some((t_us, s)) => {
            advance_sample_clock(t_us);
            let r = ImuRecord {
                sample: wing_ahrs::Sample { t_us, gyro: s.gyro, accel: s.accel, airspeed: None },
                gps_count: GPS_FIXES.load(Relaxed),
            };
            if c.records.enqueue(Record::Imu(r)).is_err() {
                RECORD_OVERFLOWS.fetch_add(1, Relaxed);
            }
            board::pend_imu();
        }
        None => RECORD_ERRORS.store(c.imu.errors(), Relaxed),
    }
}

/// GPS bytes → streaming parser → fix queue. A completed fix re-raises the IMU
/// task in case a sample was deferred waiting for it.
#[interrupt]
fn UART1RX() {
    static mut CTX: Option<&'static mut GpsRx> = None;
    let Some(c) = ctx(CTX, &GPS_RX) else { return };
    let now = sample_clock_us();
    while let Some(byte) = c.uart.read_byte() {
        if let Some(fix) = c.parser.push(byte, now) {
            if c.fixes.enqueue(fix).is_err() {
                GPS_Q_OVERFLOWS.fetch_add(1, Relaxed);
            } else {
                #[cfg(feature = "board-f405")]
                GPS_FIXES.fetch_add(1, Relaxed);
            }
            board::pend_imu();
        }
    }
    if c.uart.take_overrun() {
        UART_OVERRUNS.fetch_add(1, Relaxed);
    }
    let k = c.parser.counters();
    let errors = k
        .checksum_failures
        .wrapping_add(k.oversize)
        .wrapping_add(k.truncated)
        .wrapping_add(k.malformed);
    GPS_ERRORS.store(errors, Relaxed);
}

/// The IMU interrupt: predict (+ airspeed) and the updates for the fixes this
/// sample must see. Never blocks: a sample whose fix is still arriving is
/// deferred (the GPS ISR re-raises this interrupt when the fix completes).
#[interrupt]
fn IMU_TASK() {
    static mut CTX: Option<&'static mut ImuTask> = None;
    let Some(c) = ctx(CTX, &IMU) else { return };
    while let Some(rec) = c.records.peek().copied() {
        match rec {
            Record::Imu(r) => {
                // Fixes dropped by a full fix queue will never arrive: account for them.
                let ovf = GPS_Q_OVERFLOWS.load(Relaxed);
                c.consumed = c.consumed.wrapping_add(ovf.wrapping_sub(c.overflows_seen));
                c.overflows_seen = ovf;
                let needed = r.gps_count.wrapping_sub(c.consumed) as usize;
                let queued = c.fixes.len();
                if needed > queued {
                    if c.records.len() < RECORD_Q - 2 {
                        return; // deferred: the fix is still on the GPS UART
                    }
                    GPS_LATE.fetch_add(1, Relaxed);
                }
                c.records.dequeue();
                c.sample(&r, needed.min(queued));
            }
            Record::Config(_) | Record::Stop => {
                c.records.dequeue();
                c.control(&rec);
            }
        }
    }
}

impl ImuTask {
    fn push(&mut self, o: Out) {
        if self.out.enqueue(o).is_err() {
            OUT_DROPPED.fetch_add(1, Relaxed);
        }
        board::pend_telemetry();
    }

    /// One sample, in the facade's order (`Ahrs::step`, split so each half is timed and
    /// has its own stack frame): `Ahrs::predict`, then `Ahrs::update` per fix.
    fn sample(&mut self, r: &ImuRecord, n_fixes: usize) {
        let t0 = board::stopwatch();
        let accepted = self.predict(r);
        let predict = board::elapsed(t0);
        let mut last_fix = None;
        let mut updated = false;
        for _ in 0..n_fixes {
            if let Some(fix) = self.fixes.dequeue() {
                let fix = last_fix.insert(fix);
                fix.t_us = r.sample.t_us; // the fix is consumed at this sample
                updated |= self.update(fix);
                // A fix that missed its sample (deferral gave up) is still owed and
                // is consumed, late, by the next sample once it completes.
                self.consumed = self.consumed.wrapping_add(1);
            }
        }
        let work = board::elapsed(t0);
        if updated {
            self.costs.update_sum += work as u64;
            self.costs.update_n += 1;
        } else if accepted && n_fixes == 0 {
            self.costs.predict_sum += predict as u64;
            self.costs.predict_n += 1;
            self.costs.predict_max = self.costs.predict_max.max(predict);
        }
        self.publish(r, accepted, last_fix.as_ref(), t0);
    }

    /// A configuration or end-of-flight record → telemetry. Not inlined: keeps its
    /// `Out` off the stack of the sample path.
    #[inline(never)]
    fn control(&mut self, rec: &Record) {
        match *rec {
            Record::Config(cfg) => self.push(Out::Config(cfg)),
            Record::Stop => {
                let (h, k) = (self.ahrs.health(), self.costs);
                self.push(Out::Status(h, k));
                self.push(Out::Stop);
            }
            Record::Imu(_) => {}
        }
    }

    /// The predict (and airspeed): `Ahrs::predict`. Not inlined, like [`Self::update`]
    /// and [`Self::publish`]: the IMU task's stack is the largest of the three, not their sum.
    #[inline(never)]
    fn predict(&mut self, r: &ImuRecord) -> bool {
        self.ahrs.predict(&r.sample)
    }

    /// One GPS update: `Ahrs::update`. Not inlined: the update's temporaries and the
    /// predict's are never on the stack at the same time.
    #[inline(never)]
    fn update(&mut self, fix: &GpsFix) -> bool {
        self.ahrs.update(fix) == GpsOutcome::Updated
    }

    /// Hands the sample's read-outs to telemetry. Not inlined: its `Out` (~220 bytes)
    /// and the estimator's temporaries are never on the stack at the same time.
    #[inline(never)]
    fn publish(&mut self, r: &ImuRecord, accepted: bool, fix: Option<&GpsFix>, t0: u32) {
        let r = &r.sample;
        let a = &self.ahrs;
        let e = a.attitude();
        let upd = a.last_update();
        let update = if upd.seq != self.last_update_seq { Some(*upd) } else { None };
        self.last_update_seq = upd.seq;
        // Built once, as the `Out` that is queued; the cost figure is filled in last.
        let mut out = Out::Sample(Sample {
            t_us: r.t_us,
            accepted,
            att: [e.roll, e.pitch, e.yaw],
            rates: a.body_rates(),
            bias: a.gyro_bias(),
            sd: a.std_dev(),
            flags: a.flags().bits(),
            wind: a.wind(),
            update,
            gyro: r.gyro,
            accel: r.accel,
            fix: fix.copied(),
            isr_instructions: 0,
        });
        let isr = board::elapsed(t0);
        self.costs.isr_max = self.costs.isr_max.max(isr);
        if let Out::Sample(s) = &mut out {
            s.isr_instructions = isr;
        }
        self.push(out);
        self.since_status += 1;
        if self.since_status >= STATUS_EVERY {
            self.since_status = 0;
            let (h, k) = (self.ahrs.health(), self.costs);
            self.push(Out::Status(h, k));
        }
    }
}

/// Lowest priority: MAVLink encoding into the TX ring.
#[interrupt]
fn TELEMETRY_TASK() {
    static mut CTX: Option<&'static mut TelemetryTask> = None;
    let Some(c) = ctx(CTX, &TELEMETRY) else {
        return;
    };
    // Handled in place in the queue (an `Out` is a few hundred bytes), then released.
    while let Some(o) = c.out.peek() {
        let link = LinkCounters {
            record_errors: RECORD_ERRORS.load(Relaxed),
            record_overflows: RECORD_OVERFLOWS.load(Relaxed),
            gps_errors: GPS_ERRORS.load(Relaxed),
            gps_queue_overflows: GPS_Q_OVERFLOWS.load(Relaxed),
            uart_overruns: UART_OVERRUNS.load(Relaxed),
            out_dropped: OUT_DROPPED.load(Relaxed),
            gps_late: GPS_LATE.load(Relaxed),
        };
        c.tele.handle(o, &link);
        let stop = matches!(o, Out::Stop);
        c.out.dequeue();
        if stop {
            defmt::info!(
                "end of flight: {=u32} frames sent, {=u32} dropped",
                c.tele.frames,
                c.tele.dropped
            );
            STOPPING.store(true, Relaxed);
        }
        board::pend_telemetry_tx();
    }
}

/// Drains the TX ring into the telemetry UART; re-entered on TX-empty.
#[interrupt]
fn UART2TX() {
    static mut CTX: Option<&'static mut TxDrain> = None;
    let Some(c) = ctx(CTX, &TX) else { return };
    c.uart.clear_tx_irq();
    while let Some(&b) = c.ring.peek() {
        if !c.uart.try_write(b) {
            return; // TX full (host not reading): resume on the next TX interrupt
        }
        c.ring.dequeue();
    }
    if STOPPING.load(Relaxed) {
        board::exit(0);
    }
}

/// A handler's context: its unique reference, moved in from the handoff cell on first entry.
fn ctx<'a, T>(
    slot: &'a mut Option<&'static mut T>,
    cell: &Handoff<&'static mut T>,
) -> Option<&'a mut T> {
    if slot.is_none() {
        *slot = cell.take();
    }
    slot.as_deref_mut()
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    if let Some(l) = info.location() {
        defmt::error!("panic at {=str}:{=u32}", l.file(), l.line());
    } else {
        defmt::error!("panic");
    }
    board::fail_safe()
}
