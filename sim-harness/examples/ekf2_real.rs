//! PX4 EKF2 on one log (a real log against its reference, or a simulated one against
//! truth) with one input changed at a time: the evidence of docs/peers.md's reasons table
//! for EKF2's real-log rows. Prints the tilt RMS (and roll / pitch RMS) over `compare`'s own
//! statistics window for each variant, and ours for scale. First, the log's IMU intervals
//! and EKF2 at PX4's 10 ms `EKF2_PREDICT_US` against the set-up's (the log's period where
//! longer): tilt, its mean vertical GNSS-velocity innovation, the share of fixes whose
//! velocity it rejected, and its yaw resets, over the window.
//! `cargo run --release -p sim-harness --example ekf2_real -- LOG [defaults|matched] [FROM_S]`
//! (FROM_S: score from this many seconds after the log's start instead of 30 s).
use anyhow::{bail, Result};
use sim_harness::compare::{nominal_dt, Against};
use sim_harness::log::FlightLog;
use sim_harness::metrics::tilt_error;
use sim_harness::peers::px4_ekf2::Px4Ekf2;
use sim_harness::peers::px4_ekf2_feed as feed;
use sim_harness::peers::setup::{SensorFigures, Setup, Tuning};
use sim_harness::peers::wing::Wing;
use sim_harness::peers::Estimator;

/// Tilt, roll and pitch RMS, deg, of `est` over `log` between `from` and `to` s.
fn score(
    log: &FlightLog,
    est: &mut dyn Estimator,
    against: Against,
    from: f64,
    to: f64,
) -> [f64; 3] {
    let (mut ss, mut n) = ([0.0; 3], 0usize);
    for row in &log.rows {
        est.step(row);
        let want = match against {
            Against::Truth => row.truth,
            Against::Reference => row.reference,
        };
        let Some(want) = want else { continue };
        if row.t < from || row.t > to {
            continue;
        }
        let got = est.attitude();
        let e = [
            tilt_error(got, want),
            sim_harness::metrics::wrap(got[0] - want[0]),
            sim_harness::metrics::wrap(got[1] - want[1]),
        ];
        for i in 0..3 {
            ss[i] += e[i] * e[i];
        }
        n += 1;
    }
    ss.map(|s| (s / n.max(1) as f64).sqrt().to_degrees())
}

/// EKF2 with prediction period `predict_us` over `log`, between `from` and `to` s: tilt RMS
/// (deg), mean vertical GNSS-velocity innovation (m/s), share of fixes with the velocity
/// rejected, and its attitude resets (the yaw estimator's emergency resets).
fn innovations(
    log: &FlightLog,
    setup: &Setup,
    predict_us: i32,
    against: Against,
    from: f64,
    to: f64,
) -> (f64, f64, f64, u32) {
    let mut e = Px4Ekf2::with_setup(setup);
    e.ekf_mut().params_mut().set_predict_interval_us(predict_us);
    e.ekf_mut().update_parameters();
    let (mut ss, mut n, mut vd, mut rejected, mut fixes, mut resets) = (0.0, 0, 0.0, 0, 0, 0);
    let (mut last_fix, mut last_reset) = (0u64, 0u8);
    for row in &log.rows {
        e.step(row);
        let k = e.ekf();
        let reset = std::mem::replace(&mut last_reset, k.quat_reset_count());
        let want = match against {
            Against::Truth => row.truth,
            Against::Reference => row.reference,
        };
        let Some(want) = want.filter(|_| row.t >= from && row.t <= to) else { continue };
        resets += u32::from(last_reset.wrapping_sub(reset));
        let v = k.aid_src_gnss_vel();
        if v.timestamp_sample != std::mem::replace(&mut last_fix, v.timestamp_sample) {
            vd += f64::from(v.innovation[2]);
            rejected += usize::from(v.innovation_rejected);
            fixes += 1;
        }
        ss += tilt_error(e.attitude(), want).powi(2);
        n += 1;
    }
    let f = fixes.max(1) as f64;
    ((ss / n.max(1) as f64).sqrt().to_degrees(), vd / f, rejected as f64 / f, resets)
}

/// Sets one of EKF2's noise figures.
type SetNoise = fn(&mut feed::Noise);

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        bail!("usage: ekf2_real LOG [defaults|matched]");
    };
    let tuning = match args.get(1).map(String::as_str) {
        None | Some("matched") => Tuning::Matched,
        Some("defaults") => Tuning::Defaults,
        Some(o) => bail!("configuration {o:?}: use defaults or matched"),
    };
    let log = sim_harness::import::load_any(std::path::Path::new(path))?;
    let truth = log.rows.iter().any(|r| r.truth.is_some());
    let against = if truth { Against::Truth } else { Against::Reference };
    let figures = if truth { SensorFigures::thesis() } else { SensorFigures::realistic() };
    // As `compare`: a real log has no spec and runs as shipped.
    let tuning = if truth { tuning } else { Tuning::Defaults };
    let t0 = log.rows[0].t;
    let start: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(30.0);
    let (mut from, mut to) = (t0 + start, f64::INFINITY);
    if against == Against::Reference {
        let (takeoff, landing) = sim_harness::real_logs::airborne(&log);
        if let Some(t) = takeoff {
            from = from.max(t + sim_harness::real_logs::AFTER_TAKEOFF);
        }
        to = landing.unwrap_or(to);
    }
    let dt = nominal_dt(&log);
    let setup = Setup::for_log(&log, dt, tuning, figures);
    let lat = sim_harness::latency::estimate(&log, sim_harness::latency::MAX_S);
    println!(
        "{path}: {} rows, dt {:.4} s, window {from:.0}–{to:.0} s, in-air start {}, logged latency {:.3} s (median), measured {:?}",
        log.rows.len(),
        dt,
        setup.in_air_start,
        setup.latency,
        lat.map(|e| (e.latency_s, e.corr))
    );
    let p = |name: &str, v: [f64; 3]| {
        println!("{name:55} tilt {:6.3}°  roll {:6.3}°  pitch {:6.3}°", v[0], v[1], v[2])
    };
    let mut iv: Vec<f64> = log.rows.windows(2).map(|w| w[1].t - w[0].t).collect();
    iv.sort_by(f64::total_cmp);
    let q = |p: f64| 1e3 * iv[((iv.len() - 1) as f64 * p) as usize];
    // EKF2 adds gravity over each interval clamped to twice its period: what is left out.
    let limit = 2e-6 * f64::from(feed::PREDICT_US);
    let cut: f64 = iv.iter().map(|d| (d - limit).max(0.0)).sum();
    println!(
        "IMU intervals 1–50–99 %: {:.1}–{:.1}–{:.1} ms; {:.0} % over {:.0} ms (twice PX4's EKF2_PREDICT_US), gravity left out there {:.2} m/s² on average",
        q(0.01),
        q(0.5),
        q(0.99),
        100.0 * iv.iter().filter(|d| **d > limit).count() as f64 / iv.len() as f64,
        1e3 * limit,
        9.80665 * cut / iv.iter().sum::<f64>()
    );
    for predict_us in [feed::PREDICT_US, setup.ekf2().predict_us] {
        let (tilt, vd, rejected, resets) = innovations(&log, &setup, predict_us, against, from, to);
        println!(
            "EKF2, EKF2_PREDICT_US {predict_us} µs: tilt {tilt:.3}°, mean vertical velocity innovation {vd:+.2} m/s, velocity rejected at {:.0} % of fixes, {resets} yaw resets",
            100.0 * rejected
        );
    }
    p("ours", score(&log, &mut Wing::ekf1_with(&setup), against, from, to));
    p("EKF2 as in compare", score(&log, &mut Px4Ekf2::with_setup(&setup), against, from, to));
    let variant = |f: &dyn Fn(&mut sim_harness::log::LogRow)| {
        let mut l = log.clone();
        l.rows.iter_mut().for_each(f);
        l
    };
    let no_asp = variant(&|r| r.airspeed = None);
    p("EKF2, no airspeed", score(&no_asp, &mut Px4Ekf2::with_setup(&setup), against, from, to));
    let mut no_beta = Px4Ekf2::with_setup(&setup);
    no_beta.ekf_mut().params_mut().set_sideslip_fusion_enabled(false);
    no_beta.ekf_mut().update_parameters();
    p("EKF2, no synthetic sideslip", score(&log, &mut no_beta, against, from, to));
    let mut neither = Px4Ekf2::with_setup(&setup);
    neither.ekf_mut().params_mut().set_sideslip_fusion_enabled(false);
    neither.ekf_mut().update_parameters();
    p("EKF2, no sideslip, no airspeed", score(&no_asp, &mut neither, against, from, to));
    // EKF2_GSF_TAS: the airspeed its yaw estimator assumes without an airspeed sensor
    // (PX4: 15 m/s), at the log's median ground speed in flight.
    let mut speeds: Vec<f64> = log
        .rows
        .iter()
        .filter_map(|r| r.gps.map(|g| g.vel[0].hypot(g.vel[1])))
        .filter(|v| *v > 10.0)
        .collect();
    speeds.sort_by(f64::total_cmp);
    if let Some(&v) = speeds.get(speeds.len() / 2) {
        let mut g = Px4Ekf2::with_setup(&setup);
        g.ekf_mut().params_mut().set_gsf_tas_default_m_s(v as f32);
        g.ekf_mut().update_parameters();
        p(&format!("EKF2, EKF2_GSF_TAS {v:.1} m/s (15)"), score(&log, &mut g, against, from, to));
    }
    let no_baro = variant(&|r| r.baro_alt = None);
    p("EKF2, no barometer", score(&no_baro, &mut Px4Ekf2::with_setup(&setup), against, from, to));
    for ms in [50.0, 100.0, 150.0, 200.0, 250.0] {
        let shifted = variant(&|r| {
            if let Some(g) = r.gps.as_mut() {
                g.t -= ms * 1e-3;
            }
        });
        // The shifted epochs as given, not replaced by the measured latency.
        let mut s = Setup::for_log(&shifted, dt, tuning, figures);
        s.epochs_from_latency = false;
        s.latency = sim_harness::latency::logged(&shifted);
        p(
            &format!("EKF2, fixes' epoch {ms:.0} ms before arrival"),
            score(&shifted, &mut Px4Ekf2::with_setup(&s), against, from, to),
        );
    }
    if tuning == Tuning::Matched {
        let base = setup.ekf2();
        let n = base.noise.expect("matched");
        // PX4's defaults for one figure at a time (docs/peers.md's table).
        let keep: [(&str, SetNoise); 6] = [
            ("EKF2_GYR_NOISE", |n| n.gyro = 0.015),
            ("EKF2_ACC_NOISE", |n| n.accel = 0.35),
            ("EKF2_GYR_B_NOISE", |n| n.gyro_bias = 1e-3),
            ("EKF2_GBIAS_INIT", |n| n.gyro_bias_init = 0.1),
            ("EKF2_GPS_V_NOISE", |n| n.gps_vel = 0.3),
            ("EKF2_EAS_NOISE", |n| n.eas = 1.4),
        ];
        for (name, f) in keep {
            let mut m = n;
            f(&mut m);
            let params = feed::Params { noise: Some(m), ..base };
            p(
                &format!("EKF2 matched, {name} at PX4's default"),
                score(&log, &mut Px4Ekf2::with_params(dt, &params), against, from, to),
            );
        }
        println!("matched figures handed to EKF2: {n:?}");
    }
    // The real-log matrix of docs/peers.md: the `realistic` spec's figures or as shipped,
    // each with the fix's arrival as its epoch (no measured latency) or the measured one.
    if !truth {
        for t in [Tuning::Matched, Tuning::Defaults] {
            for measured in [false, true] {
                let mut s = Setup::for_log(&log, dt, t, figures);
                if !measured {
                    s.epochs_from_latency = false;
                    s.latency = sim_harness::latency::logged(&log);
                }
                let what = format!(
                    "EKF2, {}, {}",
                    if t == Tuning::Matched { "the realistic spec" } else { "as shipped" },
                    if measured { "measured latency" } else { "fix epoch = arrival" }
                );
                p(&what, score(&log, &mut Px4Ekf2::with_setup(&s), against, from, to));
            }
        }
    }
    let other = if tuning == Tuning::Matched { Tuning::Defaults } else { Tuning::Matched };
    let s = Setup::for_log(&log, dt, other, figures);
    p(
        &format!("EKF2, {}", other.label()),
        score(&log, &mut Px4Ekf2::with_setup(&s), against, from, to),
    );
    Ok(())
}
