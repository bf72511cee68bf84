//! Host cost of our predict and update, and of every estimator's step, in the same run
//! (criterion prints the figures; compare ratios, the machine is shared and noisy).
//!
//! `cargo bench -p sim-harness --bench cost`

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use sim_harness::log::FlightLog;
use sim_harness::peers::{self, synth};
use sim_harness::replay::fix_for_row;
use std::time::Duration;
use wing_ahrs::ekf::{Ekf, ProcessNoise, VarianceCaps};
use wing_ahrs::{Ahrs, Config};

fn turn_log() -> FlightLog {
    let segs = [(10.0, 0.0), (20.0, 30.0), (10.0, -45.0), (10.0, 0.0)];
    synth::coordinated_turns(20.0, 0.3, &segs, synth::Sensors::thesis(), 3)
}

fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

fn ours(c: &mut Criterion) {
    let log = turn_log();
    let mut g = c.benchmark_group("wing-ahrs");
    // Predict only: on_imu over the log's IMU samples (cycled; time keeps increasing).
    g.bench_function("predict (on_imu)", |b| {
        let mut ahrs = Ahrs::try_new(Config::euler()).expect("a valid configuration");
        let (mut i, mut t_us) = (0usize, 0u64);
        b.iter(|| {
            let r = &log.rows[i % log.rows.len()];
            t_us += 10_000;
            i += 1;
            black_box(ahrs.on_imu(t_us, f32s(r.gyro), f32s(r.accel)))
        })
    });
    // The EKF core alone (no facade bookkeeping): covariance + state propagation, and
    // the three scalar updates — to tell the maths from the measurement models' cost.
    let noise = ProcessNoise {
        gyro_psd: 1e-7,
        bias_psd: 1e-10,
        lambda: 10.0,
        attitude_psd: 0.0,
        inv_tau: 1.0 / 382.0,
    };
    let caps = VarianceCaps { attitude: 10.0, bias: 1.0 };
    g.bench_function("ekf core predict (Ekf::predict)", |b| {
        let mut ekf =
            Ekf::new([0.1, 0.05, 0.3, 0.0, 0.0, 0.0], [1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5]);
        let mut i = 0usize;
        b.iter(|| {
            let r = &log.rows[i % log.rows.len()];
            i += 1;
            black_box(ekf.predict(0.01, f32s(r.gyro), &noise, 0.087, caps));
        })
    });
    g.bench_function("ekf core 3 scalar updates (Ekf::update_axis ×3)", |b| {
        let mut ekf =
            Ekf::new([0.1, 0.05, 0.3, 0.0, 0.0, 0.0], [1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5]);
        b.iter(|| {
            for k in 0..3 {
                black_box(ekf.update_axis(k, black_box(0.1), 3e-4, f32::INFINITY));
            }
            // Keep P from collapsing so every iteration does the same work.
            let mut p = *ekf.covariance();
            for i in 0..3 {
                p[i][i] += 1e-4;
            }
            ekf.set_covariance(p);
        })
    });
    // Predict + EKF1 update: on_imu then on_gps on a GPS row, every iteration.
    let gps_rows: Vec<_> = log.rows.iter().filter(|r| r.gps.is_some()).collect();
    g.bench_function("predict + EKF1 update (on_imu + on_gps)", |b| {
        let mut ahrs = Ahrs::try_new(Config::euler()).expect("a valid configuration");
        let (mut i, mut t_us) = (0usize, 0u64);
        b.iter(|| {
            let r = gps_rows[i % gps_rows.len()];
            i += 1;
            t_us += 100_000;
            ahrs.on_imu(t_us, f32s(r.gyro), f32s(r.accel));
            let mut fix = fix_for_row(r).expect("gps row");
            fix.t_us = t_us;
            black_box(ahrs.on_gps(&fix))
        })
    });
    g.finish();
}

fn per_step(c: &mut Criterion) {
    let log = turn_log();
    let mut g = c.benchmark_group("step (100 Hz IMU, 10 Hz GPS, averaged)");
    for k in 0..peers::all(0.01).len() {
        let mut est = peers::all(0.01).swap_remove(k);
        let name = est.name().to_string();
        // Cycle through the log; restart the estimator (untimed) at the end so time stays monotonic.
        let mut i = 0usize;
        g.bench_function(name, |b| {
            b.iter(|| {
                if i == log.rows.len() {
                    i = 0;
                    est = peers::all(0.01).swap_remove(k);
                }
                est.step(black_box(&log.rows[i]));
                i += 1;
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(20);
    targets = ours, per_step
}
criterion_main!(benches);
