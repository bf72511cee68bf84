//! The steady turn's unobservable direction on a flight log with truth: every `EVERY_S`
//! seconds, the attitude error's component `c` along the rotation about the specific force
//! (NED, the direction no GPS acceleration sees), its σ as reported (marginal) and given
//! the other states (conditional, `1/√(uᵀP⁻¹u)`), and the gyro-bias error beside the bias
//! that direction carries in a steady turn, `c·(f×ω)/|f|` (docs/open-problems.md, "A
//! direction no steady turn observes"), with the wind estimate against its truth.
//! `cargo run --release -p sim-harness --example oc_trace -- LOG [EVERY_S]`
//! (a robustness-suite world's log: `sim-harness robust --log-dir DIR`).
use sim_harness::montecarlo::rotation_error_ned;
use wing_ahrs::Ahrs;

/// `uᵀ P⁻¹ u` by Cholesky (P symmetric positive definite), `None` otherwise.
fn information_along(p: &[[f64; 6]; 6], u: &[f64; 6]) -> Option<f64> {
    let mut l = [[0.0; 6]; 6];
    for i in 0..6 {
        for j in 0..=i {
            let s = p[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // ‖L⁻¹u‖².
    let mut z = [0.0; 6];
    for i in 0..6 {
        z[i] = (u[i] - (0..i).map(|k| l[i][k] * z[k]).sum::<f64>()) / l[i][i];
    }
    Some(z.iter().map(|v| v * v).sum())
}

fn dcm_of(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let (log, every) = sim_harness::replay::trace_args("oc_trace");
    let t0 = log.rows[0].t;
    let mut next = 0.0;
    let deg = f64::to_degrees;
    sim_harness::replay::run(&log, wing_ahrs::Config::default(), |row, ahrs: &Ahrs| {
        let (Some(tr), Some(p32)) = (row.truth, ahrs.error_covariance()) else { return };
        if row.t - t0 < next {
            return;
        }
        next += every;
        let x = ahrs.state();
        // The filter's convention, R = exp([δθ×])·R̂: the true rotation is δθ off the estimate.
        let e = rotation_error_ned([x[0], x[1], x[2]].map(f64::from), tr).map(|v| -v);
        let p: [[f64; 6]; 6] = core::array::from_fn(|i| core::array::from_fn(|j| p32[i][j] as f64));
        let b = row.truth_bias.unwrap_or([0.0; 3]);
        let be: [f64; 3] = core::array::from_fn(|i| x[3 + i] as f64 - b[i]);
        let r = dcm_of(ahrs.quaternion().map(f64::from));
        let f = row.accel;
        let f_n: [f64; 3] = core::array::from_fn(|i| (0..3).map(|k| r[i][k] * f[k]).sum());
        let norm = f_n.iter().map(|v| v * v).sum::<f64>().sqrt();
        let w: [f64; 3] = core::array::from_fn(|i| row.gyro[i] - x[3 + i] as f64);
        let fxw = [f[1] * w[2] - f[2] * w[1], f[2] * w[0] - f[0] * w[2], f[0] * w[1] - f[1] * w[0]];
        let u: [f64; 6] = core::array::from_fn(|i| if i < 3 { f_n[i] } else { fxw[i - 3] } / norm);
        let c: f64 = (0..3).map(|i| e[i] * u[i]).sum();
        let marg: f64 = (0..6).map(|i| (0..6).map(|j| u[i] * p[i][j] * u[j]).sum::<f64>()).sum();
        let cond = information_along(&p, &u).map_or(f64::NAN, |v| 1.0 / v.sqrt());
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
            deg(-c * u[3]), deg(-c * u[4]), deg(-c * u[5]),
            deg(w.iter().map(|v| v * v).sum::<f64>().sqrt()),
        );
    });
}
