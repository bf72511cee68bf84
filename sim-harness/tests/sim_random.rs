//! Randomised Monte Carlo flights (`random:SEED`): reproducible from the name, every
//! draw flies (no stall, crash or divergence), and the draws cover the airframes, both
//! flight kinds, winds up to 10 m/s, turbulence and both sensor presets.
use sim_harness::sim;

/// Seeds flown by the test (each 120 s).
const SEEDS: u64 = 40;

#[test]
fn random_flights_fly_and_cover_the_space() {
    let (mut kin, mut airframes, mut turb, mut realistic, mut wmax) =
        (0, std::collections::BTreeSet::new(), 0, 0, 0.0f64);
    for seed in 1..=SEEDS {
        let name = format!("random:{seed}");
        let sc = sim::load_scenario(&name).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        assert_eq!(sc, sim::load_scenario(&name).unwrap(), "{name}: reproducible");
        let o =
            sim::run(&sc, seed).unwrap_or_else(|e| panic!("{name} ({}): {e:#}", sc.description));
        let va_min = o.truth.iter().map(|x| x.airspeed).fold(f64::MAX, f64::min);
        println!("{name:10} Va ≥ {va_min:4.1} m/s  {}", sc.description);
        assert!(va_min > 0.5 * sc.initial.airspeed_m_s, "{name}: stalled ({va_min} m/s)");
        if sc.segments.is_empty() {
            airframes.insert(sc.airframe.name.clone());
            let roll = o.log.rows.iter().map(|r| r.truth.unwrap()[0].abs()).fold(0.0, f64::max);
            assert!(roll.to_degrees() < 80.0, "{name}: upset, roll {}°", roll.to_degrees());
        } else {
            kin += 1;
        }
        turb += (sc.wind.turbulence != "none") as usize;
        realistic += (sc.sensor_preset == "realistic") as usize;
        wmax = wmax.max(sc.wind.ned_m_s[0].hypot(sc.wind.ned_m_s[1]));
    }
    println!("{kin} kinematic, airframes {airframes:?}, {turb} turbulent, {realistic} realistic, wind up to {wmax:.1} m/s");
    assert!(kin >= 5 && airframes.len() == 2 && turb >= 10 && realistic >= 10 && wmax > 6.0);
    assert_ne!(sim::load_scenario("random:1").unwrap(), sim::load_scenario("random:2").unwrap());
    assert!(sim::load_scenario("random:x").is_err());
    assert_eq!(sim::names::expand("random").len(), sim::names::RANDOM_GROUP as usize);
}

#[test]
#[ignore]
fn describe() {
    let n = std::env::var("SIM_RANDOM").unwrap_or("random:1".into());
    println!("{}", sim::random::scenario_toml(n.trim_start_matches("random:").parse().unwrap()));
}
