//! The steady turn's unobservable direction on a flight log with truth: every `EVERY_S`
//! seconds, the attitude error's component `c` along the rotation about the specific force
//! (NED, the direction no GPS acceleration sees), its σ as reported (marginal) and given
//! the other states (conditional, `1/√(uᵀP⁻¹u)`), and the gyro-bias error beside the bias
//! that direction carries in a steady turn, `c·(f×ω)/|f|` (docs/open-problems.md, "A
//! direction no steady turn observes"), with the wind estimate against its truth.
//! `cargo run --release -p sim-harness --example oc_trace -- LOG [EVERY_S] [--told thesis|realistic]`
//! (a robustness-suite world's log: `sim-harness robust --log-dir DIR`; `--told` its
//! sensor grade for the σ the suite scores).
use nalgebra::{Matrix6, Quaternion, UnitQuaternion, Vector3, Vector6};
use sim_harness::montecarlo::rotation_error_ned;
use wing_ahrs::Ahrs;

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let sim_harness::trace_cli::TraceArgs { log, every, config } =
        sim_harness::trace_cli::args("oc_trace");
    let t0 = log.rows[0].t;
    let mut next = 0.0;
    let deg = f64::to_degrees;
    sim_harness::replay::run(&log, config, |row, ahrs: &Ahrs| {
        let (Some(tr), Some(p32)) = (row.truth, ahrs.error_covariance()) else { return };
        if row.t - t0 < next {
            return;
        }
        next += every;
        let x = ahrs.state();
        // The filter's convention, R = exp([δθ×])·R̂: the true rotation is δθ off the estimate.
        let e = Vector3::from(rotation_error_ned([x[0], x[1], x[2]].map(f64::from), tr)) * -1.0;
        let p = Matrix6::from_fn(|i, j| p32[i][j] as f64);
        let bias = Vector3::new(x[3] as f64, x[4] as f64, x[5] as f64);
        let be = bias - Vector3::from(row.truth_bias.unwrap_or([0.0; 3]));
        let [qw, qx, qy, qz] = ahrs.quaternion().map(f64::from);
        let r = UnitQuaternion::from_quaternion(Quaternion::new(qw, qx, qy, qz));
        let f = Vector3::from(row.accel);
        let f_n = r * f;
        let w = Vector3::from(row.gyro) - bias;
        let u_b = f.cross(&w) / f_n.norm();
        let u_t = f_n / f_n.norm();
        let u = Vector6::new(u_t[0], u_t[1], u_t[2], u_b[0], u_b[1], u_b[2]);
        let c = e.dot(&u_t);
        let marg = (u.transpose() * p * u)[0];
        // `uᵀP⁻¹u`: the information along u; its inverse root is c's σ given the rest.
        let cond = p.cholesky().map_or(f64::NAN, |ch| 1.0 / u.dot(&ch.solve(&u)).sqrt());
        let wind = match (ahrs.wind(), row.truth_wind) {
            (Some((we, s)), Some(wt)) => {
                format!(
                    "{:5.1} {:5.1} σ {:4.1} (true {:5.1} {:5.1}) m/s",
                    we[0], we[1], s[0], wt[0], wt[1]
                )
            }
            (Some((we, s)), None) => format!("{:5.1} {:5.1} σ {:4.1} m/s", we[0], we[1], s[0]),
            _ => "none".into(),
        };
        println!(
            "{:6.1} s | tilt {:5.2}° yaw {:6.2}° | c {:6.2}° σ {:5.2}° (given the rest {:5.2}°) | bias err {:6.3} {:6.3} {:6.3} vs c·u_b {:6.3} {:6.3} {:6.3} °/s | |ω| {:5.1}°/s | wind {wind}",
            row.t - t0,
            deg(e[0].hypot(e[1])),
            deg(e[2]),
            deg(c),
            deg(marg.sqrt()),
            deg(cond),
            deg(be[0]), deg(be[1]), deg(be[2]),
            deg(-c * u_b[0]), deg(-c * u_b[1]), deg(-c * u_b[2]),
            deg(w.norm()),
        );
    });
}
