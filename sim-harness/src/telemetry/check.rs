//! `sim-harness telemetry`: the bench-top link check. Reads MAVLink from a serial
//! port (`serialport`), a TCP socket, or a firmware it boots in QEMU on a
//! flat-and-still bench flight; shows live attitude; reports message rates, CRC
//! errors and sequence gaps; passes or fails the bench checks; `--record` writes
//! the raw IMU/GPS telemetry as a flight-log CSV for `replay`.

use super::stream::{msg_name, name_str, LinkStats, Scanner};
use crate::log::{FlightLog, GpsSample, LogRow};
use anyhow::{bail, Context, Result};
use mavlink::dialects::common::MavMessage;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Bench-check thresholds.
#[derive(Debug, Clone)]
pub struct Limits {
    /// Largest |roll|, |pitch| for a flat, still board, degrees.
    pub max_tilt_deg: f64,
    /// Configured ATTITUDE rate, Hz.
    pub attitude_hz: f64,
    /// Allowed relative rate error.
    pub rate_tol: f64,
}

/// What a session measured.
#[derive(Debug, Default)]
pub struct Report {
    /// Link statistics (CRC errors, sequence gaps, per-message counts).
    pub link: LinkStats,
    /// Message rates on the board's clock (time fields), Hz.
    pub rates: BTreeMap<&'static str, f64>,
    /// Largest |roll|, |pitch| over the second half of the session, degrees.
    pub max_tilt_deg: f64,
    /// Last NAMED_VALUE_INT values (health counters).
    pub named: BTreeMap<String, i64>,
    /// STATUSTEXT lines.
    pub texts: Vec<String>,
    /// Raw IMU + GPS as a flight log (from HIGHRES_IMU and DEBUG_VECT GPSVEL).
    pub recorded: FlightLog,
}

/// Analyses a captured byte stream.
pub fn analyze(bytes: &[u8]) -> Report {
    let mut sc = Scanner::default();
    let frames = sc.push(bytes);
    let mut r = Report::default();
    let mut times: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    let mut att = Vec::new();
    let mut gps: BTreeMap<u64, [f64; 3]> = BTreeMap::new();
    let mut hb = 0.0;
    for f in &frames {
        let name = msg_name(&f.msg);
        let t = match &f.msg {
            MavMessage::ATTITUDE(a) => {
                att.push((a.time_boot_ms as f64 * 1e-3, a.roll as f64, a.pitch as f64));
                Some(a.time_boot_ms as f64 * 1e-3)
            }
            MavMessage::HIGHRES_IMU(m) => {
                r.recorded.rows.push(LogRow {
                    t: m.time_usec as f64 * 1e-6,
                    gyro: [m.xgyro as f64, m.ygyro as f64, m.zgyro as f64],
                    accel: [m.xacc as f64, m.yacc as f64, m.zacc as f64],
                    ..Default::default()
                });
                Some(m.time_usec as f64 * 1e-6)
            }
            MavMessage::GPS_RAW_INT(g) => Some(g.time_usec as f64 * 1e-6),
            MavMessage::DEBUG_VECT(d) => {
                if name_str(&d.name[..]) == "GPSVEL" {
                    gps.insert(d.time_usec, [d.x as f64, d.y as f64, d.z as f64]);
                }
                None
            }
            MavMessage::HEARTBEAT(_) => {
                hb += 1.0;
                None
            }
            MavMessage::NAMED_VALUE_INT(n) => {
                r.named.insert(name_str(&n.name[..]), n.value as i64);
                None
            }
            MavMessage::STATUSTEXT(s) => {
                r.texts.push(name_str(&s.text[..]));
                None
            }
            _ => None,
        };
        if let Some(t) = t {
            times.entry(name).or_default().push(t);
        }
    }
    for (name, ts) in &times {
        if ts.len() >= 2 {
            let span = ts[ts.len() - 1] - ts[0];
            if span > 0.0 {
                r.rates.insert(name, (ts.len() - 1) as f64 / span);
            }
        }
    }
    if let Some(span) = times.get("ATTITUDE").and_then(|t| Some(t.last()? - t.first()?)) {
        if span > 0.0 {
            r.rates.insert("HEARTBEAT", hb / span);
        }
    }
    let half = att.len() / 2;
    r.max_tilt_deg = att[half..]
        .iter()
        .map(|(_, ro, pi)| ro.abs().max(pi.abs()).to_degrees())
        .fold(0.0, f64::max);
    for row in &mut r.recorded.rows {
        let us = (row.t * 1e6).round() as u64;
        if let Some(v) = gps.get(&us) {
            row.gps = Some(GpsSample { t: row.t, vel: *v, speed_acc: None, lla: None });
        }
    }
    r.link = sc.stats;
    r
}

/// Pass/fail lines of the bench test; `Ok` when all pass.
pub fn verdict(r: &Report, lim: &Limits) -> (bool, Vec<String>) {
    let mut lines = Vec::new();
    let mut ok = true;
    let mut check = |pass: bool, text: String| {
        ok &= pass;
        lines.push(format!("{} {text}", if pass { "PASS" } else { "FAIL" }));
    };
    check(
        r.max_tilt_deg < lim.max_tilt_deg,
        format!(
            "flat & still: max |roll|,|pitch| = {:.3}° (< {}°)",
            r.max_tilt_deg, lim.max_tilt_deg
        ),
    );
    let rate = r.rates.get("ATTITUDE").copied().unwrap_or(0.0);
    check(
        (rate - lim.attitude_hz).abs() <= lim.rate_tol * lim.attitude_hz,
        format!(
            "ATTITUDE rate {rate:.2} Hz (configured {} Hz ± {:.0} %)",
            lim.attitude_hz,
            lim.rate_tol * 100.0
        ),
    );
    check(r.link.crc_errors == 0, format!("CRC errors: {}", r.link.crc_errors));
    check(
        r.link.frames > 0,
        format!("frames decoded: {} (sequence gaps: {})", r.link.frames, r.link.seq_lost),
    );
    (ok, lines)
}

/// Prints the report tables.
pub fn print(r: &Report) {
    println!("message rates (board clock):");
    for (name, count) in &r.link.per_message {
        let rate = r.rates.get(name).map_or(String::from("-"), |h| format!("{h:.2} Hz"));
        println!("  {name:<18} {count:>7}  {rate}");
    }
    println!(
        "link: {} frames, {} CRC errors, {} lost (sequence gaps), {} bytes skipped",
        r.link.frames, r.link.crc_errors, r.link.seq_lost, r.link.bytes_skipped
    );
    if !r.named.is_empty() {
        let kv: Vec<String> = r.named.iter().map(|(k, v)| format!("{k}={v}")).collect();
        println!("health: {}", kv.join(" "));
    }
    for t in &r.texts {
        println!("statustext: {t}");
    }
}

/// Where the telemetry comes from.
pub enum Source {
    /// A serial port at a baud rate.
    Serial(String, u32),
    /// A TCP endpoint (`host:port`).
    Tcp(String),
}

/// Reads `seconds` of telemetry from `src`, printing live attitude.
pub fn capture(src: &Source, seconds: f64) -> Result<Vec<u8>> {
    let mut port: Box<dyn Read> = match src {
        Source::Serial(p, baud) => Box::new(
            serialport::new(p, *baud)
                .timeout(Duration::from_millis(200))
                .open()
                .with_context(|| format!("opening serial port {p}"))?,
        ),
        Source::Tcp(a) => {
            let s =
                std::net::TcpStream::connect(a).with_context(|| format!("connecting to {a}"))?;
            s.set_read_timeout(Some(Duration::from_millis(200)))?;
            Box::new(s)
        }
    };
    let start = Instant::now();
    let mut all = Vec::new();
    let mut sc = Scanner::default();
    let mut buf = [0u8; 4096];
    let mut last = Instant::now();
    while start.elapsed().as_secs_f64() < seconds {
        match port.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => {
                all.extend_from_slice(&buf[..n]);
                for f in sc.push(&buf[..n]) {
                    if let MavMessage::ATTITUDE(a) = f.msg {
                        if last.elapsed() > Duration::from_millis(200) {
                            last = Instant::now();
                            print!(
                                "\rroll {:7.2}°  pitch {:7.2}°  yaw {:8.2}°  p {:6.2} q {:6.2} r {:6.2} °/s",
                                a.roll.to_degrees(),
                                a.pitch.to_degrees(),
                                a.yaw.to_degrees(),
                                a.rollspeed.to_degrees(),
                                a.pitchspeed.to_degrees(),
                                a.yawspeed.to_degrees()
                            );
                            let _ = std::io::Write::flush(&mut std::io::stdout());
                        }
                    }
                }
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut | std::io::ErrorKind::WouldBlock
                ) => {}
            Err(e) => bail!("reading telemetry: {e}"),
        }
    }
    println!();
    Ok(all)
}

/// A flat, still bench "flight" (gyro bias + noise, gravity only, GPS at rest).
pub fn still_bench(seconds: f64) -> FlightLog {
    let mut rows = Vec::new();
    let n = (seconds * 100.0) as usize;
    let mut s = 0x0123_4567_89AB_CDEFu64;
    let mut noise = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0
    };
    for k in 0..n {
        let t = k as f64 * 0.01;
        rows.push(LogRow {
            t,
            gyro: [0.002 + 0.0005 * noise(), -0.001 + 0.0005 * noise(), 0.0015 + 0.0005 * noise()],
            accel: [0.02 * noise(), 0.02 * noise(), -wing_ahrs::GRAVITY as f64 + 0.02 * noise()],
            gps: (k % 10 == 5).then(|| GpsSample {
                t,
                vel: [0.01 * noise(), 0.01 * noise(), 0.01 * noise()],
                speed_acc: None,
                lla: None,
            }),
            truth: Some([0.0, 0.0, 0.0]),
            ..Default::default()
        });
    }
    FlightLog { rows }
}

/// Boots `firmware` in QEMU, flies the still bench for `seconds` at the board's
/// normal telemetry rates, and returns the telemetry bytes.
pub fn capture_qemu(
    firmware: PathBuf,
    seconds: f64,
    attitude_hz: u16,
    raw_imu_hz: u16,
) -> Result<Vec<u8>> {
    let log = still_bench(seconds);
    let items = crate::hil::plan(&log, crate::hil::GpsWire::Ubx);
    // Real-time pacing, like a bench board: the checker measures what a ground
    // station would see.
    let opts = crate::hil::Options {
        window: None,
        pace: Some(1.0),
        per_sample: false,
        attitude_hz,
        raw_imu_hz,
        ..crate::hil::Options::hil(firmware)
    };
    Ok(crate::hil::run(&log, &items, &opts)?.raw)
}
