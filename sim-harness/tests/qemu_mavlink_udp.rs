//! A ground station sees the emulated board: `hil` forwards the firmware's MAVLink over
//! UDP, and pymavlink (a real client, the one MAVProxy is built on) listening on a free
//! loopback port receives ATTITUDE and GPS_RAW_INT from it.
mod qemu_common;

use sim_harness::hil::{self, GpsWire, Options};
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

#[test]
fn qemu_mavlink_reaches_pymavlink_over_udp() {
    let Some(fw) = qemu_common::setup("qemu_mavlink_reaches_pymavlink_over_udp") else { return };
    let py_ok = Command::new("python3").args(["-c", "import pymavlink"]).status();
    if !py_ok.is_ok_and(|s| s.success()) {
        assert!(std::env::var_os("WING_AHRS_REQUIRE_QEMU").is_none(), "pymavlink not available");
        eprintln!("SKIP qemu_mavlink_reaches_pymavlink_over_udp: python3 with pymavlink absent");
        return;
    }
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/udp_listen.py");
    let mut py = Command::new("python3")
        .arg(script)
        .arg(port.to_string())
        .arg("3")
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(py.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert_eq!(line.trim(), "ready");
    let log = hil::flight::synthetic(10.0, 23);
    let items = hil::plan(&log, GpsWire::Ubx);
    let opts = Options {
        mavlink_udp: Some(format!("127.0.0.1:{port}").parse().unwrap()),
        ..Options::hil(fw)
    };
    let run = hil::run(&log, &items, &opts).expect("HIL run");
    let mut text = String::new();
    for l in out.lines() {
        text.push_str(&l.unwrap());
        text.push('\n');
    }
    assert!(py.wait().unwrap().success());
    println!("pymavlink over UDP:\n{text}");
    let count = |t: &str| -> usize {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{t} ")).map(|n| n.parse().unwrap()))
            .unwrap_or(0)
    };
    // Loopback UDP does not drop here; allow a little for a busy machine.
    assert!(
        count("ATTITUDE") * 100 >= run.attitude.len() * 95,
        "{} of {}",
        count("ATTITUDE"),
        run.attitude.len()
    );
    let fixes = log.rows.iter().filter(|r| r.gps.is_some()).count();
    assert!(
        count("GPS_RAW_INT") * 100 >= fixes * 95,
        "{} GPS_RAW_INT for {fixes} fixes",
        count("GPS_RAW_INT")
    );
    assert!(count("HEARTBEAT") >= 1);
    assert!(text.contains("gps_lat_e7 473977000"), "{text}");
}
