//! `demo` shows up in a ground station: pymavlink listening on a free loopback UDP port
//! receives its HEARTBEAT (1 Hz) and ATTITUDE (10 Hz) with the printed estimate.
mod udp_listener;

use std::process::Command;
use udp_listener::count;

#[test]
fn demo_mavlink_reaches_pymavlink_over_udp() {
    if !udp_listener::pymavlink_available() {
        sim_harness::data::skip("demo_mavlink_reaches_pymavlink_over_udp", "pymavlink absent");
        return;
    }
    let listener = udp_listener::start(2);
    let o = Command::new(env!("CARGO_BIN_EXE_sim-harness"))
        .args(["demo", "--duration", "10", "--mavlink-udp", &listener.addr])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = listener.finish();
    println!("{text}");
    assert!(count(&text, "ATTITUDE") >= 95, "{text}");
    assert!(count(&text, "HEARTBEAT") >= 10, "{text}");
}
