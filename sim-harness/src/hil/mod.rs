//! QEMU hardware-in-the-loop: stream a flight log into the firmware running on the
//! emulated Cortex-M4F (`mps2-an386`) and read its MAVLink telemetry back.
//!
//! Wire (see `docs/hil-protocol.md`): IMU + airspeed as checksummed records on
//! UART0, GPS as UBX NAV-PVT bytes on UART1, MAVLink v2 out on UART2. Each IMU
//! record carries the cumulative number of GPS fixes sent; the firmware hands the
//! estimator exactly those fixes at that sample, so the run is deterministic even
//! though QEMU interleaves the two input sockets arbitrarily.
//!
//! Bit-exactness: the firmware sees the fix the UBX bytes encode (velocity rounded
//! to mm/s, iTOW from `gps_t`), not the log's f64 velocity. [`reference`] replays
//! the log on the host with exactly those fixes; [`run`]'s attitude must equal it
//! bit for bit. Against the plain `replay` of the same log the difference is that
//! rounding and nothing else (measured: `replay` of [`with_wire_velocity`] equals
//! [`reference`]; on the simulator's flights the iTOW epochs give the same
//! intervals as the sample clock). It first shows at the first GPS update: < 1 mm/s
//! of velocity differenced over 0.1 s is < 0.01 m/s², ≈ 0.05° of initial roll.

pub mod cli;
pub mod flight;
pub mod gcs;
pub mod protocol;
pub mod qemu;

use crate::estimate::EstimateRow;
use crate::log::{FlightLog, LogRow};
use crate::replay::to_us;
use crate::telemetry::stream::{name_str, Frame, Scanner};
use anyhow::{bail, Context, Result};
use mavlink::dialects::common::MavMessage;
use std::collections::{BTreeMap, HashMap};
use std::io::{Read, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use wing_ahrs::hil_record::{self, Record};
use wing_ahrs::{
    Ahrs, AxisStatus, AxisUpdate, Config, FixType, Flags, GpsFix, Sample, UpdateRecord,
};

/// The GPS fix a log row's GPS cells become on the wire (UBX NAV-PVT, 3-D fix),
/// before the firmware restamps it with the consuming sample's time.
pub fn wire_fix(row: &LogRow) -> Option<GpsFix> {
    let g = row.gps?;
    Some(GpsFix {
        t_us: to_us(row.t),
        itow_ms: Some(((g.t * 1000.0).round() as u64 % 604_800_000) as u32),
        fix_type: FixType::Fix3D,
        fix_ok: true,
        vel_ne: [g.vel[0] as f32, g.vel[1] as f32],
        vel_d: Some(g.vel[2] as f32),
        // A log without the receiver's accuracy: send the σ the estimator assumes for such fixes.
        speed_acc: Some(g.speed_acc.map_or(Config::DEFAULT_GPS_VEL_SIGMA, |a| a as f32)),
        num_sats: 12,
        lat_e7: 473_977_000,
        lon_e7: 85_456_000,
        alt_msl_mm: 500_000,
    })
}

/// GPS wire format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum GpsWire {
    /// u-blox UBX NAV-PVT (velocity in mm/s, iTOW).
    #[default]
    Ubx,
    /// NMEA 0183 RMC + GGA + VTG (speed/course only: no vertical velocity).
    Nmea,
}

/// The bytes the receiver would send for `fix` (core encoders, `wing_ahrs::gps::encode`).
pub fn wire_bytes(fix: &GpsFix, wire: GpsWire) -> Vec<u8> {
    use wing_ahrs::gps::encode;
    let mut buf = [0u8; 256];
    let mut out = Vec::new();
    match wire {
        GpsWire::Ubx => {
            if let Some(n) = encode::nav_pvt(fix, &mut buf) {
                out.extend_from_slice(&buf[..n]);
            }
        }
        GpsWire::Nmea => {
            for f in [
                |x: &GpsFix, b: &mut [u8]| encode::nmea_rmc(x, 220526, b),
                |x: &GpsFix, b: &mut [u8]| encode::nmea_gga(x, b),
                |x: &GpsFix, b: &mut [u8]| encode::nmea_vtg(x, b),
            ] {
                if let Some(n) = f(fix, &mut buf) {
                    out.extend_from_slice(&buf[..n]);
                }
            }
        }
    }
    out
}

/// The fixes the firmware's parser (the same core `GpsParser`, fed the same byte
/// stream in order) produces for each row, stamped with the row time.
pub fn decoded_fixes(log: &FlightLog, wire: GpsWire) -> Vec<Option<GpsFix>> {
    let mut p = wing_ahrs::gps::GpsParser::new();
    log.rows
        .iter()
        .map(|row| {
            let t = to_us(row.t);
            let mut got = None;
            if let Some(f) = wire_fix(row) {
                p.push_slice(&wire_bytes(&f, wire), t, |fix| got = Some(GpsFix { t_us: t, ..fix }));
            }
            got
        })
        .collect()
}

/// `log` with each GPS velocity and speed accuracy replaced by the ones the firmware
/// decodes from the wire (UBX: whole mm/s), everything else untouched. For UBX, plain `replay` of this
/// log equals [`reference`]: the wire's velocity resolution is the whole difference
/// between `hil` and `replay` of the original log. (NMEA also drops vD: this log's
/// `gps_vd` is then 0, which the replay takes as measured, so there the two still differ.)
pub fn with_wire_velocity(log: &FlightLog, wire: GpsWire) -> FlightLog {
    let fixes = decoded_fixes(log, wire);
    let rows = log
        .rows
        .iter()
        .zip(&fixes)
        .map(|(row, fix)| {
            let mut r = *row;
            if let (Some(g), Some(f)) = (r.gps.as_mut(), fix) {
                // The log's gps_vd column cannot say "not measured": a wire without vD
                // (NMEA) writes 0, the value the estimator takes for a missing vD.
                g.vel = [f.vel_ne[0], f.vel_ne[1], f.vel_d.unwrap_or(0.0)].map(f64::from);
                g.speed_acc = f.speed_acc.map(f64::from);
            }
            r
        })
        .collect();
    FlightLog { rows }
}

/// Host replay with the fixes the firmware sees: the bit-exact reference for `hil`.
pub fn reference(log: &FlightLog, cfg: Config, wire: GpsWire) -> Vec<EstimateRow> {
    let fixes = decoded_fixes(log, wire);
    let mut ahrs = Ahrs::try_new(cfg).expect("a valid configuration");
    let mut seq = 0;
    let f = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
    log.rows
        .iter()
        .zip(&fixes)
        .map(|(row, fix)| {
            let s = Sample {
                t_us: to_us(row.t),
                gyro: f(row.gyro),
                accel: f(row.accel),
                airspeed: row.airspeed.map(|v| v as f32),
            };
            ahrs.step(&s, fix.as_slice());
            EstimateRow::capture(row.t, &ahrs, &mut seq)
        })
        .collect()
}

/// Host replay of a send plan, bit-exact reference for any plan (also corrupted
/// ones): GPS bytes go through the core parser in order; each IMU record, decoded by
/// the core codec as the firmware decodes it (so corrupted values are replayed as
/// sent), is one `Ahrs::step` with every fix completed since the previous record,
/// stamped with the record's time — the firmware's order.
pub fn reference_items(log: &FlightLog, items: &[Item], cfg: Config) -> Vec<EstimateRow> {
    let mut parser = wing_ahrs::gps::GpsParser::new();
    let mut pending: Vec<GpsFix> = Vec::new();
    let mut ahrs = Ahrs::try_new(cfg).expect("a valid configuration");
    let mut seq = 0;
    let mut out = Vec::new();
    for item in items {
        match item {
            Item::Gps(b) => parser.push_slice(b, 0, |f| pending.push(f)),
            Item::Sensor(_) => {}
            Item::Imu { row, bytes } => {
                let Some(Record::Imu(rec)) = hil_record::decode_frame(bytes) else {
                    continue; // not a valid IMU frame: the firmware drops it too
                };
                let t = rec.sample.t_us;
                pending.iter_mut().for_each(|f| f.t_us = t);
                ahrs.step(&rec.sample, &pending);
                pending.clear();
                out.push(EstimateRow::capture(log.rows[*row].t, &ahrs, &mut seq));
            }
        }
    }
    out
}

/// One thing the harness sends.
#[derive(Debug, Clone)]
pub enum Item {
    /// Bytes on the GPS UART.
    Gps(Vec<u8>),
    /// An IMU record for log row `row` (expects one sample of output).
    Imu {
        /// Log row index.
        row: usize,
        /// Record bytes.
        bytes: Vec<u8>,
    },
    /// Raw bytes on the sensor UART that produce no sample (corrupt records, garbage).
    Sensor(Vec<u8>),
}

/// The send plan for a log. `gps_filter(row, bytes)` may alter a fix's bytes and
/// returns whether they still carry a valid fix (counted in the records' GPS count).
pub fn plan_with(
    log: &FlightLog,
    wire: GpsWire,
    mut gps_filter: impl FnMut(usize, &mut Vec<u8>) -> bool,
) -> Vec<Item> {
    let mut items = Vec::with_capacity(log.rows.len() * 2);
    let mut sent = 0u32;
    let f = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
    for (i, row) in log.rows.iter().enumerate() {
        if let Some(fix) = wire_fix(row) {
            let mut b = wire_bytes(&fix, wire);
            if gps_filter(i, &mut b) {
                sent += 1;
            }
            items.push(Item::Gps(b));
        }
        let bytes = protocol::imu(
            to_us(row.t),
            f(row.gyro),
            f(row.accel),
            row.airspeed.map(|v| v as f32),
            sent,
        );
        items.push(Item::Imu { row: i, bytes });
    }
    items
}

/// The plain plan: every fix as valid UBX.
pub fn plan(log: &FlightLog, wire: GpsWire) -> Vec<Item> {
    plan_with(log, wire, |_, _| true)
}

/// How a run is driven.
#[derive(Debug, Clone)]
pub struct Options {
    /// Firmware ELF.
    pub firmware: PathBuf,
    /// Deterministic instruction counting (`-icount shift=0`).
    pub icount: bool,
    /// Flow control: at most this many samples in flight (None: send freely).
    pub window: Option<usize>,
    /// Pace rows at real time × this factor (None: as fast as possible).
    pub pace: Option<f64>,
    /// Per-sample estimate output (needed for the estimate CSV).
    pub per_sample: bool,
    /// ATTITUDE rate, Hz, when not per-sample.
    pub attitude_hz: u16,
    /// HIGHRES_IMU rate, Hz.
    pub raw_imu_hz: u16,
    /// Do not read telemetry for this long after start (back-pressure test).
    pub stall_reader: Option<Duration>,
    /// Print live attitude vs truth.
    pub live: bool,
    /// Telemetry through a small-buffered Unix socket instead of TCP (back-pressure tests).
    pub telemetry_fifo: bool,
    /// Give up after this long.
    pub timeout: Duration,
    /// The ground-station link ([`gcs`]): the autopilot's frames, one per datagram, at
    /// real time, to this UDP address (QGroundControl/MAVProxy listen on 14550).
    pub mavlink_udp: Option<std::net::SocketAddr>,
    /// Put the per-sample HIL records on the ground-station link too.
    pub gcs_hil_records: bool,
}

impl Options {
    /// Per-sample, flow-controlled, as fast as possible: the HIL comparison setup.
    pub fn hil(firmware: PathBuf) -> Self {
        Options {
            firmware,
            icount: false,
            window: Some(4),
            pace: None,
            per_sample: true,
            attitude_hz: 50,
            raw_imu_hz: 0,
            stall_reader: None,
            live: false,
            telemetry_fifo: false,
            timeout: Duration::from_secs(600),
            mavlink_udp: None,
            gcs_hil_records: false,
        }
    }
}

/// Per-sample output assembled from ATTITUDE + DEBUG_VECT frames.
#[derive(Debug, Clone, Default)]
pub struct HilSample {
    /// Sample time, µs.
    pub t_us: u64,
    /// Attitude, rad (ATTITUDE).
    pub att: [f32; 3],
    /// Body rates, rad/s.
    pub rates: [f32; 3],
    /// Gyro bias, rad/s.
    pub bias: [f32; 3],
    /// 1-σ of the six states.
    pub sd: [f32; 6],
    /// Flags, instructions of the IMU task for this sample, accepted.
    pub flags: u16,
    /// IMU-task instructions (QEMU icount; not cycles).
    pub isr_instructions: u32,
    /// Whether the firmware's estimator accepted the IMU sample.
    pub accepted: bool,
    /// Update record if one ran.
    pub update: Option<UpdateRecord>,
    /// NED velocity, m/s, of the last GPS fix the estimator consumed at this sample
    /// (DEBUG_VECT `GPSVEL`, exact f32): what the firmware's parser decoded.
    pub gps_vel: Option<[f32; 3]>,
    /// WIND_COV: wind `[w_N, w_E, w_D]` (m/s) and the horizontal variance (m/s)².
    pub wind: Option<([f32; 3], f32)>,
}

/// Everything read back from a run.
#[derive(Debug, Default)]
pub struct HilOutput {
    /// Per-sample outputs (per-sample mode: the HIL records) in arrival order.
    pub samples: Vec<HilSample>,
    /// The autopilot's ATTITUDE messages (time_boot_ms, roll, pitch, yaw) in arrival
    /// order: what a ground station sees, at `attitude_hz`.
    pub attitude: Vec<(u32, [f32; 3])>,
    /// Last value of each NAMED_VALUE_INT.
    pub named: BTreeMap<String, i64>,
    /// STATUSTEXT lines.
    pub texts: Vec<String>,
    /// SYS_STATUS count and the last one's drop rate (×0.01 %).
    pub sys_status: Option<mavlink::dialects::common::SYS_STATUS_DATA>,
    /// Link statistics.
    pub link: crate::telemetry::stream::LinkStats,
    /// Raw telemetry bytes (for independent decoders such as pymavlink).
    pub raw: Vec<u8>,
    /// defmt frames from semihosting.
    pub defmt: Vec<u8>,
    /// QEMU's exit code.
    pub exit_code: Option<i32>,
    /// Wall time of the run.
    pub wall: Duration,
}

fn axis_status(code: f32) -> AxisStatus {
    match code as u8 {
        0 => AxisStatus::Accepted,
        1 => AxisStatus::Gated,
        2 => AxisStatus::ForcedAfterGate,
        3 => AxisStatus::Initialised,
        _ => AxisStatus::NotMeasured,
    }
}

#[derive(Default)]
struct Collector {
    out: HilOutput,
    pending_att: Option<(u32, [f32; 3], [f32; 3])>,
    index: HashMap<u64, usize>,
}

impl Collector {
    /// Per-sample records come from the HIL component; the per-update ones (INNOV*,
    /// GPSVEL) only the autopilot sends, and attach to the sample of their time.
    fn frame(&mut self, f: Frame) {
        let hil = f.component == gcs::COMP_HIL;
        match f.msg {
            MavMessage::ATTITUDE(a) if !hil => {
                self.out.attitude.push((a.time_boot_ms, [a.roll, a.pitch, a.yaw]));
            }
            MavMessage::ATTITUDE(a) => {
                self.pending_att = Some((
                    a.time_boot_ms,
                    [a.roll, a.pitch, a.yaw],
                    [a.rollspeed, a.pitchspeed, a.yawspeed],
                ));
            }
            MavMessage::DEBUG_VECT(d) => {
                let name = name_str(&d.name[..]);
                let v = [d.x, d.y, d.z];
                let per_sample = matches!(name.as_str(), "BIAS" | "SD_ATT" | "SD_BIAS" | "FLAGS");
                if per_sample != hil {
                    return; // the autopilot's 10 Hz copies, or (never) HIL per-update ones
                }
                if name == "BIAS" {
                    let mut s = HilSample { t_us: d.time_usec, bias: v, ..Default::default() };
                    if let Some((ms, att, rates)) = self.pending_att {
                        if ms as u64 == d.time_usec / 1000 {
                            s.att = att;
                            s.rates = rates;
                        }
                    }
                    self.index.insert(d.time_usec, self.out.samples.len());
                    self.out.samples.push(s);
                    return;
                }
                let Some(&i) = self.index.get(&d.time_usec) else { return };
                let s = &mut self.out.samples[i];
                match name.as_str() {
                    "SD_ATT" => s.sd[..3].copy_from_slice(&v),
                    "SD_BIAS" => s.sd[3..].copy_from_slice(&v),
                    "FLAGS" => {
                        s.flags = v[0] as u16;
                        s.isr_instructions = v[1] as u32;
                        s.accepted = v[2] != 0.0;
                    }
                    "GPSVEL" => s.gps_vel = Some(v),
                    "INNOV" | "INNOV_VAR" | "INNOV_ST" => {
                        let u = s.update.get_or_insert_with(|| UpdateRecord {
                            t_us: d.time_usec,
                            axes: [AxisUpdate::default(); 3],
                            ..Default::default()
                        });
                        for k in 0..3 {
                            match name.as_str() {
                                "INNOV" => u.axes[k].innovation = v[k],
                                "INNOV_VAR" => u.axes[k].variance = v[k],
                                _ => u.axes[k].status = axis_status(v[k]),
                            }
                        }
                    }
                    _ => {}
                }
            }
            MavMessage::WIND_COV(w) if hil => {
                if let Some(&i) = self.index.get(&w.time_usec) {
                    self.out.samples[i].wind = Some(([w.wind_x, w.wind_y, w.wind_z], w.var_horiz));
                }
            }
            MavMessage::NAMED_VALUE_INT(n) => {
                self.out.named.insert(name_str(&n.name[..]), n.value as i64);
            }
            MavMessage::STATUSTEXT(t) => self.out.texts.push(name_str(&t.text[..])),
            MavMessage::SYS_STATUS(s) => self.out.sys_status = Some(s),
            _ => {}
        }
    }
}

/// Streams `items` (built from `log`) into the firmware and collects its telemetry.
pub fn run(log: &FlightLog, items: &[Item], opts: &Options) -> Result<HilOutput> {
    let start = Instant::now();
    let mut q = qemu::start(&opts.firmware, opts.icount, opts.telemetry_fifo)?;
    let acked = Arc::new(AtomicUsize::new(0));
    let done = Arc::new(AtomicBool::new(false));
    let shared = Arc::new(Mutex::new(Collector::default()));
    let mut tele = std::mem::replace(&mut q.telemetry, Box::new(std::io::empty()));
    let reader = {
        let (acked, shared, stall) = (acked.clone(), shared.clone(), opts.stall_reader);
        let mut gcs = match opts.mavlink_udp {
            Some(to) => Some(gcs::GcsLink::start(to, opts.gcs_hil_records)?),
            None => None,
        };
        std::thread::spawn(move || -> Result<(Vec<u8>, crate::telemetry::stream::LinkStats)> {
            if let Some(d) = stall {
                std::thread::sleep(d);
            }
            let mut sc = Scanner::default();
            let mut raw = Vec::new();
            let mut buf = [0u8; 8192];
            loop {
                let n = match tele.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => n,
                    Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => break,
                    Err(e) => return Err(e.into()),
                };
                raw.extend_from_slice(&buf[..n]);
                let frames = sc.push(&buf[..n]);
                let mut c = shared.lock().unwrap();
                for f in frames {
                    if let Some(g) = &mut gcs {
                        g.push(&f);
                    }
                    c.frame(f);
                }
                acked.store(c.out.samples.len().max(c.out.attitude.len()), Ordering::Release);
            }
            // The ground station's link runs at real time: let it finish the flight.
            if let Some(g) = gcs {
                g.finish();
            }
            Ok((raw, sc.stats))
        })
    };

    let send = |s: &mut std::net::TcpStream, b: &[u8], what: &str| {
        s.write_all(b).with_context(|| format!("writing to the firmware's {what} UART"))
    };
    send(
        &mut q.sensor,
        &protocol::config(opts.attitude_hz, opts.raw_imu_hz, opts.per_sample),
        "sensor",
    )?;
    let mut expected = 0usize;
    let mut last_live = Instant::now();
    let paced_from = Instant::now(); // after boot: pacing must not count QEMU start-up
    let t0 = log.rows.first().map_or(0.0, |r| r.t);
    for item in items {
        match item {
            Item::Gps(b) => send(&mut q.gps, b, "GPS")?,
            Item::Sensor(b) => send(&mut q.sensor, b, "sensor")?,
            Item::Imu { row, bytes } => {
                if let Some(speed) = opts.pace {
                    let due = Duration::from_secs_f64(((log.rows[*row].t - t0) / speed).max(0.0));
                    if let Some(wait) = due.checked_sub(paced_from.elapsed()) {
                        std::thread::sleep(wait);
                    }
                }
                if let Some(w) = opts.window {
                    while expected >= acked.load(Ordering::Acquire) + w {
                        if start.elapsed() > opts.timeout {
                            bail!(
                                "HIL timed out: {expected} samples sent, {} answered",
                                acked.load(Ordering::Acquire)
                            );
                        }
                        if let Some(st) = q.child.try_wait()? {
                            bail!("QEMU exited ({st}) mid-flight after {expected} samples (firmware panic? see defmt log)");
                        }
                        std::thread::sleep(Duration::from_micros(50));
                    }
                }
                send(&mut q.sensor, bytes, "sensor")?;
                expected += 1;
                let every =
                    if std::io::IsTerminal::is_terminal(&std::io::stdout()) { 250 } else { 2000 };
                if opts.live && last_live.elapsed() > Duration::from_millis(every) {
                    last_live = Instant::now();
                    live_line(log, &shared.lock().unwrap().out);
                }
            }
        }
    }
    if let Some(stall) = opts.stall_reader {
        // Let the reader drain first, so the final report is not itself dropped.
        let until = stall + Duration::from_millis(1500);
        if let Some(w) = until.checked_sub(start.elapsed()) {
            std::thread::sleep(w);
        }
    }
    send(&mut q.sensor, &protocol::stop(), "sensor")?;
    // The firmware exits QEMU once its final report is sent.
    let deadline = Instant::now() + Duration::from_secs(60).min(opts.timeout);
    let status = loop {
        if let Some(st) = q.child.try_wait()? {
            break st;
        }
        if Instant::now() > deadline {
            let _ = q.child.kill();
            bail!("QEMU did not exit after the end-of-flight record");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    done.store(true, Ordering::Release);
    let (raw, link) = reader.join().map_err(|_| anyhow::anyhow!("telemetry reader panicked"))??;
    let defmt =
        std::mem::replace(&mut q.defmt, std::thread::spawn(Vec::new)).join().unwrap_or_default();
    if opts.live {
        live_line(log, &shared.lock().unwrap().out);
        if std::io::IsTerminal::is_terminal(&std::io::stdout()) {
            println!();
        }
    }
    let mut c = Arc::try_unwrap(shared)
        .map_err(|_| anyhow::anyhow!("collector still shared"))?
        .into_inner()
        .unwrap();
    c.out.raw = raw;
    c.out.link = link;
    c.out.defmt = defmt;
    c.out.exit_code = status.code();
    c.out.wall = start.elapsed();
    if status.code() != Some(0) {
        bail!("QEMU exited with {status} (101 = firmware panic)");
    }
    Ok(c.out)
}

fn live_line(log: &FlightLog, out: &HilOutput) {
    let Some(&(ms, att)) = out.attitude.last() else { return };
    let t = ms as f64 / 1000.0;
    let truth = log.rows.iter().find(|r| to_us(r.t) / 1000 >= ms as u64).and_then(|r| r.truth);
    let d = |x: f32| (x as f64).to_degrees();
    let mut line = format!(
        "\rt {t:7.2} s  roll {:7.2}°  pitch {:7.2}°  yaw {:8.2}°",
        d(att[0]),
        d(att[1]),
        d(att[2])
    );
    if let Some(tr) = truth {
        line += &format!(
            "   truth {:7.2}° {:7.2}° {:8.2}°",
            tr[0].to_degrees(),
            tr[1].to_degrees(),
            tr[2].to_degrees()
        );
    }
    use std::io::IsTerminal;
    if std::io::stdout().is_terminal() {
        print!("{line}");
        let _ = std::io::stdout().flush();
    } else {
        println!("{}", line.trim_start_matches('\r'));
    }
}

/// Estimate rows (docs/formats.md) from a per-sample run, one per log row that produced output.
pub fn estimates(log: &FlightLog, out: &HilOutput) -> Vec<EstimateRow> {
    let by_t: HashMap<u64, &crate::log::LogRow> =
        log.rows.iter().map(|r| (to_us(r.t), r)).collect();
    out.samples
        .iter()
        .filter_map(|s| {
            let row = by_t.get(&s.t_us)?;
            let mut e = EstimateRow::from_state(
                row.t,
                s.att,
                s.bias,
                s.sd,
                s.update.as_ref(),
                Flags::from_bits_truncate(s.flags),
            );
            // WIND_COV carries the horizontal variance only: split evenly per axis.
            e.wind = s.wind.map(|(w, var)| {
                let sd = (var as f64 / 2.0).sqrt();
                (w.map(f64::from), [sd, sd])
            });
            Some(e)
        })
        .collect()
}
