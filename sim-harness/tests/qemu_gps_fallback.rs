//! A receiver that falls back from UBX to NMEA mid-flight (a u-blox brown-out reset to
//! factory settings): the firmware's parser suppresses NMEA for 2 s after the last UBX
//! fix, then must accept it. The firmware stamps GPS bytes with the board's sample clock;
//! with the constant 0 it passed before, 0 − 0 < 2 s held forever and every NMEA fix
//! after the fallback was dropped.
mod qemu_common;

use sim_harness::hil::{self, GpsWire, Options};

#[test]
fn qemu_nmea_fixes_are_accepted_after_the_ubx_stream_stops() {
    let Some(fw) = qemu_common::setup("qemu_nmea_fixes_are_accepted_after_the_ubx_stream_stops")
    else {
        return;
    };
    let mut log = hil::flight::synthetic(30.0, 17);
    // UBX until 10 s, silence until 12.5 s (past the 2 s suppression), NMEA after.
    for r in log.rows.iter_mut().filter(|r| r.t >= 10.0 && r.t < 12.5) {
        r.gps = None;
    }
    let n_ubx = log.rows.iter().filter(|r| r.gps.is_some() && r.t < 10.0).count();
    let n_nmea = log.rows.iter().filter(|r| r.gps.is_some() && r.t >= 12.5).count();
    let rows = log.rows.clone();
    let items = hil::plan_with(&log, GpsWire::Ubx, |i, bytes| {
        if rows[i].t >= 12.5 {
            *bytes = hil::wire_bytes(&hil::wire_fix(&rows[i]).unwrap(), GpsWire::Nmea);
        }
        true
    });
    let out = hil::run(&log, &items, &Options::hil(fw)).expect("HIL run");
    let n = |k: &str| out.named.get(k).copied().unwrap_or(-1);
    println!(
        "UBX fixes {n_ubx}, NMEA fixes {n_nmea}: GPS_FIX {}, GPS_REJ {}, GPS_LATE {}, GPS_ERR {}",
        n("GPS_FIX"),
        n("GPS_REJ"),
        n("GPS_LATE"),
        n("GPS_ERR")
    );
    assert_eq!(n("GPS_LATE"), 0, "a fix the host sent never came out of the parser");
    // Every fix reached the estimator, the NMEA ones included.
    assert_eq!(n("GPS_FIX") + n("GPS_REJ"), (n_ubx + n_nmea) as i64);
    assert!(
        n("GPS_FIX") as usize > n_ubx + n_nmea * 9 / 10,
        "NMEA fixes after the fallback were dropped"
    );
}
