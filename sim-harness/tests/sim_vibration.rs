//! Airframe vibration (scenario `[[vibration]]`, docs/scenarios.md): the simulated IMU
//! senses it, and the quaternion filter's per-interval test counts and flags it
//! (`Health::vibration`, `Flags::VIBRATION`, the estimate CSV's `vibration` word) during it
//! and not outside it, while the attitude error against the simulation's truth stays bounded.
use sim_harness::estimate::replay_estimates;
use sim_harness::{metrics, sim};
use wing_ahrs::Config;

const DEG: f64 = 180.0 / std::f64::consts::PI;

fn scenario(extra: &str) -> sim::Scenario {
    let path =
        std::env::temp_dir().join(format!("wing-vib-{}-{}.toml", std::process::id(), extra.len()));
    let body = format!("base = \"flight1\"\nname = \"flight1_vibration\"\n{extra}");
    std::fs::write(&path, body).unwrap();
    let sc = sim::load_scenario(path.to_str().unwrap()).unwrap();
    std::fs::remove_file(&path).ok();
    sc
}

#[test]
fn vibration_is_flagged_during_it_only_and_attitude_stays_bounded() {
    // 3 m/s² RMS per axis at 37 Hz (σ 30× the thesis IMU's 0.1 m/s² noise), 1 °/s on the gyro,
    // for 30 s in the middle of the flight (turns included).
    let vib = "[[vibration]]\nstart_s = 40.0\nend_s = 70.0\naccel_m_s2 = 3.0\ngyro_deg_s = 1.0\n";
    let (on, off) = (scenario(vib), scenario(""));
    assert_eq!(on.vibration.len(), 1);
    let cfg = Config::default();
    let mut figures = Vec::new();
    for (sc, shaken) in [(&on, true), (&off, false)] {
        let out = sim::run(sc, 4).unwrap();
        let (est, ahrs) = replay_estimates(&out.log, cfg);
        // Rows flagged, inside the episode (plus one GPS interval and the latency compensated, ≤ 0.3 s, after it)
        // and outside it.
        let flagged = |r: &&sim_harness::estimate::EstimateRow| r.flags.contains("vibration");
        let inside = est.iter().filter(|r| r.t >= 40.0 && r.t < 70.6).filter(flagged).count();
        let outside = est.iter().filter(|r| !(r.t >= 40.0 && r.t < 70.6)).filter(flagged).count();
        let n_in = est.iter().filter(|r| r.t >= 40.2 && r.t < 70.0).count();
        let c = metrics::compare(&out.log, &est, 20.0).unwrap();
        let count = ahrs.health().vibration;
        println!(
            "{}: Health::vibration {count}, rows flagged inside {inside}/{n_in}, outside {outside}; roll/pitch RMS {:.3}/{:.3}°, max {:.2}/{:.2}°",
            if shaken { "vibration 40–70 s" } else { "no vibration" },
            c.att[0].rms * DEG,
            c.att[1].rms * DEG,
            c.att[0].max_abs * DEG,
            c.att[1].max_abs * DEG
        );
        assert_eq!(outside, 0, "flagged outside the episode");
        if shaken {
            // 10 Hz fixes over 30 s: ~300 intervals, every one flagged.
            assert!(count >= 295, "{count}");
            assert!(inside as f64 >= 0.98 * n_in as f64, "{inside} of {n_in}");
        } else {
            assert_eq!((count, inside), (0, 0));
        }
        figures.push([c.att[0].rms, c.att[1].rms, c.att[0].max_abs, c.att[1].max_abs]);
    }
    // Bounded: vibration 30× the noise spec costs little, because each interval's scatter is in R.
    let (a, b) = (figures[0], figures[1]);
    assert!(a[0] * DEG < 1.0 && a[1] * DEG < 1.0, "RMS {a:?}");
    assert!(a[2] * DEG < 3.0 && a[3] * DEG < 3.0, "max {a:?}");
    assert!(a[0] < 4.0 * b[0].max(0.1 / DEG) && a[1] < 4.0 * b[1].max(0.1 / DEG), "{a:?} vs {b:?}");
}

/// The sensed vibration has the configured RMS (accelerometer minus true specific force).
#[test]
fn simulated_vibration_has_its_rms_and_only_in_its_window() {
    let sc = scenario("[[vibration]]\nstart_s = 10.0\nend_s = 30.0\naccel_m_s2 = 2.0\n");
    let out = sim::run(&sc, 1).unwrap();
    let resid = |a: f64, b: f64| -> f64 {
        let (mut s, mut n) = (0.0, 0);
        for (r, x) in out.log.rows.iter().zip(&out.truth) {
            if r.t >= a && r.t < b {
                s += (r.accel[0] - x.specific_force[0]).powi(2);
                n += 1;
            }
        }
        (s / n as f64).sqrt()
    };
    let (inside, outside) = (resid(10.0, 30.0), resid(40.0, 60.0));
    println!("accelerometer − truth RMS (x): inside {inside:.3} m/s², outside {outside:.3} m/s²");
    // Inside: 2 m/s² (± the draw of 20 s of a 5 Hz-wide process) on top of the 0.02 noise.
    assert!((inside / 2.0 - 1.0).abs() < 0.15, "{inside}");
    assert!(outside < 0.05, "{outside}");
}
