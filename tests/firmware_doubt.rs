//! The firmware's "attitude unreliable" monitor (`src/bin/wing-ahrs-fw/doubt.rs`, plain
//! core code, so it runs on the host too): what raises the warning, when it is announced,
//! and that recovery waits its hold time.
#[path = "../src/bin/wing-ahrs-fw/doubt.rs"]
#[allow(dead_code)]
mod doubt;

use doubt::{unreliable, Change, Evidence, Gates, Monitor, Reason, RECOVER_US};
use wing_ahrs::{AxisStatus, AxisUpdate, Config, Flags, UpdateRecord};

fn update(status: AxisStatus, nu: f32) -> UpdateRecord {
    let a = AxisUpdate { z: 0.0, innovation: nu, variance: 1.0, status };
    UpdateRecord { axes: [a; 3], ..Default::default() }
}

const OK: Flags = Flags::ALIGNED;

#[test]
fn predicate_names_the_first_reason() {
    let e = |flags, gated_recent, since_reset_us| Evidence {
        flags,
        gated_recent,
        since_reset_us,
        heading_unmeasured_us: 0,
    };
    assert_eq!(unreliable(&e(OK, 0, None)), None);
    assert_eq!(unreliable(&e(OK, 7, Some(20_000_000))), None);
    assert_eq!(unreliable(&e(OK, 8, None)), Some(Reason::Gating));
    assert_eq!(unreliable(&e(OK, 8, Some(1))), Some(Reason::Realigned));
    assert_eq!(unreliable(&e(OK | Flags::GPS_LOST, 8, Some(1))), Some(Reason::GpsLost));
    assert_eq!(unreliable(&e(Flags::default(), 0, None)), Some(Reason::Realigned));
    // The heading unmeasured: doubtful after 10 s, not during a manoeuvre's few seconds.
    let slow =
        |us| Evidence { heading_unmeasured_us: us, ..e(OK | Flags::YAW_UNOBSERVABLE, 0, None) };
    assert_eq!(unreliable(&slow(9_900_000)), None);
    assert_eq!(unreliable(&slow(10_000_000)), Some(Reason::HeadingUnobservable));
    for r in [Reason::GpsLost, Reason::Realigned, Reason::Gating, Reason::HeadingUnobservable] {
        assert!(r.text().len() <= 50, "STATUSTEXT holds 50 characters: {}", r.text());
    }
}

#[test]
fn gating_raises_at_once_and_recovery_waits() {
    let mut m = Monitor::new(Gates::of(&Config::default()));
    let mut t = 0u64;
    let mut step = |m: &mut Monitor, st: AxisStatus, nu: f32| {
        t += 100_000; // 10 Hz updates
        m.on_update(&update(st, nu));
        (t, m.step(t, OK))
    };
    // Occasional rejections (a manoeuvre's onset) do not raise it.
    for i in 0..40 {
        let st = if i % 5 == 0 { AxisStatus::Gated } else { AxisStatus::Accepted };
        assert_eq!(step(&mut m, st, 0.5).1, None, "update {i}");
    }
    // Persistent gating does, on the 8th rejection of 16.
    let mut raised = None;
    for i in 0..8 {
        if let (_, Some(c)) = step(&mut m, AxisStatus::Gated, 10.0) {
            raised = Some((i, c));
        }
    }
    assert_eq!(raised.map(|r| r.1), Some(Change::Raised(Reason::Gating)));
    assert!(raised.unwrap().0 <= 7);
    assert_eq!(m.raised(), Some(Reason::Gating));
    // Test ratio of the rejected updates: Σν²/S over the 3-dof gate, > 1.
    let (vel, heading) = m.take_ratios();
    assert!((vel - 300.0 / 16.27).abs() < 1e-3, "{vel}");
    assert_eq!(heading, 0.0);
    assert_eq!(m.take_ratios(), (0.0, 0.0));
    // Good updates again: the window clears after 9 more, then 3 s of quiet before "recovered".
    let mut first_good = None;
    let mut recovered_at = None;
    for _ in 0..80 {
        let (now, c) = step(&mut m, AxisStatus::Accepted, 0.5);
        first_good.get_or_insert(now);
        if c == Some(Change::Recovered) {
            recovered_at = Some(now);
            break;
        }
    }
    let (c, r) = (first_good.unwrap(), recovered_at.expect("never recovered"));
    assert!(r - c >= RECOVER_US + 800_000, "recovered {} µs after the gating stopped", r - c);
    assert_eq!(m.raised(), None);
}

#[test]
fn a_gate_reset_holds_the_warning_and_nothing_before_alignment() {
    let mut m = Monitor::new(Gates::of(&Config::default()));
    m.on_resets(1_000_000, 0);
    assert_eq!(m.step(1_000_000, OK), None);
    m.on_resets(2_000_000, 1);
    assert_eq!(m.step(2_000_000, OK), Some(Change::Raised(Reason::Realigned)));
    assert_eq!(m.step(11_000_000, OK), None, "held for 10 s");
    assert_eq!(m.step(12_000_000, OK), None, "then 3 s of recovery");
    assert_eq!(m.step(15_000_000, OK), Some(Change::Recovered));
    // Not yet aligned: calibrating, never a warning; aligning again later: unreliable.
    let mut m = Monitor::new(Gates::of(&Config::default()));
    assert_eq!(m.step(1, Flags::GPS_LOST), None);
    assert!(!m.aligned_once());
    assert_eq!(m.step(2, Flags::GPS_LOST | Flags::ALIGNED), Some(Change::Raised(Reason::GpsLost)));
    assert_eq!(m.step(3_100_000, OK), None);
    assert_eq!(m.step(6_100_000, OK), Some(Change::Recovered));
    assert_eq!(m.step(6_200_000, Flags::default()), Some(Change::Raised(Reason::Realigned)));
}
