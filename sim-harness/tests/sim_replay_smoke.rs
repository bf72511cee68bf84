//! Convention check between the simulator and the core: a simulated flight
//! replayed through the core facade converges to the simulator's truth
//! (FRD specific force sign, NED GPS velocity, 3-2-1 Euler all agree).
//! Loose bounds: accuracy belongs to the harness's metrics; this only catches
//! a frame or sign mismatch, which shows as tens of degrees.
use sim_harness::{replay, sim};
use wing_ahrs::Config;

#[test]
fn simulated_flights_replay_to_truth_through_the_core() {
    for name in ["level", "flight1", "flight2", "aggressive"] {
        let o = sim::run(&sim::load_scenario(name).unwrap(), 7).unwrap();
        let mut ss = [0.0f64; 3];
        let mut n = 0usize;
        replay::run(&o.log, Config::euler(), |row, ahrs| {
            if row.t < 10.0 {
                return;
            }
            let a = ahrs.attitude();
            let tr = row.truth.unwrap();
            let e = [a.roll as f64 - tr[0], a.pitch as f64 - tr[1], a.yaw as f64 - tr[2]];
            for i in 0..3 {
                ss[i] += sim::rotation::wrap_pi(e[i]).powi(2);
            }
            n += 1;
        });
        let rms = ss.map(|s| (s / n as f64).sqrt().to_degrees());
        println!("{name:10} core default config, t ≥ 10 s: RMS error roll {:.3}° pitch {:.3}° yaw {:.3}°", rms[0], rms[1], rms[2]);
        assert!(
            rms[0] < 3.0 && rms[1] < 3.0 && rms[2] < 5.0,
            "{name}: replay far from truth — a convention mismatch?"
        );
    }
}
