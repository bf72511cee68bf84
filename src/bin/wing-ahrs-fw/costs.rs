//! Boot-time micro-benchmarks of the default (quaternion) filter's kernels (QEMU
//! `-icount`: instructions, not cycles): a calibration loop of known length, the
//! per-sample attitude step (`Mekf::step`), one covariance propagation (`Mekf::propagate`),
//! one 3-D GPS-acceleration update (`Mekf::fuse`), and one `wing_ahrs::math::sin` (f32
//! only), one `math::atan2`, one `math::sqrt`. Reported as NAMED_VALUE_INT (`CAL_20K`,
//! `INS_STEP`, `INS_PROP`, `INS_FUSE`, `INS_SINF`, `INS_ATAN2`, `INS_SQRT`). And a check, not
//! a cost: `math::sqrt` (the FPU's VSQRT) against libm's software `sqrtf` on the same core
//! over a sweep of every binade (`SQRT_MISS`, inputs that differ in any bit; 0 expected).

#[cfg(feature = "boot-bench")]
use core::hint::black_box;
#[cfg(feature = "boot-bench")]
use wing_ahrs::mekf::{filter::Mekf, filter::Noise, quat};

/// Instruction counts measured at boot.
#[derive(Clone, Copy, Debug, Default)]
pub struct Breakdown {
    /// `cortex_m::asm::delay(10_000)`: a 2-instruction loop run 10 001 times = 20 002 instructions (checks the 40-per-tick stopwatch).
    pub calibration: u32,
    /// `Mekf::step`: the attitude step of one IMU sample (quaternion, DCM, block sums).
    pub step: u32,
    /// `Mekf::propagate`: one covariance propagation (every N samples, and before a fix).
    pub propagate: u32,
    /// One `wing_ahrs::math::sin` (the core's f32-only sine).
    pub sinf: u32,
    /// One `wing_ahrs::math::atan2` (f32 polynomial).
    pub atan2: u32,
    /// One `wing_ahrs::math::sqrt` (the FPU's VSQRT, through `fpu-sqrt`).
    pub sqrt: u32,
    /// Inputs of [`sqrt_mismatches`]' sweep where `math::sqrt` and libm's `sqrtf` differ.
    pub sqrt_mismatches: u32,
    /// One `Mekf::fuse` of a 3-D GPS-acceleration residual (gate, gain, covariance, injection).
    pub fuse: u32,
    /// GPS parser, UBX NAV-PVT stream: instructions per byte.
    pub gps_ubx_per_byte: u32,
    /// GPS parser, NMEA RMC+GGA+VTG stream: instructions per byte.
    pub gps_nmea_per_byte: u32,
}

#[cfg(feature = "boot-bench")]
/// Instructions per byte of the streaming GPS parser over `bytes` (frames built at boot).
fn parser_per_byte(bytes: &[u8]) -> u32 {
    let t = crate::board::stopwatch();
    let n = black_box(wing_ahrs::gps::count_fixes(black_box(bytes)));
    let ins = crate::board::elapsed(t);
    if n == 0 || bytes.is_empty() {
        return 0; // the frames did not decode: report nothing rather than a wrong figure
    }
    ins / bytes.len() as u32
}

#[cfg(feature = "boot-bench")]
/// A UBX NAV-PVT stream and an NMEA RMC/GGA/VTG stream of consecutive 10 Hz fixes.
fn gps_streams(ubx: &mut [u8], nmea: &mut [u8]) -> (usize, usize) {
    use wing_ahrs::gps::encode;
    let (mut nu, mut nn) = (0, 0);
    for k in 0..4u32 {
        let fix = wing_ahrs::GpsFix {
            t_us: 0,
            itow_ms: Some(300_000_000 + 100 * k),
            fix_type: wing_ahrs::FixType::Fix3D,
            fix_ok: true,
            vel_ne: [12.3 + k as f32 * 0.1, -4.5],
            vel_d: Some(0.7),
            speed_acc: Some(0.12),
            num_sats: 12,
            lat_e7: 520_000_000,
            lon_e7: 43_000_000,
            alt_msl_mm: 120_000,
        };
        nu += encode::nav_pvt(&fix, &mut ubx[nu..]).unwrap_or(0);
        nn += encode::nmea_rmc(&fix, 221126, &mut nmea[nn..]).unwrap_or(0);
        nn += encode::nmea_gga(&fix, &mut nmea[nn..]).unwrap_or(0);
        nn += encode::nmea_vtg(&fix, &mut nmea[nn..]).unwrap_or(0);
    }
    (nu, nn)
}

#[cfg(feature = "boot-bench")]
const N: u32 = 16;

/// Runs the micro-benchmarks (averages over N calls). Not inlined: `main` repaints
/// the stack this used (the shipped firmware does not run it).
#[cfg(feature = "boot-bench")]
#[inline(never)]
pub fn measure() -> Breakdown {
    let t = crate::board::stopwatch();
    cortex_m::asm::delay(10_000);
    let calibration = crate::board::elapsed(t);

    let (step, propagate) = predict_kernels();

    let t = crate::board::stopwatch();
    for i in 0..N {
        black_box(wing_ahrs::math::sin(black_box(0.3 + i as f32 * 0.01)));
    }
    let sinf = crate::board::elapsed(t) / N;

    let t = crate::board::stopwatch();
    for i in 0..N {
        black_box(wing_ahrs::math::atan2(
            black_box(0.3 + i as f32 * 0.1),
            black_box(1.2 - i as f32 * 0.2),
        ));
    }
    let atan2 = crate::board::elapsed(t) / N;

    let t = crate::board::stopwatch();
    for i in 0..N {
        black_box(wing_ahrs::math::sqrt(black_box(0.3 + i as f32 * 7.1)));
    }
    let sqrt = crate::board::elapsed(t) / N;
    let sqrt_mismatches = sqrt_mismatches();

    let fuse = fuse_kernel();

    let (mut ubx, mut nmea) = ([0u8; 512], [0u8; 1024]);
    let (nu, nn) = gps_streams(&mut ubx, &mut nmea);
    let gps_ubx_per_byte = parser_per_byte(&ubx[..nu]);
    let gps_nmea_per_byte = parser_per_byte(&nmea[..nn]);
    Breakdown {
        calibration,
        step,
        propagate,
        sinf,
        atan2,
        sqrt,
        sqrt_mismatches,
        fuse,
        gps_ubx_per_byte,
        gps_nmea_per_byte,
    }
}

/// Inputs where `math::sqrt` (VSQRT) and libm's correctly rounded software `sqrtf` differ in
/// any bit, over 8,192 values spread evenly in bits across the positive finite floats
/// (subnormals included, so every binade), with 0, −0 and +∞: the host replay uses libm, so
/// a difference would break the bit-identity of firmware and host.
#[cfg(feature = "boot-bench")]
#[inline(never)]
fn sqrt_mismatches() -> u32 {
    let differ = |x: f32| {
        wing_ahrs::math::sqrt(black_box(x)).to_bits() != libm::sqrtf(black_box(x)).to_bits()
    };
    let mut n = [0.0f32, -0.0, f32::INFINITY].iter().filter(|&&x| differ(x)).count() as u32;
    const STEP: u32 = 0x7f80_0000 / 8192;
    for k in 0..8192u32 {
        n += differ(f32::from_bits(1 + k * STEP + (k & 0xff))) as u32;
    }
    n
}

/// `Mekf::step` and `Mekf::propagate`, instructions per call.
#[cfg(feature = "boot-bench")]
fn predict_kernels() -> (u32, u32) {
    let gyro = [0.05f32, 0.02, 0.1];
    let var = [1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4];
    let mut ekf =
        Mekf::new(quat::from_euler(&wing_ahrs::Euler { roll: 0.3, pitch: 0.1, yaw: 1.0 }), var);
    let t = crate::board::stopwatch();
    for _ in 0..N {
        black_box(ekf.step(black_box(gyro), black_box(0.01)));
    }
    let step = crate::board::elapsed(t) / N;

    let noise = Noise {
        gyro_psd: 1e-6,
        bias_psd: 1e-9,
        rate_psd: 1e-6,
        scale_var: 0.0,
        #[cfg(feature = "gyro-scale-states")]
        scale_var_xy: 0.0,
        misalignment_var: 0.0,
    };
    // Each propagation needs a block to propagate: a step and a propagation per
    // iteration, less the step's own cost.
    let t = crate::board::stopwatch();
    for _ in 0..N {
        black_box(ekf.step(black_box(gyro), black_box(0.01)));
        ekf.propagate(black_box(&noise));
    }
    let propagate = (crate::board::elapsed(t) / N).saturating_sub(step);
    (step, propagate)
}

/// One `Mekf::fuse` of a 3-D GPS-acceleration residual, instructions.
#[cfg(feature = "boot-bench")]
fn fuse_kernel() -> u32 {
    let var = [1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4];
    let mut ekf = Mekf::new(quat::IDENTITY, var);
    // A level wings-level interval: f̄ ≈ −g, residual of a few cm/s².
    let f = [0.2f32, -0.1, -9.81];
    let h = [[0.0, f[2], -f[1]], [-f[2], 0.0, f[0]], [f[1], -f[0], 0.0]];
    let t = crate::board::stopwatch();
    for i in 0..N {
        let y = [0.01 * (i % 3) as f32, -0.02, 0.005];
        black_box(ekf.fuse(black_box(y), &h, [4e-3; 3], f32::INFINITY));
    }
    let fuse = crate::board::elapsed(t) / N;
    fuse
}
