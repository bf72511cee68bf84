//! In-air switch-on in a 25–35° bank (the robustness suite's `air-bank30` start, thesis
//! sensors, 10 Hz honest receiver): every 0.5 s the tilt and yaw error against the
//! simulator's truth, the reported 1-σ, the update status and the flags.
//! `cargo run --release -p sim-harness --example in_air_bank_trace -- [BASE [WIND [HZ [LATENCY_S [SEED [realistic]]]]]]`,
//! e.g. `sim:flight1 wind=12@315 4 0.15` (defaults `sim:coordinated_turn`, still air, 10 Hz, 0 s, seed 1, thesis sensors).
use sim_harness::robust::{self, Start, World};
use sim_harness::sim::SensorSpec;
fn main() {
    sim_harness::quiet_on_closed_pipe();
    let arg = |i: usize| std::env::args().nth(i);
    let num = |i: usize, default: f64| match arg(i) {
        None => default,
        Some(s) => s.parse().unwrap_or_else(|_| {
            eprintln!("argument {i} is not a number: {s}");
            std::process::exit(2)
        }),
    };
    let w = World {
        base: arg(1).unwrap_or_else(|| "sim:coordinated_turn".into()),
        spec: if arg(6).as_deref() == Some("realistic") {
            SensorSpec::Realistic
        } else {
            SensorSpec::Thesis
        },
        rate_hz: num(3, 10.0),
        latency_s: num(4, 0.0),
        start: Start::AirBank,
        wind: arg(2).unwrap_or_default(),
        seed: num(5, 1.0) as u64,
    };
    let log = robust::flight(&w, "honest".parse().unwrap()).unwrap();
    let t0 = log.rows[0].t;
    let mut next = 0.0;
    let mut flow = [f64::NAN; 2];
    sim_harness::replay::run(&log, wing_ahrs::Config::default(), |row, ahrs| {
        let (Some(tr), a) = (row.truth, ahrs.attitude()) else { return };
        if let Some(g) = row.gps {
            flow = alpha_beta(tr, g.vel, row.truth_wind.unwrap_or_default());
        }
        if row.t - t0 < next {
            return;
        }
        next += 0.25;
        let e = sim_harness::metrics::tilt_error([a.roll, a.pitch, a.yaw].map(f64::from), tr);
        let wrap = |x: f64| {
            (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
        };
        let sd = ahrs.std_dev();
        let u = ahrs.last_update();
        print!("α {:5.2} β {:5.2} | ", flow[0].to_degrees(), flow[1].to_degrees());
        println!("{:5.1} tilt {:5.2} yaw {:6.2} | sd r {:5.2} p {:5.2} y {:5.2} | truth roll {:5.1} | {:?} {:?} {:?}",
            row.t - t0, e.to_degrees(), wrap(a.yaw as f64 - tr[2]).to_degrees(),
            (sd[0] as f64).to_degrees(), (sd[1] as f64).to_degrees(), (sd[2] as f64).to_degrees(), tr[0].to_degrees(),
            u.axes[0].status, u.axes[2].status, ahrs.flags());
    });
}

/// The true angle of attack and sideslip, rad, from the true attitude (roll, pitch, yaw),
/// the fix's ground velocity and the true wind (NED, m/s).
fn alpha_beta(att: [f64; 3], v: [f64; 3], wind: [f64; 3]) -> [f64; 2] {
    let r = sim_harness::sim::rotation::r_bn(att[0], att[1], att[2]);
    let va: [f64; 3] = std::array::from_fn(|i| v[i] - wind[i]);
    let b: [f64; 3] = std::array::from_fn(|j| (0..3).map(|i| r[j][i] * va[i]).sum());
    let n = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
    [b[2].atan2(b[0]), (b[1] / n).asin()]
}
