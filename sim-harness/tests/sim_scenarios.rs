//! Built-in scenarios fly the maneuvers they promise (thesis §5.1.4, §5.3.2).
use sim_harness::sim::{self, SimOutput};

fn fly(name: &str) -> SimOutput {
    let sc = sim::load_scenario(name).unwrap();
    sim::run(&sc, 1).unwrap_or_else(|e| panic!("{name}: {e:#}"))
}

/// Prints a one-line summary per scenario (max bank, sideslip, speeds).
fn summary(name: &str, o: &SimOutput) {
    let d = f64::to_degrees;
    let roll: Vec<f64> = o.log.rows.iter().map(|r| r.truth.unwrap()[0]).collect();
    let pitch: Vec<f64> = o.log.rows.iter().map(|r| r.truth.unwrap()[1]).collect();
    let mx = |v: &[f64]| v.iter().cloned().fold(f64::MIN, f64::max);
    let mn = |v: &[f64]| v.iter().cloned().fold(f64::MAX, f64::min);
    let beta: Vec<f64> = o.truth.iter().map(|x| x.beta.abs()).collect();
    let va: Vec<f64> = o.truth.iter().map(|x| x.airspeed).collect();
    let gs: Vec<f64> = o.truth.iter().map(|x| x.velocity_ned[0].hypot(x.velocity_ned[1])).collect();
    let alt: Vec<f64> = o.truth.iter().map(|x| -x.position_ned[2]).collect();
    println!(
        "{name:15} roll [{:6.1}, {:6.1}]°  pitch [{:5.1}, {:5.1}]°  |β|max {:4.1}°  Va [{:4.1}, {:4.1}]  Vg [{:4.1}, {:4.1}] m/s  alt [{:5.1}, {:5.1}] m",
        d(mn(&roll)), d(mx(&roll)), d(mn(&pitch)), d(mx(&pitch)), d(mx(&beta)), mn(&va), mx(&va), mn(&gs), mx(&gs), mn(&alt), mx(&alt)
    );
}

#[test]
fn print_scenario_summaries() {
    for name in sim::builtin_names() {
        let o = fly(name);
        summary(name, &o);
    }
}

#[test]
#[ignore]
fn debug_trace() {
    let name = std::env::var("SIM_DEBUG").unwrap_or("flight1".into());
    let dur: f64 = std::env::var("SIM_DUR").map(|s| s.parse().unwrap()).unwrap_or(100.0);
    let o = sim::run(&sim::load_scenario(&name).unwrap().with_duration(dur), 1).unwrap();
    for (r, x) in o.log.rows.iter().zip(&o.truth).step_by(std::env::var("SIM_STEP").map(|s| s.parse().unwrap()).unwrap_or(50)) {
        let e = r.truth.unwrap();
        println!("t {:5.1} rpy {:6.1} {:6.1} {:6.1}  β {:5.1} α {:5.1} Va {:5.1} h {:6.1} pqr {:6.1} {:6.1} {:6.1} u e{:5.1} a{:5.1} r{:5.1} t{:4.2}",
          r.t, e[0].to_degrees(), e[1].to_degrees(), e[2].to_degrees(), x.beta.to_degrees(), x.alpha.to_degrees(), x.airspeed, -x.position_ned[2],
          x.body_rates[0].to_degrees(), x.body_rates[1].to_degrees(), x.body_rates[2].to_degrees(),
          x.controls[0].to_degrees(), x.controls[1].to_degrees(), x.controls[2].to_degrees(), x.controls[3]);
    }
}
