//! The `compare` command end to end: every estimator runs on every requested log, the
//! table and figures are written, the numbers are sane against simulated truth, and bad
//! arguments give a clear error (exit 1, no panic).

use sim_harness::compare::{self, CompareArgs};
use sim_harness::peers;
use std::process::Command;

fn args(scenarios: &[&str], out: &std::path::Path) -> CompareArgs {
    CompareArgs {
        scenarios: scenarios.iter().map(|s| s.to_string()).collect(),
        runs: 2,
        seed: 5,
        warmup: 10.0,
        out: out.to_path_buf(),
    }
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
        assert_eq!(md.matches(&format!("| {n} |")).count(), 2, "{n} has a row per scenario");
    }
    for f in ["turns_errors.png", "turns_errors.svg", "level_errors.png"] {
        assert!(out.join(f).metadata().map(|m| m.len() > 1000).unwrap_or(false), "{f} written");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn real_logs_are_compared_as_agreement_or_skipped() {
    let out = std::env::temp_dir().join(format!("wing-compare-real-{}", std::process::id()));
    let mut a = args(&["real_b"], &out);
    a.runs = 1;
    let res = compare::run(&a).expect("compare runs");
    if sim_harness::data::real_log("px4_2014_flight_b.csv").is_none() {
        let why = "shared/data/real not present; compare skipped the log";
        sim_harness::data::skip("real_logs_are_compared_as_agreement_or_skipped", why);
        assert!(res.is_empty());
        return;
    }
    assert_eq!(res[0].against, compare::Against::Reference);
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    assert!(md.contains("agreement w/ ref"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bad_arguments_fail_cleanly() {
    let bin = env!("CARGO_BIN_EXE_sim-harness");
    for extra in [&["--scenarios", "nosuch"][..], &["--runs", "0"][..]] {
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
