//! NEES/NIS over 50 Monte Carlo runs of thesis-spec flight1 with the default EKF1
//! against their 95 % χ² bounds. Prints the figures; asserts the filter is not
//! over-confident in attitude (the run-averaged 3-dof NEES above its upper bound in
//! less than half of the epochs) and never produces NaN or a non-PD P.
use sim_harness::{montecarlo, sim};
use wing_ahrs::Config;

#[test]
fn nees_nis_over_50_runs() {
    let sc = sim::load_scenario("flight1").unwrap().with_spec(sim::SensorSpec::Thesis);
    let res = montecarlo::run(50, 1, Config::default(), 10.0, false, |s| Ok(sim::run(&sc, s)?.log)).unwrap();
    println!("{}", montecarlo::format(&res));
    assert_eq!(res.runs.iter().filter(|r| r.broken).count(), 0);
    let n3 = res.nees3.as_ref().unwrap();
    assert!(n3.above < 0.5, "attitude NEES above its 95 % bound in {:.0} % of epochs", 100.0 * n3.above);
}
