//! Boot-time micro-benchmarks that split the predict cost (QEMU `-icount`:
//! instructions, not cycles): a calibration loop of known length, the Jacobian
//! linearisation, the full `Ekf::predict`, and one `wing_ahrs::math::sin` (f32 only).
//! Reported as NAMED_VALUE_INT (`CAL_20K`, `INS_LIN`, `INS_EKFP`, `INS_SINF`).

use core::hint::black_box;
use wing_ahrs::ekf::{process, Ekf, ProcessNoise, VarianceCaps};

/// Instruction counts measured at boot.
#[derive(Clone, Copy, Debug, Default)]
pub struct Breakdown {
    /// `cortex_m::asm::delay(10_000)`: a 2-instruction loop run 10 001 times = 20 002 instructions (checks the 40-per-tick stopwatch).
    pub calibration: u32,
    /// `process::linearize` (sin/cos of φ, θ + Euler rates, A and B blocks).
    pub linearize: u32,
    /// `Ekf::predict` alone (state + covariance propagation).
    pub ekf_predict: u32,
    /// One `wing_ahrs::math::sin` (the core's f32-only sine).
    pub sinf: u32,
}

const N: u32 = 16;

/// Runs the micro-benchmarks (averages over N calls).
pub fn measure() -> Breakdown {
    let t = crate::board::stopwatch();
    cortex_m::asm::delay(10_000);
    let calibration = crate::board::elapsed_instructions(t);

    let x = [0.3f32, 0.1, 1.0, 0.001, -0.002, 0.003];
    let gyro = [0.05f32, 0.02, 0.1];
    let t = crate::board::stopwatch();
    for _ in 0..N {
        black_box(process::linearize(black_box(&x), black_box(gyro), 0.087));
    }
    let linearize = crate::board::elapsed_instructions(t) / N;

    let noise = ProcessNoise { gyro_psd: 1e-6, bias_psd: 1e-9, lambda: 10.0, attitude_psd: 0.0, inv_tau: 1.0 / 382.0 };
    let caps = VarianceCaps { attitude: 9.8, bias: 1e-2 };
    let mut ekf = Ekf::new(x, [1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4]);
    let t = crate::board::stopwatch();
    for _ in 0..N {
        black_box(ekf.predict(black_box(0.01), black_box(gyro), &noise, 0.087, caps));
    }
    let ekf_predict = crate::board::elapsed_instructions(t) / N;

    let t = crate::board::stopwatch();
    for i in 0..N {
        black_box(wing_ahrs::math::sin(black_box(0.3 + i as f32 * 0.01)));
    }
    let sinf = crate::board::elapsed_instructions(t) / N;
    Breakdown { calibration, linearize, ekf_predict, sinf }
}
