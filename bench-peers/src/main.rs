//! Cost of one estimator on the Cortex-M4F (QEMU mps2-an386, `-icount shift=0`): every IMU
//! sample of an embedded simulated flight is fed as the host comparison feeds it, and the
//! instructions of each step are counted with the same SysTick stopwatch as the firmware's
//! (1 instruction = 1 ns of virtual time; SysTick at 25 MHz: 40 instructions per tick).
//! Instructions, not cycles. Prints `key: value` lines over semihosting, then the stack
//! high-water mark (cortex-m-rt paints the stack at boot). After each counted step (outside
//! the stopwatch) the attitude is compared with the flight's truth (`truth.rs`).

#![no_std]
#![no_main]

#[cfg(feature = "ekf2")]
mod heap;
mod record;
#[cfg(feature = "ekf2")]
mod reference;
#[cfg(feature = "ekf2")]
mod run_ekf2;
#[cfg(feature = "fusion-nav")]
mod run_fusion_nav;
#[cfg(feature = "ours")]
mod run_ours;
mod truth;

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use record::Record;

#[cfg(feature = "ekf2")]
use run_ekf2::Peer;
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
    #[cfg(feature = "ekf2")]
    heap::init();
    let mut peer = Peer::new();
    #[cfg(feature = "ekf2")]
    let init_allocs = heap::allocs();
    #[cfg(feature = "ekf2")]
    let mut agreement = reference::Agreement::default();
    let mut errors = truth::Errors::default();
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
        errors.add(r.t_us, peer.attitude(), r.truth);
        #[cfg(feature = "ekf2")]
        agreement.check(k, r.t_us, peer.quaternion());
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
    errors.print(key);
    #[cfg(feature = "ekf2")]
    {
        semihosting::println!("{key}.heap_arena_bytes: {}", heap::ARENA_BYTES);
        semihosting::println!("{key}.heap_peak_bytes: {}", heap::peak());
        semihosting::println!("{key}.heap_in_use_bytes: {}", heap::used());
        semihosting::println!("{key}.heap_allocs_construction: {init_allocs}");
        semihosting::println!("{key}.heap_allocs_in_steps: {}", heap::allocs() - init_allocs);
        semihosting::println!("{key}.embedded_reference_bytes: {}", reference::bytes());
        agreement.print(key);
    }
    semihosting::process::exit(0)
}

/// Roll, pitch, yaw (3-2-1), rad, of a unit quaternion (w, x, y, z) rotating body → NED.
#[cfg(feature = "ekf2")]
fn euler_of_quat([w, x, y, z]: [f32; 4]) -> [f32; 3] {
    use wing_ahrs::math::{asin, atan2};
    let roll = atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
    let pitch = asin((2.0 * (w * y - z * x)).clamp(-1.0, 1.0));
    let yaw = atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
    [roll, pitch, yaw]
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
