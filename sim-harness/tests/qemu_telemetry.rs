//! The bench telemetry check against the QEMU firmware on a flat, still bench at
//! the board's normal rates: ATTITUDE at the configured 50 Hz (±10 %), HEARTBEAT
//! at 1 Hz, HIGHRES_IMU at 100 Hz, a GPS_RAW_INT per fix, no CRC errors, |roll|,|pitch| < 2°, and
//! `--record` output that replays to the same raw samples that were sent.
mod qemu_common;

use sim_harness::telemetry::check::{analyze, capture_qemu, still_bench, verdict, Limits};

#[test]
fn qemu_telemetry_bench_check_passes_and_records() {
    let Some(fw) = qemu_common::setup("qemu_telemetry_bench_check_passes_and_records") else {
        return;
    };
    let bytes = capture_qemu(fw, 12.0, 50, 100).expect("QEMU bench");
    let r = analyze(&bytes);
    let (ok, lines) = verdict(&r, &Limits { max_tilt_deg: 2.0, attitude_hz: 50.0, rate_tol: 0.10 });
    assert!(ok, "{lines:#?}");
    let hz = |k: &str| r.rates.get(k).copied().unwrap_or(0.0);
    assert!((hz("ATTITUDE") - 50.0).abs() < 1.0, "ATTITUDE {} Hz", hz("ATTITUDE"));
    assert!((hz("HIGHRES_IMU") - 100.0).abs() < 2.0, "HIGHRES_IMU {} Hz", hz("HIGHRES_IMU"));
    assert!((hz("HEARTBEAT") - 1.0).abs() < 0.2, "HEARTBEAT {} Hz", hz("HEARTBEAT"));
    assert!(r.link.per_message.get("SYS_STATUS").copied().unwrap_or(0) >= 10);
    // One GPS_RAW_INT per fix streamed in, counted, not timed: the capture is paced by the
    // wall clock (no -icount), and on a loaded host the firmware's telemetry ring may
    // overflow and drop a message — which it must then show as a sequence gap.
    let sent = still_bench(12.0);
    let fixes = sent.rows.iter().filter(|r| r.gps.is_some()).count() as u64;
    let raw = r.link.per_message.get("GPS_RAW_INT").copied().unwrap_or(0);
    assert!(raw <= fixes, "{raw} GPS_RAW_INT for {fixes} fixes");
    assert!(
        raw + r.link.seq_lost >= fixes && raw * 10 >= fixes * 9,
        "{raw} GPS_RAW_INT for {fixes} fixes, {} frames lost by sequence; health {:?}",
        r.link.seq_lost,
        r.named
    );
    // The recording carries exactly the f32 samples that were streamed in.
    assert_eq!(r.recorded.rows.len(), sent.rows.len());
    for (a, b) in r.recorded.rows.iter().zip(&sent.rows) {
        assert_eq!(a.gyro.map(|v| v as f32), b.gyro.map(|v| v as f32));
        assert_eq!(a.accel.map(|v| v as f32), b.accel.map(|v| v as f32));
        assert_eq!(a.gps.is_some(), b.gps.is_some());
    }
}
