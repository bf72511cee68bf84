//! In-air switch-on in a 25–35° bank (the robustness suite's `air-bank30` start, thesis
//! sensors, 10 Hz honest receiver): every 0.5 s the tilt and yaw error against the
//! simulator's truth, the reported 1-σ, the update status and the flags.
//! `cargo run --release -p sim-harness --example in_air_bank_trace -- [sim:coordinated_turn]`
use sim_harness::robust::{self, Start, World};
use sim_harness::sim::SensorSpec;
fn main() {
    sim_harness::quiet_on_closed_pipe();
    let base = std::env::args().nth(1).unwrap_or_else(|| "sim:coordinated_turn".into());
    let w = World {
        base,
        spec: SensorSpec::Thesis,
        rate_hz: 10.0,
        latency_s: 0.0,
        start: Start::AirBank,
        wind: String::new(),
        seed: 1,
    };
    let log = robust::flight(&w, "honest".parse().unwrap()).unwrap();
    let t0 = log.rows[0].t;
    let mut next = 0.0;
    sim_harness::replay::run(&log, wing_ahrs::Config::default(), |row, ahrs| {
        let (Some(tr), a) = (row.truth, ahrs.attitude()) else { return };
        if row.t - t0 < next {
            return;
        }
        next += 0.5;
        let e = sim_harness::metrics::tilt_error([a.roll, a.pitch, a.yaw].map(f64::from), tr);
        let wrap = |x: f64| {
            (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
        };
        let sd = ahrs.std_dev();
        let u = ahrs.last_update();
        println!("{:5.1} tilt {:5.2} yaw {:6.2} | sd r {:5.2} p {:5.2} y {:5.2} | truth roll {:5.1} | {:?} {:?} {:?}",
            row.t - t0, e.to_degrees(), wrap(a.yaw as f64 - tr[2]).to_degrees(),
            (sd[0] as f64).to_degrees(), (sd[1] as f64).to_degrees(), (sd[2] as f64).to_degrees(), tr[0].to_degrees(),
            u.axes[0].status, u.axes[2].status, ahrs.flags());
    });
}
