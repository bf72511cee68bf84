//! The wind suite: the `BASE+modifiers` grammar, the `wind` group, the shear and
//! gust shapes in the flown truth, and every base surviving the harshest wind.
use sim_harness::sim::{self, names, rotation as rot};

#[test]
fn modifier_grammar_sets_the_wind_it_names() {
    let sc = sim::load_scenario("flight2+wind=6@45,turb=light,spec=realistic,dur=30").unwrap();
    let s = 6.0 / 2f64.sqrt();
    let w = sc.wind.ned_m_s;
    // From 045°: blowing towards the south-west.
    assert!((w[0] + s).abs() < 1e-12 && (w[1] + s).abs() < 1e-12 && w[2] == 0.0, "{w:?}");
    assert_eq!(sc.wind.turbulence, "light");
    assert_eq!(sc.sensor_preset, "realistic");
    assert_eq!(sc.sensors, sim::sensors::SensorParams::realistic());
    assert_eq!(sc.duration, 30.0);
    assert_eq!(sc.name, "flight2+wind=6@45,turb=light,spec=realistic,dur=30");
    // The base's maneuvers are kept.
    assert_eq!(sc.maneuvers, sim::load_scenario("flight2").unwrap().maneuvers);
    // Shear along the wind, gust train inside the duration.
    let sc = sim::load_scenario("flight1+wind=10@270,shear=0.05,gust=3").unwrap();
    assert!((sc.wind.ned_m_s[1] - 10.0).abs() < 1e-12, "from the west: towards east");
    assert!((sc.wind.shear_m_s_per_m[1] - 0.05).abs() < 1e-12);
    assert_eq!(sc.wind.gust.len(), 6, "t = 10, 25, …, 85 s within 100 s");
    for bad in [
        "flight1+wind=6@x",
        "flight1+speed=3",
        "flight1+turb=severe",
        "flight1+shear=0.1",
        "flight1+wind=3,wind=4",
        "nosuch+wind=3",
    ] {
        let e = format!("{:#}", sim::load_scenario(bad).unwrap_err());
        println!("{bad}: {e}");
        assert!(e.len() > 20, "{bad}: an explanation");
    }
}

#[test]
fn the_wind_group_covers_every_base_speed_and_turbulence() {
    let g = names::expand("wind");
    assert_eq!(g.len(), names::WIND_BASES.len() * names::WIND_CONDITIONS.len());
    assert_eq!(names::expand("flight1"), vec!["flight1".to_string()]);
    let mut speeds = vec![];
    for n in &g {
        let sc = sim::load_scenario(n).unwrap_or_else(|e| panic!("{n}: {e:#}"));
        let w = sc.wind.ned_m_s;
        speeds.push((w[0].hypot(w[1]) * 10.0).round() as i64);
    }
    for s in [30, 60, 100] {
        assert!(speeds.contains(&s), "{s}");
    }
    for t in ["turb=light", "turb=moderate", "shear=", "gust="] {
        assert!(g.iter().any(|n| n.contains(t)), "{t}");
    }
}

#[test]
fn shear_and_gusts_appear_in_the_truth_wind() {
    // No turbulence, so the truth wind is the steady profile exactly.
    let sc = sim::load_scenario("flight1+wind=6@180,shear=0.05,gust=3,dur=45").unwrap();
    let o = sim::run(&sc, 2).unwrap();
    let h0 = sc.initial.altitude_m;
    let mut worst = 0.0f64;
    let (mut peak, mut climb) = (0.0f64, 0.0f64);
    for (r, x) in o.log.rows.iter().zip(&o.truth) {
        let h = -x.position_ned[2];
        // Independent of WindSpec::steady_at: 6 m/s towards north, shear, gusts (crosswind
        // 90° right of it = east, up, along).
        let mut w = [6.0 + 0.05 * (h - h0), 0.0, 0.0];
        for (k, dir) in [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]].iter().enumerate() {
            let t0 = 10.0 + 15.0 * k as f64;
            if (t0..=t0 + 4.0).contains(&r.t) {
                let a = 1.5 * (1.0 - (std::f64::consts::TAU * (r.t - t0) / 4.0).cos());
                w = rot::add(w, rot::scale(*dir, a));
                peak = peak.max(a);
            }
        }
        let tw = r.truth_wind.expect("the simulator writes the wind truth");
        assert_eq!(tw, x.wind_ned);
        worst = worst.max(rot::norm(rot::sub(tw, w)));
        climb = climb.max(h - h0);
    }
    println!("shear+gust: max |wind − profile| {worst:.2e} m/s, gust peak {peak:.2} m/s, climbed {climb:.1} m");
    assert!(worst < 1e-9, "truth wind follows the shear and 1 − cos gust profile");
    assert!((peak - 3.0).abs() < 0.01 && climb > 10.0, "the flight exercises both");
}

#[test]
fn every_wind_base_survives_the_harshest_conditions() {
    for b in names::WIND_BASES {
        for c in ["wind=10@315,turb=moderate", "wind=6@180,shear=0.05,gust=3"] {
            let n = format!("{b}+{c}");
            let o = sim::run(&sim::load_scenario(&n).unwrap(), 1)
                .unwrap_or_else(|e| panic!("{n}: {e:#}"));
            let va: Vec<f64> = o.truth.iter().map(|x| x.airspeed).collect();
            let lo = va.iter().cloned().fold(f64::MAX, f64::min);
            let roll = o.log.rows.iter().map(|r| r.truth.unwrap()[0].abs()).fold(0.0, f64::max);
            println!("{n:45} Va min {lo:5.1} m/s, |roll| max {:5.1}°", roll.to_degrees());
            assert!(
                lo > 0.6 * sim::load_scenario(b).unwrap().initial.airspeed_m_s,
                "{n}: no stall"
            );
            assert!(roll.to_degrees() < 80.0, "{n}: no upset");
        }
    }
}
