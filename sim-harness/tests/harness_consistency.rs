//! NEES/NIS over 50 Monte Carlo runs of thesis-spec flight1 with the default EKF1
//! against their 95 % χ² bounds. Prints the figures; asserts the filter is not
//! over-confident in attitude (the run-averaged 3-dof NEES above its upper bound in
//! less than half of the epochs), that the roll and pitch innovations are consistent
//! with their per-update R (`measure::noise`: the run-averaged NIS inside its 95 %
//! bounds in ≥ 85 % of updates, its overall mean inside the bounds), and never
//! produces NaN or a non-PD P.
use sim_harness::{montecarlo, sim};
use wing_ahrs::Config;

#[test]
fn nees_nis_over_50_runs() {
    let sc = sim::load_scenario("flight1").unwrap().with_spec(sim::SensorSpec::Thesis);
    let res = montecarlo::run(50, 1, Config::euler(), 10.0, false, |s| Ok(sim::run(&sc, s)?.log))
        .unwrap();
    println!("{}", montecarlo::format(&res));
    assert_eq!(res.runs.iter().filter(|r| r.broken).count(), 0);
    let n3 = res.nees3.as_ref().unwrap();
    assert!(
        n3.above < 0.5,
        "attitude NEES above its 95 % bound in {:.0} % of epochs",
        100.0 * n3.above
    );
    for (i, axis) in ["roll", "pitch"].iter().enumerate() {
        let nis = res.nis[i].as_ref().unwrap();
        assert!(
            nis.inside >= 0.85,
            "{axis} NIS inside its bounds in only {:.0} % of updates",
            100.0 * nis.inside
        );
        assert!(
            (nis.bounds.0..=nis.bounds.1).contains(&nis.mean),
            "{axis} NIS mean {} outside {:?}",
            nis.mean,
            nis.bounds
        );
    }
}
