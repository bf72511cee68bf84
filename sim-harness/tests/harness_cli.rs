//! The CLI end to end: simulate → replay writes the estimate CSV contract; bad input
//! gives a one-line error and exit code 1, never a panic or backtrace.
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sim-harness"))
}

#[test]
fn simulate_then_replay_writes_the_estimate_contract() {
    let dir = std::env::temp_dir().join(format!("harness_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("f1.csv");
    let est = dir.join("est.csv");
    let o = bin()
        .args(["simulate", "flight1", "--out"])
        .arg(&log)
        .args(["--seed", "3", "--duration", "20"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = bin()
        .arg("replay")
        .arg(&log)
        .arg("--out")
        .arg(&est)
        .args(["--model", "ekf1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("error vs truth"), "{out}");
    let rows = sim_harness::estimate::read_estimates(&est).unwrap();
    let n_log = sim_harness::csv::read_log(&log).unwrap().rows.len();
    assert_eq!(rows.len(), n_log);
    assert!(rows.iter().filter(|r| r.is_update()).count() > 100);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_is_a_clear_error_not_a_panic() {
    let dir = std::env::temp_dir().join(format!("harness_cli_bad_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,-9.8\n0.01,0,x,0,0,0,-9.8\n").unwrap();
    let cases: Vec<Vec<std::ffi::OsString>> = vec![
        vec!["replay".into(), bad.clone().into(), "--out".into(), dir.join("e.csv").into()],
        vec![
            "replay".into(),
            dir.join("missing.csv").into(),
            "--out".into(),
            dir.join("e.csv").into(),
        ],
        vec![
            "simulate".into(),
            "no_such_scenario".into(),
            "--out".into(),
            dir.join("l.csv").into(),
        ],
        vec!["montecarlo".into(), "flight1".into(), "--runs".into(), "0".into()],
        // A ground-station link runs at real time: another speed is refused, before QEMU.
        ["hil", "--seconds", "1", "--live", "--speed", "4"].map(Into::into).to_vec(),
        ["hil", "--seconds", "1", "--mavlink-udp", "nowhere"].map(Into::into).to_vec(),
        // One world of a draw: it must be one of the draw's, and is not the whole suite.
        ["robust", "--worlds", "4", "--world", "4"].map(Into::into).to_vec(),
        vec![
            "robust".into(),
            "--world".into(),
            "0".into(),
            "--doc".into(),
            dir.join("h.md").into(),
        ],
    ];
    for args in cases {
        let o = bin().args(&args).env("RUST_BACKTRACE", "1").output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && !err.contains("panicked") && !err.contains("backtrace"),
            "{args:?}: {err}"
        );
    }
    let o = bin().arg("replay").arg(&bad).arg("--out").arg(dir.join("e.csv")).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("line 3") && err.contains("`gy`"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_configuration_out_of_range_names_its_field() {
    // No CLI range covers --gyro-noise: the core's Config::validate() refuses it, before any
    // input is read.
    let o = bin()
        .args(["replay", "unused.csv", "--out", "unused_e.csv", "--gyro-noise", "0"])
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("error: ")
            && err.contains("`gyro_noise_density`")
            && err.contains("> 0 and finite")
            && !err.contains("panicked"),
        "{err}"
    );
}
