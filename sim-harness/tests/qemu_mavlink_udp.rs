//! A ground station sees the emulated board: `hil` forwards the firmware's MAVLink over
//! UDP, and pymavlink (a real client, the one MAVProxy is built on) listening on a free
//! loopback port receives ATTITUDE and GPS_RAW_INT from it.
mod qemu_common;
mod udp_listener;

use sim_harness::hil::{self, GpsWire, Options};
use udp_listener::count;

#[test]
fn qemu_mavlink_reaches_pymavlink_over_udp() {
    let Some(fw) = qemu_common::setup("qemu_mavlink_reaches_pymavlink_over_udp") else { return };
    if !udp_listener::pymavlink_available() {
        assert!(std::env::var_os("WING_AHRS_REQUIRE_QEMU").is_none(), "pymavlink not available");
        eprintln!("SKIP qemu_mavlink_reaches_pymavlink_over_udp: python3 with pymavlink absent");
        return;
    }
    let listener = udp_listener::start(3);
    let log = hil::flight::synthetic(10.0, 23);
    let items = hil::plan(&log, GpsWire::Ubx);
    let opts = Options { mavlink_udp: Some(listener.addr.parse().unwrap()), ..Options::hil(fw) };
    let run = hil::run(&log, &items, &opts).expect("HIL run");
    let text = listener.finish();
    println!("pymavlink over UDP:\n{text}");
    // Loopback UDP does not drop here; allow a little for a busy machine.
    assert!(
        count(&text, "ATTITUDE") * 100 >= run.attitude.len() * 95,
        "{} of {}",
        count(&text, "ATTITUDE"),
        run.attitude.len()
    );
    let fixes = log.rows.iter().filter(|r| r.gps.is_some()).count();
    assert!(
        count(&text, "GPS_RAW_INT") * 100 >= fixes * 95,
        "{} GPS_RAW_INT for {fixes} fixes",
        count(&text, "GPS_RAW_INT")
    );
    assert!(count(&text, "HEARTBEAT") >= 1);
    assert!(text.contains("gps_lat_e7 473977000"), "{text}");
}
