//! Real PX4 flights (shared/data/real): replay end to end through the core and
//! report agreement with the autopilot's own attitude (`ref_*`, not truth).
//! Skips with a message when the data is absent.
use sim_harness::estimate::replay_estimates;
use sim_harness::metrics::{compare, Against};
use sim_harness::{csv, data};
use wing_ahrs::{Config, Model};

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// Std of (GPS course − ref yaw) over fixes faster than 5 m/s after 20 s, degrees:
/// the crab/sideslip angle the yaw measurement itself carries, independent of the filter.
fn course_vs_ref_std(log: &sim_harness::log::FlightLog) -> f64 {
    let s = course_vs_ref_std_quiet(log);
    println!("course − ref_yaw (fixes > 5 m/s after 20 s): std {s:.2}° (wind crab + sideslip: the limit of a course-based yaw)");
    s
}

fn course_vs_ref_std_quiet(log: &sim_harness::log::FlightLog) -> f64 {
    let d: Vec<f64> = log
        .rows
        .iter()
        .filter(|r| r.t > 20.0)
        .filter_map(|r| {
            let g = r.gps?;
            let rf = r.reference?;
            (g.vel[0].hypot(g.vel[1]) > 5.0)
                .then(|| sim_harness::metrics::wrap(g.vel[1].atan2(g.vel[0]) - rf[2]) * DEG)
        })
        .collect();
    sim_harness::metrics::Stats::of(&d).std
}

/// The real flights that are present, by name; the absent ones skip `test`, saying so.
fn real_logs(test: &str) -> Vec<(&'static str, sim_harness::log::FlightLog)> {
    let mut out = Vec::new();
    for name in data::REAL_FLIGHTS {
        let Some(path) = data::real_log(name) else {
            let why = format!("{name} not found (set WING_AHRS_DATA or provide ../shared/data)");
            data::skip(test, &why);
            continue;
        };
        out.push((name, csv::read_log(&path).unwrap()));
    }
    out
}

#[test]
fn real_flights_replay_and_agree_with_autopilot() {
    for (name, log) in real_logs("real_flights_replay_and_agree_with_autopilot") {
        // IMU ≈145 Hz irregular, GPS 5 Hz.
        let n_gps = log.rows.iter().filter(|r| r.gps.is_some()).count();
        let dur = log.rows.last().unwrap().t - log.rows[0].t;
        assert!(log.rows.len() as f64 / dur > 100.0 && (n_gps as f64 / dur - 5.0).abs() < 1.0);
        let _ = course_vs_ref_std(&log);
        for (label, model) in
            [("Ekf1", Model::Ekf1(Default::default())), ("Ekf2", Model::Ekf2(Default::default()))]
        {
            let (est, ahrs) = replay_estimates(&log, Config::euler().with_model(model));
            assert_eq!(est.len(), log.rows.len());
            assert!(
                est.iter().all(|e| e.att.iter().chain(&e.bias).chain(&e.sd).all(|v| v.is_finite())),
                "{name} {label}: non-finite estimate"
            );
            let h = ahrs.health();
            assert!(
                h.updates as usize > n_gps / 2,
                "{name} {label}: only {} updates for {n_gps} fixes",
                h.updates
            );
            let c = compare(&log, &est, 20.0).unwrap();
            assert_eq!(c.against, Against::Reference);
            let s = c.att.map(|x| x.scaled(DEG));
            println!(
                "{name} {label}: agreement vs ref_* (from 20 s): std {:.2}/{:.2}/{:.2}°, mean {:.2}/{:.2}/{:.2}°, RMS {:.2}/{:.2}/{:.2}° (thesis vs MTi-G std 2.08/2.21/8.27°); gate rejections {:?}",
                s[0].std, s[1].std, s[2].std, s[0].mean, s[1].mean, s[2].mean, s[0].rms, s[1].rms, s[2].rms, h.gate_rejections
            );
            // Sanity bounds only (see the README for the measured figures and why the
            // default's 1° R with χ² gating rejects most real updates). Yaw: the estimator
            // measures yaw as the GPS course, so it cannot agree with the autopilot's
            // (magnetometer) heading better than the course does; allow that spread + 5°.
            let lim = course_vs_ref_std_quiet(&log) + 5.0;
            // EKF1 with the defaults measures ≤ 5.8° (README); with the earlier 1° R the gates
            // rejected ~90 % of real updates and EKF1 reached 11.7° — this bound catches that.
            // EKF2 (windowed, ground mode, airborne hold) measures ≤ 5.5°; the thesis form
            // loses roll on flight b (47° std, max 180°) — this bound catches that.
            assert!(s[0].std < 7.0 && s[1].std < 7.0, "{name} {label}: {s:?}");
            if matches!(model, Model::Ekf1(_)) {
                assert!(
                    s[2].std < lim,
                    "{name}: yaw agreement std {:.1}° > course-vs-ref std + 5° = {lim:.1}°",
                    s[2].std
                );
            }
        }
    }
}

/// The default filter's heading on the real flights does not depend on luck at the
/// start: begun at a latency of 0 or at the latency measured offline from the log
/// (`latency::estimate`), the heading stays with the autopilot's. Before the direct
/// heading solution (`mekf/heading_accel.rs`) a linear update with a 57° heading σ
/// turned flight b's heading 150° on the launch jolt when started at the measured
/// 0.255 s: 74.5° RMS against 11.3° from 0. The bound is the course's own spread
/// against the (magnetometer) reference plus 10°.
#[test]
fn default_filter_keeps_the_real_heading_from_any_starting_latency() {
    for (name, log) in real_logs("default_filter_keeps_the_real_heading_from_any_starting_latency")
    {
        let measured = sim_harness::latency::estimate(&log, sim_harness::latency::MAX_S)
            .expect("the real flights' latency is measurable")
            .latency_s;
        let lim = course_vs_ref_std_quiet(&log) + 10.0;
        for start in [0.0, measured] {
            let cfg = Config { gps_latency: start as f32, ..Config::default() };
            let (est, _) = replay_estimates(&log, cfg);
            let s = compare(&log, &est, 20.0).unwrap().att.map(|x| x.scaled(DEG));
            println!(
                "{name} default, latency from {start:.3} s: RMS {:.2}/{:.2}/{:.2}° (yaw bound {lim:.1}°)",
                s[0].rms, s[1].rms, s[2].rms
            );
            assert!(
                s[2].rms < lim,
                "{name} from {start:.3} s: yaw RMS {:.1}° ≥ {lim:.1}°",
                s[2].rms
            );
            assert!(s[0].rms < 7.0, "{name} from {start:.3} s: roll RMS {:.1}°", s[0].rms);
        }
    }
}
