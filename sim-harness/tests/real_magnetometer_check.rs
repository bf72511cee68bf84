//! The gyro scale-factor states against a sensor no estimator here uses: the magnetometer
//! of two real ArduPlane F3A flights (the two with a clean compass; `sim-harness
//! fetch-logs`). Each flight is replayed with the default filter and with the states, and
//! `tools/magcheck/magcheck.py` fits one earth field and the airframe's iron to each
//! attitude: in rolls and loops the field must fit the attitude with the states better,
//! with the 95 % block-bootstrap interval of the difference below zero (measured −0.47°
//! and −0.43°, tools/magcheck/README.md). Skips, saying so, without the logs, python3,
//! numpy or pymavlink (fails instead under `cargo xtask test`).
use sim_harness::estimate::{replay_estimates, EstimateWriter};
use sim_harness::{data, pypi_logs};
use std::path::Path;
use wing_ahrs::Config;

const TEST: &str = "the_scale_states_bring_the_attitude_closer_to_the_magnetometer_in_rolls";
const LOGS: [&str; 2] =
    ["ardupilot_log_reader_00000129.BIN", "ardupilot_log_reader_test_log_00000052.BIN"];

fn write(path: &Path, log: &sim_harness::log::FlightLog, cfg: Config) {
    let (est, _) = replay_estimates(log, cfg);
    let mut w = EstimateWriter::new(std::fs::File::create(path).unwrap()).unwrap();
    for r in &est {
        w.write(r).unwrap();
    }
    w.finish().unwrap();
}

/// The full model's high-rate difference line of `magcheck.py`'s output for `label`:
/// the difference and its interval, degrees.
fn high_rate_full(out: &str, label: &str) -> [f64; 3] {
    let line = out
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("{label}-off RMS diff HR")))
        .unwrap_or_else(|| panic!("no {label} high-rate line in:\n{out}"));
    let full = line.split("full ").nth(1).unwrap_or_else(|| panic!("no full model: {line}"));
    let nums: Vec<f64> = full
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == '+'))
        .filter_map(|s| s.parse().ok())
        .collect();
    [nums[0], nums[1], nums[2]]
}

#[test]
fn the_scale_states_bring_the_attitude_closer_to_the_magnetometer_in_rolls() {
    for m in ["numpy", "pymavlink"] {
        if !data::python_has(m) {
            return data::skip(TEST, &format!("python3 cannot import {m}"));
        }
    }
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/magcheck/magcheck.py");
    let dir = std::env::temp_dir().join(format!("wing-ahrs-magcheck-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Both arms take the receiver's report as given, as when the states were validated: with
    // the learnt noise (the default since) the filter itself sits 0.10° and 0.37° further
    // from this magnetometer in rolls and loops, and the states' gain on 00000052 is not
    // resolved (+0.29° [−0.46, +0.77]): docs/open-problems.md.
    let mut off = Config::default();
    off.quat_mut().expect("the default is the quaternion filter").learn_vel_noise = false;
    let mut states = off;
    states.quat_mut().expect("the default is the quaternion filter").gyro_scale_state_sigma = 0.002;
    for file in LOGS {
        let Some(bin) = pypi_logs::path(file) else {
            data::skip(TEST, &format!("{file} not fetched (run `sim-harness fetch-logs`)"));
            continue;
        };
        let log = sim_harness::import::load_any(&bin).unwrap();
        let (off_csv, on) =
            (dir.join(format!("{file}-off.csv")), dir.join(format!("{file}-states.csv")));
        write(&off_csv, &log, off);
        write(&on, &log, states);
        let out = std::process::Command::new("python3")
            .arg(&tool)
            .arg(&bin)
            .arg(format!("off={}", off_csv.display()))
            .arg(format!("states={}", on.display()))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{file}: {}\n{text}", String::from_utf8_lossy(&out.stderr));
        let [d, lo, hi] = high_rate_full(&text, "states");
        println!("{file}: high-rate field residual, states − off: {d:+.3}° [{lo:+.3}, {hi:+.3}]");
        assert!(d < -0.2 && hi < 0.0, "{file}: {d} [{lo}, {hi}]");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
