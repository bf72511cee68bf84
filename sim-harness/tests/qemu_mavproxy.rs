//! A ground station nobody here wrote — MAVProxy, headless — on the QEMU firmware's
//! ground-station link for a whole (short) simulated flight at real time, its logs decoded
//! with pymavlink (`py/mavproxy_tlog.py`):
//! - not one BAD_DATA in its raw log nor in its telemetry log, and none of the per-sample
//!   HIL records (component 25) on its link;
//! - every message docs/mavlink.md lists for the link at its documented rate (±15 %, on
//!   MAVProxy's own receive clock), and nothing on the link the document does not list;
//! - on a good flight no warning, no `MAV_STATE_CRITICAL`, the AHRS healthy; on a flight
//!   whose GPS velocities go bad, the WARNING STATUSTEXT within 5 s, with the HEARTBEAT
//!   state and SYS_STATUS' AHRS bit to match.
//!
//! Needs `pip install MAVProxy` (`cargo xtask test` installs it).
mod qemu_common;

use sim_harness::hil::{self, GpsWire, Options};
use sim_harness::log::FlightLog;
use sim_harness::sim;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Seconds of each flight (real time: this is the test's wall time).
const FLIGHT_S: f64 = 40.0;
/// The bad flight's GPS velocities go bad from here on, flight time s.
const CORRUPT_FROM_S: f64 = 20.0;
/// Allowed relative difference between the flight's span and its span on MAVProxy's clock.
/// The pacer is a host thread: on a loaded 2-core machine it has lagged 6 % with both flights
/// at once, so the flights run one at a time and a link that falls behind still shows.
const REAL_TIME_TOL: f64 = 0.03;
/// Allowed relative error of a documented rate.
const RATE_TOL: f64 = 0.15;
/// STATUSTEXT severity WARNING (MAV_SEVERITY_WARNING = 4; lower is worse).
const WARNING: u8 = 4;
/// HEARTBEAT `MAV_STATE_CRITICAL`.
const CRITICAL: u8 = 5;

/// What MAVProxy logged of one flight.
#[derive(Debug, Default)]
struct Seen {
    values: BTreeMap<String, Vec<String>>,
    /// (severity, flight time s, text).
    texts: Vec<(u8, f64, String)>,
    /// (MAV_STATE, flight time s) at each change.
    states: Vec<(u8, f64)>,
    /// message key → (Hz, count).
    rates: BTreeMap<String, (f64, usize)>,
    /// MAVProxy's console output.
    console: String,
}

impl Seen {
    fn num(&self, key: &str, i: usize) -> f64 {
        self.values.get(key).and_then(|v| v.get(i)).and_then(|x| x.parse().ok()).unwrap_or(-1.0)
    }
}

fn parse(summary: &str, console: String) -> Seen {
    let mut s = Seen { console, ..Default::default() };
    for line in summary.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        match f.as_slice() {
            ["text", sev, ft, _wall, rest @ ..] => {
                s.texts.push((sev.parse().unwrap(), ft.parse().unwrap(), rest.join(" ")))
            }
            ["state", st, ft] => s.states.push((st.parse().unwrap(), ft.parse().unwrap())),
            ["rate", key, hz, n, _span] => {
                s.rates.insert(key.to_string(), (hz.parse().unwrap(), n.parse().unwrap()));
            }
            ["component", c, n] => {
                s.values.insert(format!("component{c}"), vec![n.to_string()]);
            }
            [key, rest @ ..] => {
                s.values.insert(key.to_string(), rest.iter().map(|x| x.to_string()).collect());
            }
            [] => {}
        }
    }
    s
}

/// MAVProxy on a free loopback port, then the flight streamed to it at real time.
fn fly(name: &str, fw: PathBuf, log: &FlightLog) -> Seen {
    // One flight at a time: two QEMUs, two MAVProxies and two pacers share 2 cores badly.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("wing-mavproxy-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let port = std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let tlog = dir.join("flight.tlog");
    // `python3 -m`: the module xtask installs, whether or not pip put its script on PATH.
    let mut gcs = Command::new("python3")
        .args(["-m", "MAVProxy.mavproxy"])
        .arg(format!("--master=udpin:127.0.0.1:{port}"))
        .args(["--non-interactive", "--daemon", "--nowait"])
        .arg(format!("--logfile={}", tlog.display()))
        .arg(format!("--state-basedir={}", dir.display()))
        .current_dir(&dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("starting MAVProxy");
    let console = collect(gcs.stdout.take().unwrap(), gcs.stderr.take().unwrap());
    wait_bound(port, &mut gcs);
    let items = hil::plan(log, GpsWire::Ubx);
    let opts = Options {
        pace: Some(1.0),
        mavlink_udp: Some(format!("127.0.0.1:{port}").parse().unwrap()),
        ..Options::hil(fw)
    };
    let started = Instant::now();
    let out = hil::run(log, &items, &opts).expect("HIL run");
    let wall = started.elapsed().as_secs_f64();
    assert_eq!(out.samples.len(), log.rows.len(), "{name}: the harness still gets every sample");
    // Let MAVProxy write its logs, then stop it as Ctrl-C would.
    std::thread::sleep(Duration::from_secs(2));
    let _ = Command::new("kill").arg("-INT").arg(gcs.id().to_string()).status();
    let deadline = Instant::now() + Duration::from_secs(10);
    while gcs.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = gcs.kill();
            let _ = gcs.wait();
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let console = console.join().unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/mavproxy_tlog.py");
    let o = Command::new("python3").arg(script).arg(&tlog).output().expect("python3");
    assert!(o.status.success(), "{name}: tlog decoder: {}", String::from_utf8_lossy(&o.stderr));
    let summary = String::from_utf8(o.stdout).unwrap();
    println!(
        "--- {name}: flight {FLIGHT_S} s, wall {wall:.1} s, firmware {}; MAVProxy's logs:\n{summary}",
        opts.firmware.display()
    );
    let _ = std::fs::remove_dir_all(&dir);
    parse(&summary, console)
}

/// Both output streams of MAVProxy, read to the end in the background.
fn collect(
    out: impl std::io::Read + Send + 'static,
    err: impl std::io::Read + Send + 'static,
) -> std::thread::JoinHandle<String> {
    let e = std::thread::spawn(move || {
        BufReader::new(err).lines().map_while(Result::ok).collect::<Vec<_>>().join("\n")
    });
    std::thread::spawn(move || {
        let o: Vec<String> = BufReader::new(out).lines().map_while(Result::ok).collect();
        o.join("\n") + "\n" + &e.join().unwrap_or_default()
    })
}

/// Waits until MAVProxy has bound its UDP port (read from /proc/net/udp, so the test never
/// holds the port itself while MAVProxy tries to bind it).
fn wait_bound(port: u16, gcs: &mut std::process::Child) {
    let local = format!(":{port:04X}");
    let bound = |table: &str| {
        table.lines().any(|l| l.split_whitespace().nth(1).is_some_and(|a| a.ends_with(&local)))
    };
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        match std::fs::read_to_string("/proc/net/udp") {
            Ok(t) if bound(&t) => return,
            Ok(_) => {}
            Err(_) => return std::thread::sleep(Duration::from_secs(3)), // no procfs: give it time
        }
        assert!(gcs.try_wait().unwrap().is_none(), "MAVProxy exited at start");
        assert!(Instant::now() < deadline, "MAVProxy did not bind udp port {port}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// A documented rate.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rate {
    Hz(f64),
    Events,
    Off,
}

/// docs/mavlink.md's ground-station table: message key → documented rate.
fn documented(gps_hz: f64) -> BTreeMap<String, Rate> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/mavlink.md");
    let text = std::fs::read_to_string(&path).unwrap();
    let (a, b) = (text.find("<!-- gcs-link:begin -->"), text.find("<!-- gcs-link:end -->"));
    let table = &text[a.expect("gcs-link:begin marker")..b.expect("gcs-link:end marker")];
    let mut doc = BTreeMap::new();
    for row in table.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let key = cells[1].trim_matches('`').to_string();
        let rate = cells[2];
        let hz = match rate {
            "on events" => Rate::Events,
            "off" => Rate::Off,
            "per GPS fix" => Rate::Hz(gps_hz),
            r => Rate::Hz(
                r.trim_end_matches(" Hz")
                    .parse::<f64>()
                    .unwrap_or_else(|_| panic!("docs/mavlink.md: rate {r:?} of {key}")),
            ),
        };
        doc.insert(key, hz);
    }
    assert!(doc.len() >= 10, "docs/mavlink.md's ground-station table: {doc:?}");
    doc
}

/// The documented rate of a measured key (`NAMED_VALUE_INT:X` → `NAMED_VALUE_INT:*`).
fn doc_rate(doc: &BTreeMap<String, Rate>, key: &str) -> Option<Rate> {
    doc.get(key).copied().or_else(|| {
        let (msg, _) = key.split_once(':')?;
        doc.get(&format!("{msg}:*")).copied()
    })
}

fn check_link(name: &str, s: &Seen, log: &FlightLog) {
    assert_eq!(s.num("raw_bad_data", 0), 0.0, "{name}: BAD_DATA in MAVProxy's raw log");
    assert_eq!(s.num("tlog_bad_data", 0), 0.0, "{name}: BAD_DATA in MAVProxy's telemetry log");
    assert!(s.num("raw_frames", 0) > 1000.0, "{name}: MAVProxy read too little");
    assert_eq!(s.num("component25", 0), -1.0, "{name}: HIL records reached the ground station");
    // Real time: the flight's ATTITUDE stream spans as long on MAVProxy's clock.
    let (flight, received) = (s.num("clock", 1), s.num("clock", 3));
    assert!(flight > FLIGHT_S - 2.0, "{name}: ATTITUDE covers {flight} s of flight");
    assert!(
        (received - flight).abs() <= REAL_TIME_TOL * flight,
        "{name}: {flight:.2} s of flight arrived over {received:.2} s"
    );
    let console = s.console.to_lowercase();
    for junk in ["fence breach", "bad_data", "bad data"] {
        assert!(!console.contains(junk), "{name}: MAVProxy says {junk:?}:\n{}", s.console);
    }
    let fixes = log.rows.iter().filter(|r| r.gps.is_some()).count() as f64;
    let gps_hz = fixes / (log.rows.last().unwrap().t - log.rows[0].t);
    let doc = documented(gps_hz);
    for (key, &(hz, n)) in &s.rates {
        let Some(want) = doc_rate(&doc, key) else {
            panic!("{name}: {key} goes to the ground station but docs/mavlink.md does not list it")
        };
        let want = match want {
            Rate::Events => continue,
            Rate::Off => panic!("{name}: {key} arrived ({n}), docs/mavlink.md says off"),
            Rate::Hz(w) => w,
        };
        assert!(
            (hz - want).abs() <= RATE_TOL * want,
            "{name}: {key} at {hz:.2} Hz ({n} messages), docs/mavlink.md says {want} Hz"
        );
    }
    for (key, want) in &doc {
        if matches!(want, Rate::Hz(_)) && !key.ends_with(":*") {
            assert!(s.rates.contains_key(key), "{name}: documented {key} never arrived");
        }
    }
    let named = s.rates.keys().filter(|k| k.starts_with("NAMED_VALUE_INT:")).count();
    assert_eq!(named, 36, "{name}: NAMED_VALUE_INT names on the link");
}

fn flight() -> FlightLog {
    let sc = sim::load_scenario("flight1").unwrap().with_duration(FLIGHT_S);
    sim::run(&sc, 5).unwrap().log
}

/// The receiver's velocities go bad: from `CORRUPT_FROM_S` each fix is off by a
/// deterministic ±6 m/s per axis (a multipath-struck or spoofed receiver that still
/// reports a good fix).
fn corrupted(mut log: FlightLog) -> FlightLog {
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    for r in &mut log.rows {
        if let Some(g) = r.gps.as_mut().filter(|_| r.t >= CORRUPT_FROM_S) {
            for v in &mut g.vel {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                *v += ((x >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 12.0;
            }
        }
    }
    log
}

fn available(test: &str) -> Option<PathBuf> {
    let fw = qemu_common::setup(test)?;
    let ok = Command::new("python3")
        .args(["-c", "import MAVProxy.mavproxy, pymavlink"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !ok {
        assert!(
            std::env::var_os("WING_AHRS_REQUIRE_QEMU").is_none(),
            "{test}: MAVProxy not available (`cargo xtask test` installs it)"
        );
        eprintln!("SKIP {test}: MAVProxy not installed (pip install MAVProxy)");
        return None;
    }
    Some(fw)
}

#[test]
fn mavproxy_sees_a_clean_real_time_link_and_no_false_alarm() {
    let Some(fw) = available("mavproxy_sees_a_clean_real_time_link_and_no_false_alarm") else {
        return;
    };
    let log = flight();
    let s = fly("good", fw, &log);
    check_link("good flight", &s, &log);
    let warnings: Vec<_> = s.texts.iter().filter(|t| t.0 <= WARNING).collect();
    assert!(warnings.is_empty(), "warnings on a good flight: {warnings:?}");
    // MAV_STATE_CALIBRATING until aligned, then MAV_STATE_ACTIVE to the end.
    let states: Vec<u8> = s.states.iter().map(|st| st.0).collect();
    assert_eq!(states, [2, 4], "HEARTBEAT states of a good flight: {:?}", s.states);
    // The AHRS is healthy from the first SYS_STATUS after alignment on.
    let (n, healthy) = (s.num("sys_status", 0), s.num("sys_status", 2));
    assert!(healthy >= n - 2.0, "AHRS healthy in {healthy} of {n} SYS_STATUS");
    let (n, good) = (s.num("estimator_status", 0), s.num("estimator_status", 2));
    assert!(good >= n - 2.0, "ESTIMATOR_ATTITUDE in {good} of {n} ESTIMATOR_STATUS");
}

#[test]
fn mavproxy_gets_the_ahrs_warning_within_5_s_of_bad_gps() {
    let Some(fw) = available("mavproxy_gets_the_ahrs_warning_within_5_s_of_bad_gps") else {
        return;
    };
    let log = corrupted(flight());
    let s = fly("bad-gps", fw, &log);
    check_link("bad-GPS flight", &s, &log);
    let early: Vec<_> = s.texts.iter().filter(|t| t.0 <= WARNING && t.1 < CORRUPT_FROM_S).collect();
    assert!(early.is_empty(), "warnings before the GPS went bad: {early:?}");
    let warn = s
        .texts
        .iter()
        .find(|t| t.0 <= WARNING && t.2.starts_with("AHRS unreliable"))
        .unwrap_or_else(|| panic!("no AHRS warning; texts: {:?}", s.texts));
    let delay = warn.1 - CORRUPT_FROM_S;
    println!("AHRS warning {delay:.2} s after the GPS went bad: {:?}", warn.2);
    assert!((0.0..=5.0).contains(&delay), "warning {delay:.2} s after the GPS went bad");
    assert!(
        s.states.iter().any(|st| st.0 == CRITICAL && st.1 >= CORRUPT_FROM_S),
        "HEARTBEAT never MAV_STATE_CRITICAL: {:?}",
        s.states
    );
    let (n, healthy) = (s.num("sys_status", 0), s.num("sys_status", 2));
    assert!(healthy < n - 3.0, "AHRS healthy in {healthy} of {n} SYS_STATUS");
}
