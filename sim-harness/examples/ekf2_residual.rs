//! EKF2's residual tilt after convergence, one mechanism at a time (docs/peers.md, the
//! reasons table): PX4 EKF2 in the matched configuration on one `compare` item, scored from
//! FROM s (default 120) against truth, with one input, parameter or sensor error changed at
//! a time. Diagnostics only — no variant is a table entry.
//!
//! `cargo run --release -p sim-harness --example ekf2_residual -- ITEM [--from S] [--seed N] [--trace STEP]`
//!
//! Each line: tilt / roll / pitch RMS, yaw RMS, EKF2's own tilt σ (mean of √`tilt_variance`),
//! its accelerometer-bias estimate (mean over the window; the simulated sensors have none),
//! and the mean innovation test ratios of airspeed (`tas`) and synthetic sideslip (`beta`).
//! Variants:
//! - `perfect sensors`: the same flight through a sensor model with no noise, no bias, no
//!   turn-on offset (JSBSim flights and simulator scenarios; EKF2's tuning unchanged);
//! - `heading from truth`: EKF2's yaw reset to truth (at its delayed fusion time) every
//!   second, σ 0.01 rad: a perfect heading sensor;
//! - the airspeed, sideslip and accelerometer-bias switches.
//!
//! `--trace STEP`: the as-compared run every STEP s (tilt, roll, pitch and yaw error, σ,
//! accelerometer bias, horizontal-velocity / airspeed / sideslip test ratios, true sideslip).
use anyhow::{bail, Result};
use ekf2::params::ImuControl;
use ekf2::Ekf;
use sim_harness::compare::{nominal_dt, Item, ItemKind};
use sim_harness::log::{FlightLog, LogRow};
use sim_harness::metrics::{tilt_error, wrap};
use sim_harness::peers::px4_ekf2::Px4Ekf2;
use sim_harness::peers::setup::{Setup, Tuning};
use sim_harness::peers::wing::Wing;
use sim_harness::peers::Estimator;
use sim_harness::sim::rotation;
use sim_harness::sim::sensors::SensorParams;

/// A change to EKF2's parameters before its first sample.
type Tweak = fn(&mut Ekf<'static>);

#[derive(Default)]
struct Acc {
    n: usize,
    ss: [f64; 4],
    sigma: f64,
    abias: [f64; 3],
    tas: (f64, usize),
    beta: (f64, usize),
}

fn rms(s: f64, n: usize) -> f64 {
    (s / n.max(1) as f64).sqrt().to_degrees()
}

/// The true sideslip at a fix row, rad: the air-relative velocity (fix velocity − true wind)
/// in the true body frame.
fn true_beta(row: &LogRow) -> Option<f64> {
    let (g, w, a) = (row.gps?, row.truth_wind?, row.truth?);
    let v = [g.vel[0] - w[0], g.vel[1] - w[1], g.vel[2] - w[2]];
    let [vx, vy, _] = rotation::mul_mv(&rotation::r_bn(a[0], a[1], a[2]), v);
    (vx > 5.0).then(|| vy.atan2(vx))
}

/// Runs EKF2 over `log`; scores from `from`; `heading` resets its yaw to truth every second.
fn run(
    log: &FlightLog,
    setup: &Setup,
    tweak: Option<Tweak>,
    heading: bool,
    from: f64,
    trace: Option<f64>,
) -> Acc {
    let mut e = Px4Ekf2::with_setup(setup);
    if let Some(f) = tweak {
        f(e.ekf_mut());
        e.ekf_mut().update_parameters();
    }
    run_with(log, e, heading, from, trace)
}

/// As [`run`], for an EKF2 already set up.
fn run_with(log: &FlightLog, mut e: Px4Ekf2, heading: bool, from: f64, trace: Option<f64>) -> Acc {
    let mut acc = Acc::default();
    let mut next_reset = log.rows[0].t + 1.0;
    let mut next_trace = log.rows[0].t;
    let delay = f64::from(e.ekf().params().delay_max_ms()) * 1e-3;
    let mut history: std::collections::VecDeque<(f64, f64)> = Default::default();
    if trace.is_some() {
        println!("| t | tilt | roll err | pitch err | yaw err | tilt σ | accel bias | hvel / tas / beta test ratio | true β | fusing |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
    }
    for row in &log.rows {
        e.step(row);
        let Some(want) = row.truth else { continue };
        history.push_back((row.t, want[2]));
        while history.len() > 2 && history[1].0 <= row.t - delay {
            history.pop_front();
        }
        if heading && row.t >= next_reset {
            // EKF2's states lie at its delayed fusion horizon, EKF2_DELAY_MAX behind.
            e.ekf_mut().reset_heading_to_external_observation(history[0].1 as f32, 0.01);
            next_reset += 1.0;
        }
        let a = e.attitude();
        let k = e.ekf();
        if let Some(step) = trace {
            if row.t >= next_trace {
                next_trace += step;
                let b = k.accel_bias();
                println!(
                    "| {:.0} | {:.2}° | {:+.2}° | {:+.2}° | {:+.1}° | {:.2}° | [{:+.3}, {:+.3}, {:+.3}] | {:.2} / {:.2} / {:.2} | {} | {} |",
                    row.t - log.rows[0].t,
                    tilt_error(a, want).to_degrees(),
                    wrap(a[0] - want[0]).to_degrees(),
                    wrap(a[1] - want[1]).to_degrees(),
                    wrap(a[2] - want[2]).to_degrees(),
                    f64::from(k.tilt_variance()).sqrt().to_degrees(),
                    b[0],
                    b[1],
                    b[2],
                    k.horiz_vel_innov_test_ratio(),
                    k.airspeed_innov_test_ratio(),
                    k.sideslip_innov_test_ratio(),
                    true_beta(row).map_or("".into(), |b| format!("{:+.2}°", b.to_degrees())),
                    fusing(k),
                );
            }
        }
        if row.t < from {
            continue;
        }
        let err =
            [tilt_error(a, want), wrap(a[0] - want[0]), wrap(a[1] - want[1]), wrap(a[2] - want[2])];
        for i in 0..4 {
            acc.ss[i] += err[i] * err[i];
        }
        acc.n += 1;
        acc.sigma += f64::from(k.tilt_variance()).sqrt();
        let b = k.accel_bias();
        for i in 0..3 {
            acc.abias[i] += f64::from(b[i]);
        }
        let (tas, beta) = (k.airspeed_innov_test_ratio(), k.sideslip_innov_test_ratio());
        if tas > 0.0 {
            acc.tas.0 += f64::from(tas);
            acc.tas.1 += 1;
        }
        if beta > 0.0 {
            acc.beta.0 += f64::from(beta);
            acc.beta.1 += 1;
        }
    }
    acc
}

/// EKF2's aiding as letters: yaw aligned, GNSS velocity and position, airspeed, sideslip,
/// fake position, wind dead reckoning.
fn fusing(k: &Ekf<'static>) -> String {
    use ekf2::params::ControlStatus as C;
    let c = k.control_status();
    [
        (C::YAW_ALIGN, "yaw"),
        (C::GNSS_VEL, "vel"),
        (C::GNSS_POS, "pos"),
        (C::FUSE_ASPD, "aspd"),
        (C::FUSE_BETA, "beta"),
        (C::FAKE_POS, "FAKE"),
        (C::WIND_DEAD_RECKONING, "WIND-DR"),
    ]
    .iter()
    .filter(|(f, _)| c.contains(*f))
    .map(|(_, n)| *n)
    .collect::<Vec<_>>()
    .join(" ")
}

fn print(name: &str, a: &Acc) {
    let n = a.n.max(1) as f64;
    println!(
        "| {name} | {:.3}° | {:.3}° | {:.3}° | {:.2}° | {:.3}° | [{:+.3}, {:+.3}, {:+.3}] | {:.2} / {:.2} |",
        rms(a.ss[0], a.n),
        rms(a.ss[1], a.n),
        rms(a.ss[2], a.n),
        rms(a.ss[3], a.n),
        (a.sigma / n).to_degrees(),
        a.abias[0] / n,
        a.abias[1] / n,
        a.abias[2] / n,
        a.tas.0 / a.tas.1.max(1) as f64,
        a.beta.0 / a.beta.1.max(1) as f64,
    );
}

/// The item's flight through perfect sensors (no noise, bias or turn-on offset), if it can
/// be regenerated: a JSBSim flight from its truth file, a simulator scenario with its
/// sensor model zeroed.
fn perfect(item: &Item, seed: u64) -> Result<Option<FlightLog>> {
    let zero = |mut p: SensorParams| {
        p.imu.gyro_noise_deg_s = 0.0;
        p.imu.gyro_turn_on_bias_deg_s = 0.0;
        p.imu.gyro_bias_gm_sigma_deg_h = 0.0;
        p.imu.gyro_bias_rw_deg_s_per_sqrt_s = 0.0;
        p.imu.accel_noise_m_s2 = 0.0;
        p.imu.accel_turn_on_bias_m_s2 = 0.0;
        p.imu.accel_bias_gm_sigma_m_s2 = 0.0;
        p.gps.vel_noise_ne_m_s = 0.0;
        p.gps.vel_noise_d_m_s = 0.0;
        p.airspeed.noise_m_s = 0.0;
        p.airspeed.bias_m_s = 0.0;
        p
    };
    if let Some(name) = item.name.strip_prefix("jsbsim:") {
        let truth = sim_harness::jsbsim::log_path(name).with_extension("truth.csv");
        return Ok(Some(sim_harness::jsbsim::export(&truth, &zero(SensorParams::thesis()), seed)?));
    }
    if let ItemKind::Simulated(sc) = &item.kind {
        let mut sc = (**sc).clone();
        sc.sensors = zero(sc.sensors);
        return Ok(Some(sim_harness::sim::run(&sc, seed)?.log));
    }
    Ok(None)
}

fn main() -> Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut opt = |flag: &str| {
        let k = args.iter().position(|a| a == flag)?;
        let v = args.get(k + 1).and_then(|s| s.parse::<f64>().ok());
        args.drain(k..(k + 2).min(args.len()));
        v
    };
    let from_s = opt("--from").unwrap_or(120.0);
    let seed = opt("--seed").map_or(1, |s| s as u64);
    let trace = opt("--trace");
    let Some(name) = args.first() else {
        bail!("usage: ekf2_residual ITEM [--from S] [--seed N] [--trace STEP]");
    };
    let item = Item::resolve(name)?;
    let Some((log, _)) = item.log(seed)? else { bail!("{name}: no log") };
    if !log.rows.iter().any(|r| r.truth.is_some()) {
        bail!("{name}: no truth (simulated and JSBSim flights only)");
    }
    let setup = Setup::for_log(&log, nominal_dt(&log), Tuning::Matched, item.figures());
    let t0 = log.rows[0].t;
    let from = t0 + from_s;
    // Ours, for scale.
    let (mut ss, mut n) = (0.0, 0usize);
    let mut w = Wing::ekf1_with(&setup);
    for row in &log.rows {
        w.step(row);
        if let (Some(want), true) = (row.truth, row.t >= from) {
            let e = tilt_error(w.attitude(), want);
            ss += e * e;
            n += 1;
        }
    }
    let betas: Vec<f64> = log.rows.iter().filter(|r| r.t >= from).filter_map(true_beta).collect();
    let beta_rms = (betas.iter().map(|b| b * b).sum::<f64>() / betas.len().max(1) as f64).sqrt();
    println!(
        "{}: seed {seed}, from {from_s:.0} s; ours tilt {:.3}°; true sideslip RMS {:.2}° (at the fixes)",
        item.name,
        rms(ss, n),
        beta_rms.to_degrees()
    );
    if let Some(step) = trace {
        run(&log, &setup, None, false, from, Some(step));
        return Ok(());
    }
    if let Some(k) = args.iter().position(|a| a == "--abias-init") {
        // EKF2_ABIAS_INIT (m/s²) values, comma-separated, with EKF2_ACC_B_NOISE at the spec's.
        let list: Vec<f32> = args
            .get(k + 1)
            .map_or(vec![], |s| s.split(',').filter_map(|v| v.parse().ok()).collect());
        for init in list {
            let mut e = Px4Ekf2::with_setup(&setup);
            e.ekf_mut().params_mut().set_accel_bias_init(init);
            e.ekf_mut().update_parameters();
            print(&format!("EKF2_ABIAS_INIT {init}"), &run_with(&log, e, false, from, None));
        }
        return Ok(());
    }
    println!("| EKF2 variant | tilt | roll | pitch | yaw | own tilt σ | accel bias (m/s²) | tas / beta test ratio |");
    println!("|---|---|---|---|---|---|---|---|");
    let no_asp = {
        let mut l = log.clone();
        l.rows.iter_mut().for_each(|r| r.airspeed = None);
        l
    };
    let no_beta: Tweak = |k| k.params_mut().set_sideslip_fusion_enabled(false);
    let no_abias: Tweak = |k| k.params_mut().set_imu_control(ImuControl::GYRO_BIAS);
    let abias_spec: Tweak = |k| {
        // The spec has no accelerometer bias: EKF2's bias states nearly frozen at zero.
        k.params_mut().set_accel_bias_noise(1e-5);
        k.params_mut().set_accel_bias_init(1e-3);
    };
    let px4_params: Tweak = |k| {
        // PX4's parameter-file defaults where the C++ struct's initialisers differ.
        let mut p = k.params_mut();
        p.set_accel_bias_noise(3e-3);
        p.set_wind_nsd(5e-2);
        p.set_baro_noise(3.5);
        p.set_hgt_ref(ekf2::params::HeightReference::Gnss);
    };
    let both: Tweak = |k| {
        k.params_mut().set_sideslip_fusion_enabled(false);
    };
    print("as compared (matched)", &run(&log, &setup, None, false, from, None));
    print("no synthetic sideslip", &run(&log, &setup, Some(no_beta), false, from, None));
    print("no airspeed", &run(&no_asp, &setup, None, false, from, None));
    print("no airspeed, no sideslip", &run(&no_asp, &setup, Some(both), false, from, None));
    print("accel-bias learning off", &run(&log, &setup, Some(no_abias), false, from, None));
    print(
        "accel-bias noise at the spec's (≈0)",
        &run(&log, &setup, Some(abias_spec), false, from, None),
    );
    print(
        "PX4 param-file defaults (ACC_B, WIND_NSD, BARO, HGT_REF)",
        &run(&log, &setup, Some(px4_params), false, from, None),
    );
    let abias_zero: Tweak = |k| {
        k.params_mut().set_accel_bias_noise(0.0);
        k.params_mut().set_accel_bias_init(0.0);
    };
    print(
        "accel-bias noise and init exactly 0",
        &run(&log, &setup, Some(abias_zero), false, from, None),
    );
    let sweep: [(&str, Tweak); 5] = [
        ("EKF2_ACC_B_NOISE 1e-2 (the C++ struct's), ABIAS_INIT 0.2", |k| {
            k.params_mut().set_accel_bias_noise(1e-2);
            k.params_mut().set_accel_bias_init(0.2);
        }),
        ("EKF2_ACC_B_NOISE 3e-3 (PX4's parameter), ABIAS_INIT 0.2", |k| {
            k.params_mut().set_accel_bias_noise(3e-3);
            k.params_mut().set_accel_bias_init(0.2);
        }),
        ("EKF2_ACC_B_NOISE 1e-3, ABIAS_INIT 0.2", |k| {
            k.params_mut().set_accel_bias_noise(1e-3);
            k.params_mut().set_accel_bias_init(0.2);
        }),
        ("EKF2_ACC_B_NOISE 3e-4, ABIAS_INIT 0.2", |k| {
            k.params_mut().set_accel_bias_noise(3e-4);
            k.params_mut().set_accel_bias_init(0.2);
        }),
        ("EKF2_ACC_B_NOISE 0, ABIAS_INIT 0.2", |k| {
            k.params_mut().set_accel_bias_noise(0.0);
            k.params_mut().set_accel_bias_init(0.2);
        }),
    ];
    for (name, t) in sweep {
        print(name, &run(&log, &setup, Some(t), false, from, None));
    }
    print("heading from truth every 1 s", &run(&log, &setup, None, true, from, None));
    print(
        "heading from truth, accel-bias noise ≈0",
        &run(&log, &setup, Some(abias_spec), true, from, None),
    );
    print("heading from truth, no sideslip", &run(&log, &setup, Some(no_beta), true, from, None));
    if let Some(p) = perfect(&item, seed)? {
        let ps = Setup::for_log(&p, nominal_dt(&p), Tuning::Matched, item.figures());
        print("perfect sensors", &run(&p, &ps, None, false, from, None));
        print("perfect sensors, no sideslip", &run(&p, &ps, Some(no_beta), false, from, None));
        let mut pa = p.clone();
        pa.rows.iter_mut().for_each(|r| r.airspeed = None);
        print(
            "perfect sensors, no airspeed, no sideslip",
            &run(&pa, &ps, Some(both), false, from, None),
        );
        print("perfect sensors, heading from truth", &run(&p, &ps, None, true, from, None));
    }
    Ok(())
}
