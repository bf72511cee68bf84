//! Cost of one estimator on the Cortex-M4F (QEMU mps2-an386, `-icount shift=0`): every IMU
//! sample of an embedded simulated flight is fed as the host comparison feeds it, and the
//! instructions of each step are counted with the same SysTick stopwatch as the firmware's
//! (1 instruction = 1 ns of virtual time; SysTick at 25 MHz: 40 instructions per tick).
//! Instructions, not cycles. Prints `key: value` lines over semihosting, then the stack
//! high-water mark (cortex-m-rt paints the stack at boot).

#![no_std]
#![no_main]

mod record;
#[cfg(feature = "fusion-nav")]
mod run_fusion_nav;
#[cfg(feature = "ours")]
mod run_ours;

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use record::Record;

#[cfg(feature = "fusion-nav")]
use run_fusion_nav::Peer;
#[cfg(feature = "ours")]
use run_ours::Peer;

/// Instructions per SysTick tick: 1e9 instructions/s of virtual time over the 25 MHz core clock.
const INSTRUCTIONS_PER_TICK: u32 = 40;

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| fail());
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00FF_FFFF);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    let mut peer = Peer::new();
    let (mut sum, mut n, mut max) = (0u64, 0u64, 0u32);
    let (mut gps_sum, mut gps_n, mut gps_max) = (0u64, 0u64, 0u32);
    for k in 0..record::count() {
        let r: Record = record::get(k);
        let start = SYST::get_current();
        peer.step(&r);
        let ins = (start.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF) * INSTRUCTIONS_PER_TICK;
        sum += ins as u64;
        n += 1;
        max = max.max(ins);
        if r.fix {
            gps_sum += ins as u64;
            gps_n += 1;
            gps_max = gps_max.max(ins);
        }
    }
    let att = core::hint::black_box(peer.attitude());
    let key = Peer::KEY;
    semihosting::println!("{key}.samples: {n}");
    semihosting::println!("{key}.mean_instr: {}", sum / n.max(1));
    semihosting::println!("{key}.gps_instr: {}", gps_sum / gps_n.max(1));
    semihosting::println!("{key}.gps_max_instr: {gps_max}");
    semihosting::println!("{key}.max_instr: {max}");
    // The estimator lives on main's stack, so the stack figure includes its state.
    semihosting::println!("{key}.stack_bytes: {}", stack_used());
    semihosting::println!("{key}.state_bytes: {}", core::mem::size_of::<Peer>());
    semihosting::println!("{key}.embedded_flight_bytes: {}", record::bytes());
    semihosting::println!(
        "{key}.final_attitude_deg: {:.2} {:.2} {:.2}",
        att[0].to_degrees(),
        att[1].to_degrees(),
        att[2].to_degrees()
    );
    semihosting::process::exit(0)
}

/// Bytes of stack ever used: from the top down to the lowest word no longer painted.
fn stack_used() -> usize {
    extern "C" {
        static _stack_start: u32;
        static _stack_end: u32;
    }
    // SAFETY: reads words between the linker's stack bounds, which are RAM this program owns.
    unsafe {
        let top = core::ptr::addr_of!(_stack_start) as usize;
        let mut p = core::ptr::addr_of!(_stack_end) as usize;
        while p < top && core::ptr::read_volatile(p as *const u32) == cortex_m_rt::STACK_PAINT_VALUE
        {
            p += 4;
        }
        top - p
    }
}

/// Device interrupt vectors (cortex-m-rt's `device` feature, which wing-ahrs enables for the
/// firmware, wants them): none is enabled here, so every slot is the fail-safe.
#[link_section = ".vector_table.interrupts"]
#[no_mangle]
#[used]
static __INTERRUPTS: [unsafe extern "C" fn(); 32] = [unused_irq; 32];

unsafe extern "C" fn unused_irq() {
    fail()
}

fn fail() -> ! {
    semihosting::process::exit(101)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    fail()
}
