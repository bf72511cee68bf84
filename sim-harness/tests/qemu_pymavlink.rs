//! The firmware's telemetry decoded by pymavlink (the reference MAVLink
//! implementation, independent of the `mavlink` crate the firmware and harness
//! use): every per-sample ATTITUDE (the HIL records, component 25) it reads must equal,
//! bit for bit, the attitude our decoder read and the host replay computed. Needs
//! `pip install pymavlink`.
mod qemu_common;

use sim_harness::hil::{self, GpsWire, Options};
use std::process::Command;

#[test]
fn qemu_pymavlink_reads_the_same_attitude() {
    let Some(fw) = qemu_common::setup("qemu_pymavlink_reads_the_same_attitude") else { return };
    let py_ok = sim_harness::data::python_has("pymavlink");
    if !py_ok {
        assert!(
            std::env::var_os("WING_AHRS_REQUIRE_QEMU").is_none(),
            "pymavlink not available: `cargo xtask test` installs it"
        );
        eprintln!("SKIP qemu_pymavlink_reads_the_same_attitude: python3 with pymavlink not available (pip install pymavlink)");
        return;
    }
    let log = hil::flight::synthetic(15.0, 21);
    let items = hil::plan(&log, GpsWire::Ubx);
    let out = hil::run(&log, &items, &Options::hil(fw)).expect("HIL run");
    let cap = std::env::temp_dir().join(format!("wing-ahrs-pymavlink-{}.bin", std::process::id()));
    std::fs::write(&cap, &out.raw).unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/decode_attitude.py");
    let res =
        Command::new("python3").arg(script).arg(&cap).arg("25").output().expect("running python3");
    let _ = std::fs::remove_file(&cap);
    assert!(
        res.status.success(),
        "pymavlink decoder failed: {}",
        String::from_utf8_lossy(&res.stderr)
    );
    let text = String::from_utf8(res.stdout).unwrap();
    let mut py = Vec::new();
    let mut crc_errors = None;
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f[0] == "crc_errors" {
            crc_errors = Some(f[1].parse::<u32>().unwrap());
            continue;
        }
        // Hex of the little-endian bytes → the f32 bit pattern.
        let bits = |s: &str| u32::from_str_radix(s, 16).unwrap().swap_bytes();
        py.push((f[0].parse::<u32>().unwrap(), [bits(f[1]), bits(f[2]), bits(f[3])]));
    }
    assert_eq!(crc_errors, Some(0));
    assert_eq!(
        py.len(),
        out.samples.len(),
        "pymavlink read {} per-sample ATTITUDE, we read {}",
        py.len(),
        out.samples.len()
    );
    assert_eq!(py.len(), log.rows.len());
    let host = hil::reference_items(&log, &items, wing_ahrs::Config::default());
    for ((p, ours), h) in py.iter().zip(&out.samples).zip(&host) {
        assert_eq!(p.0 as u64, ours.t_us / 1000);
        assert_eq!(p.1, ours.att.map(f32::to_bits), "pymavlink vs our decoder at {} ms", p.0);
        // The replay's attitude is the same f32 (widened to f64 in the estimate row).
        assert_eq!(
            p.1,
            h.att.map(|v| (v as f32).to_bits()),
            "pymavlink vs host replay at {} ms",
            p.0
        );
    }
}
