//! The `compare` command end to end: every estimator runs on every requested log, the
//! table and figures are written, the numbers are sane against simulated truth, and bad
//! arguments give a clear error (exit 1, no panic).

use sim_harness::compare::{self, CompareArgs};
use sim_harness::peers;
use std::process::Command;

fn args(scenarios: &[&str], out: &std::path::Path) -> CompareArgs {
    let mut a = CompareArgs::new(scenarios, out);
    a.runs = 2;
    a.seed = 5;
    a
}

#[test]
fn compare_runs_every_estimator_and_writes_table_and_figures() {
    let out = std::env::temp_dir().join(format!("wing-compare-{}", std::process::id()));
    let a = args(&["turns", "level"], &out);
    let res = compare::run(&a).expect("compare runs");
    let names: Vec<String> = peers::all(0.01).iter().map(|e| e.name().to_string()).collect();
    assert_eq!(res.len(), 2);
    for sc in &res {
        assert_eq!(sc.runs, 2, "{}: both Monte Carlo runs pooled", sc.name);
        let got: Vec<&str> = sc.rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(got, names, "{}: every estimator, in order", sc.name);
        for r in &sc.rows {
            let rms = r.stats.rms();
            assert!(
                rms.iter().all(|x| x.is_finite()) && r.stats.ns_per_step() > 0.0,
                "{} on {}",
                r.name,
                sc.name
            );
            // RMS can never exceed the max |error|.
            assert!((0..3).all(|i| rms[i] <= r.stats.max()[i] + 1e-12));
        }
        // Against simulated truth our EKF1 must be accurate (a broken wiring would not be).
        let ours = &sc.rows[0];
        assert!(
            ours.stats.rp_rms().to_degrees() < 1.0,
            "{}: EKF1 roll/pitch RMS {}°",
            sc.name,
            ours.stats.rp_rms().to_degrees()
        );
    }
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    for n in &names {
        let rows =
            md.matches(&format!("| {n} |")).count() + md.matches(&format!("| {n} † |")).count();
        assert_eq!(rows, 2, "{n} has a row per scenario");
    }
    // The peers a user would pick lead the table, right after ours.
    assert_eq!(&names[2..4], [peers::fusion_nav::NAME, peers::px4_ekf2::NAME]);
    // One goal line per scenario, and it agrees with the numbers in the results.
    for sc in &res {
        let met = compare::goal_met(sc).expect("both peers ran");
        let line =
            md.lines().find(|l| l.starts_with(&format!("- {}: ", sc.name))).expect("goal line");
        assert!(line.contains(if met { "**PASS**" } else { "**FAIL**" }), "{line}");
    }
    for f in ["turns_errors.png", "turns_errors.svg", "level_errors.png"] {
        assert!(out.join(f).metadata().map(|m| m.len() > 1000).unwrap_or(false), "{f} written");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A flight-log CSV is an item like a scenario; without `lat`/`lon`/`alt` the navigation
/// peers get a position integrated from the velocities, and the table marks them with †;
/// with them (the simulator writes them) they get the log's and no †.
/// The headline table has ours and both peers.
#[test]
fn a_csv_log_is_compared_and_the_headline_written() {
    let dir = std::env::temp_dir().join(format!("wing-compare-csv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let sc = sim_harness::sim::load_scenario("level").unwrap().with_duration(40.0);
    let log = sim_harness::sim::run(&sc, 3).unwrap().log;
    assert!(log.rows.iter().filter_map(|r| r.gps).all(|g| g.lla.is_some()));
    let mut no_pos = log.clone();
    for g in no_pos.rows.iter_mut().filter_map(|r| r.gps.as_mut()) {
        g.lla = None;
    }
    let csv = dir.join("level40.csv");
    sim_harness::csv::write_log_file(&csv, &no_pos).unwrap();
    let csv_pos = dir.join("level40pos.csv");
    sim_harness::csv::write_log_file(&csv_pos, &log).unwrap();
    let mut a = CompareArgs::new(&[csv.to_str().unwrap(), csv_pos.to_str().unwrap()], &dir);
    a.headline = Some(dir.join("headline.md"));
    let res = compare::run(&a).expect("compare runs");
    assert_eq!(res.len(), 2);
    assert_eq!(res[0].name, "level40");
    assert_eq!(res[0].class, compare::FlightClass::StillAir);
    for name in [peers::fusion_nav::NAME, peers::px4_ekf2::NAME] {
        assert!(compare::find(&res[0], name).unwrap().synthetic_position, "{name}");
        assert!(!compare::find(&res[1], name).unwrap().synthetic_position, "{name}");
    }
    let md = std::fs::read_to_string(dir.join("compare.md")).unwrap();
    assert!(md.contains(&format!("| {} † |", peers::fusion_nav::NAME)), "{md}");
    let h = std::fs::read_to_string(dir.join("headline.md")).unwrap();
    for name in [peers::wing::NAME, peers::fusion_nav::NAME, peers::px4_ekf2::NAME] {
        assert_eq!(h.matches(&format!("| {name} |")).count(), 1, "{h}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn real_logs_are_compared_as_agreement_or_skipped() {
    let out = std::env::temp_dir().join(format!("wing-compare-real-{}", std::process::id()));
    let mut a = args(&["real_b"], &out);
    a.runs = 1;
    let res = compare::run(&a);
    if sim_harness::data::real_log("px4_2014_flight_b.csv").is_none() {
        let why = "shared/data/real not present; compare skipped the log";
        sim_harness::data::skip("real_logs_are_compared_as_agreement_or_skipped", why);
        // Nothing left to compare is an error, not an empty table with exit 0.
        let e = res.expect_err("no data, no table");
        assert!(format!("{e}").contains("nothing was compared"), "{e}");
        return;
    }
    let res = res.expect("compare runs");
    assert_eq!(res[0].against, compare::Against::Reference);
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    assert!(md.contains("agreement w/ ref"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bad_arguments_fail_cleanly() {
    let bin = env!("CARGO_BIN_EXE_sim-harness");
    for extra in [
        &["--scenarios", "nosuch"][..],
        &["nosuch"][..],
        &["no/such.csv"][..],
        &["--runs", "0"][..],
    ] {
        let o = Command::new(bin)
            .arg("compare")
            .args(extra)
            .args(["--out", std::env::temp_dir().to_str().unwrap()])
            .output()
            .expect("run binary");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.starts_with("error:") && !err.contains("panicked"), "{extra:?}: {err}");
    }
}

#[test]
fn converged_is_the_start_of_the_first_ten_seconds_within_one_degree() {
    let d = 1f64.to_radians();
    let tilt: Vec<(f64, f64)> = (0..3000)
        .map(|k| {
            let t = k as f64 * 0.01;
            let e = if t < 5.0 || (12.0..12.5).contains(&t) { 3.0 * d } else { 0.5 * d };
            (t, e)
        })
        .collect();
    // 5–12 s within 1° is too short; from 12.5 s it holds to the end.
    let c = compare::converged_at(0.0, &tilt).expect("converges");
    assert!((c - 12.5).abs() < 0.011, "{c}");
    assert_eq!(compare::converged_at(0.0, &tilt[..1500]), None, "only 2.5 s within 1°");
}
