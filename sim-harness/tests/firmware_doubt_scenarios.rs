//! The firmware's "AHRS unreliable" predicate (`src/bin/wing-ahrs-fw/doubt.rs`, plain core
//! code) fed as the firmware feeds it — every sample's flags, every new update, the gate
//! resets once a second — on the host replay of every built-in scenario: no warning on the
//! flights whose estimate is good, the GPS-lost warning on the flight with an outage.
#[path = "../../src/bin/wing-ahrs-fw/doubt.rs"]
#[allow(dead_code)]
mod doubt;

use doubt::{Change, Gates, Monitor, Reason};
use sim_harness::{replay, sim};

/// Every announcement on the replay of `scenario` (seed 1): (flight time s, change).
fn announcements(scenario: &str) -> Vec<(f64, Change)> {
    let sc = sim::load_scenario(scenario).unwrap();
    let log = sim::run(&sc, 1).unwrap().log;
    let cfg = wing_ahrs::Config::default();
    let mut m = Monitor::new(Gates::of(&cfg));
    let (mut seq, mut n, mut out) = (0, 0u32, Vec::new());
    replay::run(&log, cfg, |row, a| {
        let t = replay::to_us(row.t);
        let u = a.last_update();
        if u.seq != seq {
            seq = u.seq;
            m.on_update(u);
        }
        n += 1;
        if n % 100 == 0 {
            m.on_resets(t, a.health().gate_resets.iter().sum());
        }
        if let Some(c) = m.step(t, a.flags()) {
            out.push((row.t, c));
        }
    });
    out
}

#[test]
fn no_warning_on_the_good_flights_and_one_for_the_outage() {
    for name in [
        "level",
        "flight1",
        "flight2",
        "coordinated_turn",
        "aggressive",
        "aerobatics",
        "aerobatics_realistic",
        "aerobatics_wind5",
    ] {
        let a = announcements(name);
        println!("{name}: {a:?}");
        assert!(a.is_empty(), "{name}: {a:?}");
    }
    let a = announcements("flight1_outage");
    println!("flight1_outage: {a:?}");
    assert!(matches!(a.first(), Some((_, Change::Raised(Reason::GpsLost)))), "{a:?}");
    assert!(matches!(a.last(), Some((_, Change::Recovered))), "{a:?}");
}
