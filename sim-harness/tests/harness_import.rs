//! `import`: PX4 ULog and ArduPilot DataFlash → flight-log rows.
//!
//! - DataFlash: a simulated flight written as a `.bin` by an independent encoder below
//!   (FMT + IMU/GPS/GPA/ATT/ARSP, the real ArduPilot field layouts), imported back and
//!   checked against the simulation's own rows and truth; pymavlink's DFReader reads the
//!   same file when it is installed (checks the encoder itself).
//! - ULog: the real PX4 fixture `real/raw/sample_log_small.ulg` from shared/data, checked
//!   against pyulog's read of the same file.
use sim_harness::import::{self, Format};
use sim_harness::log::FlightLog;
use sim_harness::{data, sim};
use std::path::{Path, PathBuf};
use std::process::Command;

const DEG: f64 = 180.0 / std::f64::consts::PI;

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("wing-ahrs-import-{}-{name}", std::process::id()))
}

/// Minimal DataFlash encoder: one FMT per message type, then the messages.
struct DfWriter {
    buf: Vec<u8>,
}

impl DfWriter {
    fn new() -> Self {
        let mut w = DfWriter { buf: Vec::new() };
        w.fmt(128, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
        w
    }
    fn size(c: char) -> usize {
        match c {
            'b' | 'B' | 'M' => 1,
            'h' | 'H' | 'c' | 'C' => 2,
            'i' | 'I' | 'e' | 'E' | 'L' | 'f' | 'n' => 4,
            'q' | 'Q' | 'd' => 8,
            'N' => 16,
            'Z' => 64,
            _ => panic!("format char {c}"),
        }
    }
    fn fmt(&mut self, ty: u8, name: &str, format: &str, labels: &str) {
        let len = 3 + format.chars().map(Self::size).sum::<usize>();
        self.buf.extend([0xA3, 0x95, 128, ty, len as u8]);
        let pad = |s: &str, n: usize| {
            let mut v = s.as_bytes().to_vec();
            v.resize(n, 0);
            v
        };
        self.buf.extend(pad(name, 4));
        self.buf.extend(pad(format, 16));
        self.buf.extend(pad(labels, 64));
    }
    fn msg(&mut self, ty: u8, fields: &[u8]) {
        self.buf.extend([0xA3, 0x95, ty]);
        self.buf.extend(fields);
    }
}

fn le<T: ToLe>(v: T, out: &mut Vec<u8>) {
    v.put(out)
}

trait ToLe {
    fn put(self, out: &mut Vec<u8>);
}
macro_rules! tole {
    ($($t:ty),*) => {$(impl ToLe for $t { fn put(self, out: &mut Vec<u8>) { out.extend(self.to_le_bytes()) } })*};
}
tole!(u8, u16, u32, u64, i16, i32, f32);

const IMU: u8 = 130;
const GPS: u8 = 131;
const GPA: u8 = 132;
const ATT: u8 = 133;
const ARSP: u8 = 134;
const BARO: u8 = 135;
const PARM: u8 = 136;

/// Writes a simulated log as ArduPilot would: TimeUS from a 1 s boot offset, IMU
/// instance 0 = the log's IMU and instance 1 = a second, wrong IMU (must be ignored),
/// GPS Lat/Lng (1e-7 deg), Alt (cm), Spd/GCrs/VZ, BARO Alt (m), ATT in centidegrees from
/// the truth.
/// The board trim written as `AHRS_TRIM_Y`, rad.
const TRIM_Y: f32 = 0.06;

fn write_bin(log: &FlightLog, path: &Path) {
    let mut w = DfWriter::new();
    w.fmt(IMU, "IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ");
    w.fmt(
        GPS,
        "GPS",
        "QBBIHBcLLeffff",
        "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw",
    );
    w.fmt(GPA, "GPA", "QBCCCC", "TimeUS,I,VDop,HAcc,VAcc,SAcc");
    w.fmt(ATT, "ATT", "QccccCC", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw");
    w.fmt(ARSP, "ARSP", "QBff", "TimeUS,I,Airspeed,DiffPress");
    w.fmt(BARO, "BARO", "QBfff", "TimeUS,I,Alt,Press,Temp");
    // Parameters as ArduPilot ≥ 3.3 writes them: with a time stamp.
    w.fmt(PARM, "PARM", "QNf", "TimeUS,Name,Value");
    for (name, value) in [("GPS_DELAY_MS", 120f32), ("AHRS_TRIM_Y", TRIM_Y), ("AHRS_EKF_TYPE", 3.0)]
    {
        let mut b = Vec::new();
        le(1_000_000u64, &mut b);
        let mut n = name.as_bytes().to_vec();
        n.resize(16, 0);
        b.extend(n);
        le(value, &mut b);
        w.msg(PARM, &b);
    }
    for r in &log.rows {
        let us = 1_000_000 + (r.t * 1e6).round() as u64;
        for inst in 0..2u8 {
            let mut b = Vec::new();
            le(us, &mut b);
            le(inst, &mut b);
            let k = if inst == 0 { 1.0 } else { -3.0 };
            for v in r.gyro.iter().chain(&r.accel) {
                le((v * k) as f32, &mut b);
            }
            w.msg(IMU, &b);
        }
        if let Some(g) = r.gps {
            let spd = g.vel[0].hypot(g.vel[1]);
            let crs = g.vel[1].atan2(g.vel[0]).to_degrees().rem_euclid(360.0);
            let mut b = Vec::new();
            le(us, &mut b);
            le(0u8, &mut b);
            le(3u8, &mut b); // 3-D fix
            le(0u32, &mut b);
            le(0u16, &mut b);
            le(12u8, &mut b);
            le(90i16, &mut b);
            let [lat, lon, alt] = g.lla.expect("the simulator writes positions");
            le((lat * 1e7).round() as i32, &mut b);
            le((lon * 1e7).round() as i32, &mut b);
            le((alt * 100.0).round() as i32, &mut b); // cm
            le(spd as f32, &mut b);
            le(crs as f32, &mut b);
            le(g.vel[2] as f32, &mut b);
            le(0f32, &mut b);
            w.msg(GPS, &b);
            let mut b = Vec::new();
            le(us, &mut b);
            le(0u8, &mut b);
            for v in [1.2, 2.5, 3.5, g.speed_acc.unwrap_or(0.4)] {
                le((v * 100.0_f64).round() as u16, &mut b);
            }
            w.msg(GPA, &b);
        }
        if let Some(va) = r.airspeed {
            let mut b = Vec::new();
            le(us, &mut b);
            le(0u8, &mut b);
            le(va as f32, &mut b);
            le(0f32, &mut b);
            w.msg(ARSP, &b);
        }
        if let Some(h) = r.baro_alt {
            let mut b = Vec::new();
            le(us, &mut b);
            le(0u8, &mut b);
            for v in [h as f32, 101_325.0, 20.0] {
                le(v, &mut b);
            }
            w.msg(BARO, &b);
        }
        // ATT as EKF3 reports it (`getEulerAngles`): the IMU's Euler angles minus the
        // board trim, angle by angle.
        let tr = r.truth.expect("simulated truth");
        let cd = |a: f64| (a * DEG * 100.0).round();
        let mut b = Vec::new();
        le(us, &mut b);
        for a in [0.0, cd(tr[0]), 0.0, cd(tr[1] - TRIM_Y as f64), 0.0] {
            le(a as i16, &mut b);
        }
        le(cd(tr[2]).rem_euclid(36000.0) as u16, &mut b);
        w.msg(ATT, &b);
    }
    std::fs::write(path, &w.buf).unwrap();
}

fn sim_log(seconds: f64) -> FlightLog {
    // Realistic sensors: the barometer and the receiver's position error are in this preset.
    let sc = sim::load_scenario("flight1+spec=realistic").unwrap().with_duration(seconds);
    sim::run(&sc, 3).unwrap().log
}

#[test]
fn dataflash_import_reproduces_the_simulated_flight() {
    let log = sim_log(40.0);
    let bin = tmp("sim.bin");
    write_bin(&log, &bin);
    assert_eq!(import::detect(&bin).unwrap(), Format::DataFlash);
    let (imp, sum) = import::import(&bin).unwrap();
    std::fs::remove_file(&bin).ok();
    println!("{}", sum.describe());
    assert_eq!(imp.rows.len(), log.rows.len());
    let n_gps = log.rows.iter().filter(|r| r.gps.is_some()).count();
    assert_eq!(sum.gps_fixes, n_gps);
    assert_eq!(
        (sum.gps_positions, sum.baro),
        (n_gps, log.rows.iter().filter(|r| r.baro_alt.is_some()).count())
    );
    assert!(sum.notes.iter().any(|n| n.contains("instance 0 of 2")), "{:?}", sum.notes);
    // Time-stamped PARM messages are read: the autopilot's GPS lag and board trim are said.
    assert!(sum.notes.iter().any(|n| n.contains("GPS_DELAY_MS = 120 ms")), "{:?}", sum.notes);
    // … and the reference is turned back by the trim (EKF convention), so it is the IMU's
    // attitude again: the truth the IMU was simulated from, to the centidegree below.
    assert!(
        sum.notes.iter().any(|n| n.contains("AHRS_TRIM_X/Y/Z = 0.00°/3.44°/0.00° (the EKF's")),
        "{:?}",
        sum.notes
    );
    for (a, b) in imp.rows.iter().zip(&log.rows) {
        assert!((a.t - (b.t - log.rows[0].t)).abs() < 1e-6);
        for (x, y) in a.gyro.iter().chain(&a.accel).zip(b.gyro.iter().chain(&b.accel)) {
            assert_eq!(*x, *y as f32 as f64, "IMU instance 0, f32 as logged");
        }
        assert_eq!(a.gps.is_some(), b.gps.is_some(), "fix on its own row at t = {}", b.t);
        if let (Some(ga), Some(gb)) = (a.gps, b.gps) {
            for k in 0..3 {
                assert!((ga.vel[k] - gb.vel[k]).abs() < 1e-4, "{:?} vs {:?}", ga.vel, gb.vel);
            }
            let sacc = gb.speed_acc.unwrap_or(0.4);
            assert!((ga.speed_acc.unwrap() - sacc).abs() <= 0.005 + 1e-9);
            // Position: 1e-7° (1 cm) and 1 cm steps as logged.
            let (pa, pb) = (ga.lla.expect("imported position"), gb.lla.unwrap());
            assert!((pa[0] - pb[0]).abs() <= 0.6e-7 && (pa[1] - pb[1]).abs() <= 0.6e-7);
            assert!((pa[2] - pb[2]).abs() <= 0.006, "{pa:?} vs {pb:?}");
        }
        assert_eq!(a.airspeed.map(|v| v as f32), b.airspeed.map(|v| v as f32));
        assert_eq!(a.baro_alt.map(|v| v as f32), b.baro_alt.map(|v| v as f32));
        let (ra, tb) = (a.reference.unwrap(), b.truth.unwrap());
        for k in 0..3 {
            let d = sim_harness::metrics::wrap(ra[k] - tb[k]) * DEG;
            assert!(d.abs() <= 0.0051, "ATT centidegrees + trim vs truth: {d}°");
        }
    }
    // Replaying the import agrees with the autopilot attitude (= truth here) as
    // closely as replaying the simulation agrees with truth.
    let (e1, _) = sim_harness::estimate::replay_estimates(&imp, wing_ahrs::Config::default());
    let c = sim_harness::metrics::compare(&imp, &e1, 10.0).unwrap();
    assert_eq!(c.against, sim_harness::metrics::Against::Reference);
    let (e0, _) = sim_harness::estimate::replay_estimates(&log, wing_ahrs::Config::default());
    let c0 = sim_harness::metrics::compare(&log, &e0, 10.0).unwrap();
    for k in 0..2 {
        assert!((c.att[k].rms - c0.att[k].rms).abs() < 0.002, "{:?} vs {:?}", c.att, c0.att);
    }
}

/// ArduPilot ≤ 3.2's formats (ArduPlane 3.1 `LogStructure`): `TimeMS` boot time on the
/// IMU; on GPS `TimeMS` is the GPS time of week and the boot time is `T` (ms), speed and
/// course in cm/s and centidegrees (`E`, `e`). The fixes must land on their own IMU rows.
#[test]
fn dataflash_import_reads_arduplane_3_1_gps_timing() {
    let log = sim_log(20.0);
    let mut w = DfWriter::new();
    w.fmt(IMU, "IMU", "Iffffff", "TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ");
    w.fmt(
        GPS,
        "GPS",
        "BIHBcLLeeEefI",
        "Status,TimeMS,Week,NSats,HDop,Lat,Lng,RelAlt,Alt,Spd,GCrs,VZ,T",
    );
    for r in &log.rows {
        let ms = 1_000 + (r.t * 1e3).round() as u32;
        let mut b = Vec::new();
        le(ms, &mut b);
        for v in r.gyro.iter().chain(&r.accel) {
            le(*v as f32, &mut b);
        }
        w.msg(IMU, &b);
        if let Some(g) = r.gps {
            let spd = g.vel[0].hypot(g.vel[1]);
            let crs = g.vel[1].atan2(g.vel[0]).to_degrees().rem_euclid(360.0);
            let [lat, lon, alt] = g.lla.expect("the simulator writes positions");
            let mut b = Vec::new();
            le(3u8, &mut b);
            le(345_600_000 + ms, &mut b); // GPS time of week, ms: not the boot clock
            le(1822u16, &mut b);
            le(10u8, &mut b);
            le(120i16, &mut b);
            le((lat * 1e7).round() as i32, &mut b);
            le((lon * 1e7).round() as i32, &mut b);
            le((alt * 100.0).round() as i32, &mut b);
            le((alt * 100.0).round() as i32, &mut b);
            le((spd * 100.0).round() as u32, &mut b);
            le((crs * 100.0).round() as i32, &mut b);
            le(g.vel[2] as f32, &mut b);
            le(ms, &mut b);
            w.msg(GPS, &b);
        }
    }
    let bin = tmp("apm31.bin");
    std::fs::write(&bin, &w.buf).unwrap();
    let (imp, sum) = import::import(&bin).unwrap();
    std::fs::remove_file(&bin).ok();
    println!("{}", sum.describe());
    let n_gps = log.rows.iter().filter(|r| r.gps.is_some()).count();
    assert_eq!(sum.gps_fixes, n_gps, "every fix timed by `T`, on the IMU's clock");
    for (a, b) in imp.rows.iter().zip(&log.rows) {
        assert_eq!(a.gps.is_some(), b.gps.is_some(), "fix on its own row at t = {}", b.t);
        if let (Some(ga), Some(gb)) = (a.gps, b.gps) {
            for k in 0..2 {
                // cm/s and 0.01° on the wire: ≤ 1 cm/s + the course's share.
                assert!((ga.vel[k] - gb.vel[k]).abs() < 0.02, "{:?} vs {:?}", ga.vel, gb.vel);
            }
        }
    }
}

/// A log without `ATT` (its `LOG_BITMASK` left attitude out, as in some ArduPilot 4.x
/// logs): the reference is EKF3's `XKF1` core 0, not the other core nor the secondary
/// AHRS `AHR2`; and an old log's untimed `MSG` still names the firmware.
#[test]
fn dataflash_reference_falls_back_to_xkf1_core_0() {
    const XKF1: u8 = 136;
    const AHR2: u8 = 137;
    const MSG: u8 = 138;
    let log = sim_log(10.0);
    let mut w = DfWriter::new();
    w.fmt(MSG, "MSG", "Z", "Message");
    let mut b = b"ArduPlane V3.1.2beta1 (12345678)".to_vec();
    b.resize(64, 0);
    w.msg(MSG, &b);
    w.fmt(IMU, "IMU", "QBffffff", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ");
    w.fmt(XKF1, "XKF1", "QBccC", "TimeUS,C,Roll,Pitch,Yaw");
    w.fmt(AHR2, "AHR2", "QccC", "TimeUS,Roll,Pitch,Yaw");
    let cd = |a: f64| (a * DEG * 100.0).round();
    for r in &log.rows {
        let us = 1_000_000 + (r.t * 1e6).round() as u64;
        let mut b = Vec::new();
        le(us, &mut b);
        le(0u8, &mut b);
        for v in r.gyro.iter().chain(&r.accel) {
            le(*v as f32, &mut b);
        }
        w.msg(IMU, &b);
        let tr = r.truth.expect("simulated truth");
        // Core 1 and AHR2 are 10° off: they must not be chosen.
        for (core, off) in [(0u8, 0.0), (1u8, 10.0)] {
            let mut b = Vec::new();
            le(us, &mut b);
            le(core, &mut b);
            le((cd(tr[0]) + off * 100.0) as i16, &mut b);
            le(cd(tr[1]) as i16, &mut b);
            le(cd(tr[2]).rem_euclid(36000.0) as u16, &mut b);
            w.msg(XKF1, &b);
        }
        let mut b = Vec::new();
        le(us, &mut b);
        le((cd(tr[0]) + 1000.0) as i16, &mut b);
        le(cd(tr[1]) as i16, &mut b);
        le(cd(tr[2]).rem_euclid(36000.0) as u16, &mut b);
        w.msg(AHR2, &b);
    }
    let bin = tmp("xkf1.bin");
    std::fs::write(&bin, &w.buf).unwrap();
    let (imp, sum) = import::import(&bin).unwrap();
    std::fs::remove_file(&bin).ok();
    println!("{}", sum.describe());
    assert!(sum.notes.iter().any(|n| n.contains("ArduPlane V3.1.2beta1")), "{:?}", sum.notes);
    assert!(sum.notes.iter().any(|n| n.contains("`XKF1` core 0")), "{:?}", sum.notes);
    for (a, b) in imp.rows.iter().zip(&log.rows) {
        let (ra, tb) = (a.reference.expect("reference on every row"), b.truth.unwrap());
        for k in 0..3 {
            let d = sim_harness::metrics::wrap(ra[k] - tb[k]) * DEG;
            assert!(d.abs() <= 0.0051, "XKF1 core 0 centidegrees vs truth: {d}°");
        }
    }
}

#[test]
fn pymavlink_reads_the_test_encoder_the_same() {
    if !data::python_has("pymavlink") {
        data::skip("pymavlink_reads_the_test_encoder_the_same", "python3 with pymavlink absent");
        return;
    }
    let log = sim_log(5.0);
    let bin = tmp("py.bin");
    write_bin(&log, &bin);
    let script = "import sys\nfrom pymavlink import DFReader\nr=DFReader.DFReader_binary(sys.argv[1])\nn=0;g=0;s=0.0\nwhile True:\n m=r.recv_match(type=['IMU','GPS'])\n if m is None: break\n if m.get_type()=='IMU' and m.I==0: n+=1; s+=m.GyrX\n if m.get_type()=='GPS': g+=1\nprint(n,g,repr(s))\n";
    let out = Command::new("python3").args(["-c", script]).arg(&bin).output().unwrap();
    let (imp, _) = import::import(&bin).unwrap();
    std::fs::remove_file(&bin).ok();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let f: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(f[0].parse::<usize>().unwrap(), imp.rows.len());
    assert_eq!(f[1].parse::<usize>().unwrap(), imp.rows.iter().filter(|r| r.gps.is_some()).count());
    let s: f64 = imp.rows.iter().map(|r| r.gyro[0]).sum();
    assert!((f[2].parse::<f64>().unwrap() - s).abs() < 1e-9 * imp.rows.len() as f64);
}

#[test]
fn real_px4_ulog_matches_pyulog() {
    const T: &str = "real_px4_ulog_matches_pyulog";
    let Some(ulg) = data::data_file("real/raw/sample_log_small.ulg") else {
        data::skip(T, "real/raw/sample_log_small.ulg not found (set WING_AHRS_DATA)");
        return;
    };
    let (log, sum) = import::import(&ulg).unwrap();
    println!("{}", sum.describe());
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/ulog_summary.py");
    let out = match Command::new("python3").arg(script).arg(&ulg).output() {
        Ok(o) if o.status.success() => String::from_utf8(o.stdout).unwrap(),
        _ => {
            data::skip(T, "python3 with pyulog absent (pip install pyulog)");
            return;
        }
    };
    let val = |key: &str| -> f64 {
        let l = out.lines().find(|l| l.starts_with(key)).unwrap_or_else(|| panic!("{key}"));
        l.rsplit(' ').next().unwrap().parse().unwrap()
    };
    assert_eq!(log.rows.len() as f64, val("imu_n"));
    for (k, name) in ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"].iter().enumerate() {
        let ours: f64 = log.rows.iter().map(|r| r.gyro[k]).sum();
        assert!((ours - val(&format!("sum {name}"))).abs() < 1e-9, "{name}");
    }
    let az: f64 = log.rows.iter().map(|r| r.accel[2]).sum();
    assert!((az - val("sum accelerometer_m_s2[2]")).abs() < 1e-6);
    let fixes: Vec<_> = log.rows.iter().filter_map(|r| r.gps).collect();
    assert_eq!(fixes.len() as f64, val("gps_3d"));
    let vn: f64 = fixes.iter().map(|g| g.vel[0]).sum();
    assert!((vn - val("gps_sum_vn")).abs() < 1e-6);
    // The reference attitude at the row of the first attitude sample equals pyulog's roll.
    let i = log.rows.iter().position(|r| r.t >= (val("att0_t") - sum.t0_us as f64) * 1e-6);
    let r = log.rows[i.unwrap()].reference.unwrap();
    assert!((r[0] - val("att0_roll")).abs() < 0.01, "{} vs {}", r[0], val("att0_roll"));
}

#[test]
fn import_errors_are_clear() {
    let junk = tmp("junk.ulg");
    std::fs::write(&junk, b"not a log at all").unwrap();
    let e = import::import(&junk).unwrap_err().to_string();
    assert!(e.contains("not a ULog"), "{e}");
    let empty_bin = tmp("empty.bin");
    let mut w = DfWriter::new();
    w.fmt(ATT, "ATT", "QccccCC", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw");
    std::fs::write(&empty_bin, &w.buf).unwrap();
    let e = format!("{:#}", import::import(&empty_bin).unwrap_err());
    assert!(e.contains("no IMU messages"), "{e}");
    std::fs::remove_file(&junk).ok();
    std::fs::remove_file(&empty_bin).ok();
}

/// The raw InertialNav exports of flights a and b (shared data `real/raw/*.zip`, PX4 sdlog2
/// logs as text) import to the rows of the CSVs that were converted from them outside the
/// project: the same IMU samples, fixes and reference attitude.
#[test]
fn inertialnav_export_reproduces_the_shared_csv() {
    const T: &str = "inertialnav_export_reproduces_the_shared_csv";
    for (zip, csv) in [
        ("real/raw/InputFilesPX4_search.zip", "real/px4_2014_flight_a.csv"),
        ("real/raw/InputFilesPX4_flow.zip", "real/px4_2014_flight_b.csv"),
    ] {
        let (Some(zip), Some(csv)) = (data::data_file(zip), data::data_file(csv)) else {
            data::skip(T, &format!("{zip} or {csv} not found (set WING_AHRS_DATA)"));
            return;
        };
        let (imp, sum) = import::import(&zip).unwrap();
        let conv = sim_harness::csv::read_log(&csv).unwrap();
        println!("{}\n{}", zip.display(), sum.describe());
        assert_eq!(imp.rows.len(), conv.rows.len());
        let close =
            |a: &[f64], b: &[f64], tol: f64| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        // The reference: `import` interpolates between the ~50 Hz ATT samples, the outside
        // conversion held the last one, so they differ by up to one sample's change.
        let mut ref_sq = [0.0f64; 3];
        for (a, b) in imp.rows.iter().zip(&conv.rows) {
            assert!((a.t - b.t).abs() < 1e-6, "t {} vs {}", a.t, b.t);
            assert!(
                close(&a.gyro, &b.gyro, 1e-9) && close(&a.accel, &b.accel, 1e-9),
                "IMU at {}",
                a.t
            );
            assert_eq!(a.airspeed.is_some(), b.airspeed.is_some(), "airspeed row at {}", a.t);
            let (ra, rb) = (a.reference.unwrap(), b.reference.unwrap());
            for k in 0..3 {
                let d = (ra[k] - rb[k] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                assert!(d.abs() < 5f64.to_radians(), "reference at {}: {ra:?} vs {rb:?}", a.t);
                ref_sq[k] += d * d;
            }
        }
        for sq in ref_sq {
            let rms = (sq / imp.rows.len() as f64).sqrt().to_degrees();
            assert!(rms < 0.3, "reference RMS difference {rms}°");
        }
        let fixes = |l: &sim_harness::log::FlightLog| -> Vec<[f64; 3]> {
            l.rows.iter().filter_map(|r| r.gps.map(|g| g.vel)).collect()
        };
        let (fa, fb) = (fixes(&imp), fixes(&conv));
        assert!(fa.len() >= 700 && fa.len() == fb.len(), "{} vs {} fixes", fa.len(), fb.len());
        assert!(fa.iter().zip(&fb).all(|(a, b)| close(a, b, 1e-9)));
        assert!(imp.rows.iter().filter(|r| r.airspeed.is_some()).count() > 5_000);
    }
}
