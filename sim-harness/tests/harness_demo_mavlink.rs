//! `demo` shows up in a ground station: pymavlink listening on a free loopback UDP port
//! receives its HEARTBEAT (1 Hz) and ATTITUDE (10 Hz) with the printed estimate.
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

#[test]
fn demo_mavlink_reaches_pymavlink_over_udp() {
    let py = Command::new("python3").args(["-c", "import pymavlink"]).status();
    if !py.is_ok_and(|s| s.success()) {
        sim_harness::data::skip("demo_mavlink_reaches_pymavlink_over_udp", "pymavlink absent");
        return;
    }
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/udp_listen.py");
    let mut py = Command::new("python3")
        .arg(script)
        .arg(port.to_string())
        .arg("2")
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(py.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert_eq!(line.trim(), "ready");
    let o = Command::new(env!("CARGO_BIN_EXE_sim-harness"))
        .args(["demo", "--duration", "10", "--mavlink-udp", &format!("127.0.0.1:{port}")])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text: String = out.lines().map(|l| l.unwrap() + "\n").collect();
    assert!(py.wait().unwrap().success());
    let count = |t: &str| -> usize {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{t} ")).map(|n| n.parse().unwrap()))
            .unwrap_or(0)
    };
    println!("{text}");
    assert!(count("ATTITUDE") >= 95, "{text}");
    assert!(count("HEARTBEAT") >= 10, "{text}");
}
