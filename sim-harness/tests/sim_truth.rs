//! The simulator's truth is self-consistent (independently of the dynamics code):
//! integrating the true body rates reproduces the true attitude, and the true
//! specific force equals R_BN·(dv_N/dt − g) from the true NED velocity. Also:
//! reproducibility from the seed, the coordinated-turn law, trimmed level flight.
use sim_harness::sim::{self, dynamics::G, rotation as rot, SimOutput};

fn fly(name: &str, seed: u64) -> SimOutput {
    sim::run(&sim::load_scenario(name).unwrap(), seed).unwrap()
}

/// Truth sampled at the 1 kHz integration rate (IMU rate raised to it), so the
/// finite-difference checks below measure the simulator, not the 100 Hz sampling.
fn fly_1khz(name: &str, seed: u64) -> SimOutput {
    let mut sc = sim::load_scenario(name).unwrap();
    sc.sensors.imu.rate_hz = 1000.0;
    sc.integration_hz = 1000.0;
    sim::run(&sc, seed).unwrap()
}

/// Integrates the logged true rates (2nd-order rotation vector with coning term)
/// from the initial true attitude; returns (RMS, max) attitude error, rad.
fn rate_integration_residual(o: &SimOutput) -> (f64, f64) {
    let rows = &o.log.rows;
    let e0 = rows[0].truth.unwrap();
    let mut q = rot::quat_from_euler(e0[0], e0[1], e0[2]);
    let (mut ss, mut mx) = (0.0, 0.0f64);
    for k in 0..rows.len() - 1 {
        let dt = rows[k + 1].t - rows[k].t;
        let (w0, w1) = (o.truth[k].body_rates, o.truth[k + 1].body_rates);
        let th = rot::add(
            rot::scale(rot::add(w0, w1), 0.5 * dt),
            rot::scale(rot::cross(w0, w1), dt * dt / 12.0),
        );
        q = rot::normalize_quat(rot::quat_mul(q, rot::quat_from_rotvec(th)));
        let e = rows[k + 1].truth.unwrap();
        let err = rot::quat_angle_between(q, rot::quat_from_euler(e[0], e[1], e[2]));
        ss += err * err;
        mx = mx.max(err);
    }
    ((ss / (rows.len() - 1) as f64).sqrt(), mx)
}

/// Central difference of the true NED velocity, rotated into body axes, minus
/// gravity, against the true specific force; returns (RMS per axis, max), m/s².
fn specific_force_residual(o: &SimOutput) -> ([f64; 3], f64) {
    let rows = &o.log.rows;
    let mut ss = [0.0; 3];
    let mut mx = 0.0f64;
    let n = rows.len() - 2;
    for k in 1..=n {
        let dt = rows[k + 1].t - rows[k - 1].t;
        let a_n = rot::scale(
            rot::sub(o.truth[k + 1].velocity_ned, o.truth[k - 1].velocity_ned),
            1.0 / dt,
        );
        let e = rows[k].truth.unwrap();
        let f = rot::mul_mv(&rot::r_bn(e[0], e[1], e[2]), rot::sub(a_n, [0.0, 0.0, G]));
        let r = rot::sub(f, o.truth[k].specific_force);
        for i in 0..3 {
            ss[i] += r[i] * r[i];
            mx = mx.max(r[i].abs());
        }
    }
    (ss.map(|s| (s / n as f64).sqrt()), mx)
}

#[test]
fn integrating_true_rates_reproduces_true_attitude() {
    for name in ["flight1", "flight2", "aggressive"] {
        let o = fly_1khz(name, 3);
        let (rms, max) = rate_integration_residual(&o);
        println!(
            "{name:10} attitude from integrated true rates: RMS {:.2e}°  max {:.2e}° over {} s",
            rms.to_degrees(),
            max.to_degrees(),
            o.log.rows.last().unwrap().t
        );
        assert!(
            rms.to_degrees() < 1e-4 && max.to_degrees() < 1e-3,
            "{name}: rate integration drifts from truth"
        );
    }
}

#[test]
fn true_specific_force_matches_differentiated_velocity() {
    for name in ["flight1", "flight2", "aggressive"] {
        let o = fly_1khz(name, 3);
        let (rms, max) = specific_force_residual(&o);
        println!("{name:10} specific force vs R_BN(dv/dt − g): RMS [{:.1e}, {:.1e}, {:.1e}] m/s²  max {:.1e}", rms[0], rms[1], rms[2], max);
        assert!(rms.iter().all(|r| *r < 1e-3), "{name}: specific force inconsistent with velocity");
        // Max: kinks where a servo starts slewing after a step command (rate jump × dt).
        assert!(max < 0.1, "{name}: specific force outlier {max}");
    }
}

#[test]
fn a_run_is_reproducible_from_its_seed() {
    let sc = sim::load_scenario("flight1").unwrap().with_duration(20.0);
    let a = sim::run(&sc, 11).unwrap();
    let b = sim::run(&sc, 11).unwrap();
    let c = sim::run(&sc, 12).unwrap();
    assert_eq!(a.log, b.log, "same seed, same log");
    assert_eq!(a.truth, b.truth);
    assert_ne!(a.log.rows[5].gyro, c.log.rows[5].gyro, "another seed, other noise");
    // The streaming form yields the same rows.
    let mut streamed = vec![];
    sim::run_streaming(&sc, 11, |r, _| streamed.push(*r)).unwrap();
    assert_eq!(streamed, a.log.rows);
    // The flown trajectory does not depend on sensor noise.
    assert_eq!(a.log.rows[1500].truth, c.log.rows[1500].truth);
}

#[test]
fn coordinated_turn_rate_is_g_tan_phi_over_v() {
    // flight2: sustained −30° coordinated turn, t ∈ [12, 28] s, level, no wind.
    let o = fly("flight2", 5);
    let rows = &o.log.rows;
    let (mut sum_meas, mut sum_model, mut n) = (0.0, 0.0, 0);
    for k in 1200..2800 {
        let (v0, v1) = (o.truth[k - 1].velocity_ned, o.truth[k + 1].velocity_ned);
        let dchi =
            rot::wrap_pi(v1[1].atan2(v1[0]) - v0[1].atan2(v0[0])) / (rows[k + 1].t - rows[k - 1].t);
        let v = o.truth[k].velocity_ned;
        let phi = rows[k].truth.unwrap()[0];
        sum_meas += dchi;
        sum_model += G * phi.tan() / v[0].hypot(v[1]);
        n += 1;
        assert!(
            (phi.to_degrees() + 30.0).abs() < 1.5,
            "t = {}: bank {}° is not the commanded −30°",
            rows[k].t,
            phi.to_degrees()
        );
    }
    let (m, p) = (sum_meas / n as f64, sum_model / n as f64);
    println!(
        "coordinated turn: mean course rate {:.3}°/s, g·tanφ/V {:.3}°/s ({:+.2} %)",
        m.to_degrees(),
        p.to_degrees(),
        100.0 * (m / p - 1.0)
    );
    // 3 %: the rudder loop holds β = 0 (Beard & McLain), which leaves a small rudder
    // side force (C_Yδr·δr ≈ −0.13 m/s² here, +2 % turn rate) and cos θ ≈ 0.996.
    assert!((m / p - 1.0).abs() < 0.03, "turn rate departs from g·tanφ/V");
}

#[test]
fn trimmed_level_flight_holds_altitude_airspeed_and_attitude() {
    let o = fly("level", 1);
    let mut worst = [0.0f64; 4];
    for (r, x) in o.log.rows.iter().zip(&o.truth) {
        let e = r.truth.unwrap();
        worst[0] = worst[0].max((-x.position_ned[2] - 100.0).abs());
        worst[1] = worst[1].max((x.airspeed - 25.0).abs());
        worst[2] = worst[2].max(e[0].abs().to_degrees());
        worst[3] = worst[3].max(rot::wrap_pi(e[2] - 45f64.to_radians()).abs().to_degrees());
    }
    println!(
        "level: max |Δh| {:.2e} m, |ΔVa| {:.2e} m/s, |φ| {:.2e}°, |Δψ| {:.2e}°",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst[0] < 0.05 && worst[1] < 0.01 && worst[2] < 0.01 && worst[3] < 0.01);
}

/// Steady wind, shear, gusts and moderate turbulence at once.
const WINDY: &str = "flight1+wind=6@45,turb=moderate,shear=0.05,gust=3,dur=60";

fn fly_windy_1khz(seed: u64) -> SimOutput {
    let mut sc = sim::load_scenario(WINDY).unwrap();
    sc.sensors.imu.rate_hz = 1000.0;
    sc.sensors.airspeed.rate_hz = 1000.0;
    sc.integration_hz = 1000.0;
    sim::run(&sc, seed).unwrap()
}

#[test]
fn in_wind_ground_velocity_is_air_velocity_plus_wind() {
    let o = fly_windy_1khz(4);
    let (mut worst, mut wind_max) = (0.0f64, 0.0f64);
    for (r, x) in o.log.rows.iter().zip(&o.truth) {
        let e = r.truth.unwrap();
        // Air-relative velocity from Va, α, β (Beard & McLain eq 2.7), rotated to NED.
        let (sa, ca) = x.alpha.sin_cos();
        let (sb, cb) = x.beta.sin_cos();
        let v_air_b = rot::scale([ca * cb, sb, sa * cb], x.airspeed);
        let v_air_n = rot::mul_mtv(&rot::r_bn(e[0], e[1], e[2]), v_air_b);
        let w = r.truth_wind.unwrap();
        worst = worst.max(rot::norm(rot::sub(x.velocity_ned, rot::add(v_air_n, w))));
        wind_max = wind_max.max(rot::norm(w));
    }
    println!("{WINDY}: max |v_ground − (R·v_air + wind)| {worst:.2e} m/s, |wind| up to {wind_max:.1} m/s");
    assert!(worst < 1e-9);
    assert!(wind_max > 8.0, "the wind is strong enough to matter");
}

#[test]
fn in_wind_the_airspeed_sensor_reads_air_relative_speed() {
    let o = fly_windy_1khz(5);
    let sc = sim::load_scenario(WINDY).unwrap();
    let (mut d_air, mut d_ground) = (vec![], vec![]);
    for (r, x) in o.log.rows.iter().zip(&o.truth) {
        let Some(m) = r.airspeed else { continue };
        let va = rot::norm(rot::sub(x.velocity_ned, r.truth_wind.unwrap()));
        d_air.push(m - va);
        d_ground.push(m - rot::norm(x.velocity_ned));
    }
    let stats = |v: &[f64]| {
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        (mean, (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt())
    };
    let ((ma, sa), (mg, sg)) = (stats(&d_air), stats(&d_ground));
    let sigma = sc.sensors.airspeed.noise_m_s;
    println!("airspeed − |v_g − w|: mean {ma:+.4} std {sa:.4} m/s (σ {sigma}); airspeed − |v_g|: mean {mg:+.2} std {sg:.2}");
    assert!(
        ma.abs() < 0.01 && (sa / sigma - 1.0).abs() < 0.05,
        "noise about the air-relative speed"
    );
    assert!(sg > 2.0, "not the ground speed");
}

/// Per step k → k+1: the forward difference of the true NED ground velocity against
/// the trapezoid of `R_NB·f + g` with `f` from `force(k)` (in turbulence the force is
/// rough at step boundaries — the Dryden gust is a filtered white noise — so a central
/// difference against the point value would measure the gust, not the simulator).
/// Returns the residuals, m/s², three per step.
fn trapezoid_residuals(o: &SimOutput, force: impl Fn(usize) -> [f64; 3]) -> Vec<f64> {
    let rows = &o.log.rows;
    let a_n = |k: usize| {
        let e = rows[k].truth.unwrap();
        rot::add(rot::mul_mtv(&rot::r_bn(e[0], e[1], e[2]), force(k)), [0.0, 0.0, G])
    };
    let mut res = Vec::with_capacity(3 * rows.len());
    for k in 0..rows.len() - 1 {
        let dt = rows[k + 1].t - rows[k].t;
        let dv =
            rot::scale(rot::sub(o.truth[k + 1].velocity_ned, o.truth[k].velocity_ned), 1.0 / dt);
        res.extend(rot::sub(dv, rot::scale(rot::add(a_n(k), a_n(k + 1)), 0.5)));
    }
    res
}

fn mean_sd_max(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    (mean, sd, v.iter().fold(0.0f64, |m, x| m.max(x.abs())))
}

#[test]
fn in_wind_specific_force_and_accelerometer_match_differentiated_ground_velocity() {
    let o = fly_windy_1khz(6);
    let (mean, sd, max) = mean_sd_max(&trapezoid_residuals(&o, |k| o.truth[k].specific_force));
    println!("{WINDY}: dv_ground/dt vs trapezoid of R_NB·f_true + g: mean {mean:+.1e} std {sd:.1e} max {max:.1e} m/s²");
    assert!(sd < 1e-3 && max < 0.05, "true specific force inconsistent with the ground velocity");
    // The accelerometer model (thesis: unbiased, 0.02 m/s² white noise): the trapezoid of
    // two samples carries 0.02/√2 of noise.
    let (mean, sd, _) = mean_sd_max(&trapezoid_residuals(&o, |k| o.log.rows[k].accel));
    println!("accelerometer: mean {mean:+.1e}, std {sd:.4} m/s² (model 0.02/√2 = 0.0141)");
    assert!(mean.abs() < 1e-3 && (sd / (0.02 / 2f64.sqrt()) - 1.0).abs() < 0.1);
}

/// The kinematic aerobatic sequence at 1 kHz (loops through ±90° pitch, inverted
/// flight, knife-edge, rolls), optionally in wind with turbulence.
fn fly_aerobatics_1khz(name: &str, seed: u64) -> SimOutput {
    let mut sc = sim::load_scenario(name).unwrap();
    sc.sensors.imu.rate_hz = 1000.0;
    sc.integration_hz = 1000.0;
    sim::run(&sc, seed).unwrap()
}

#[test]
fn kinematic_gyro_truth_is_the_rotation_of_the_truth_attitude() {
    let o = fly_aerobatics_1khz("aerobatics", 7);
    let rows = &o.log.rows;
    let q = |k: usize| {
        let e = rows[k].truth.unwrap();
        rot::quat_from_euler(e[0], e[1], e[2])
    };
    // Body-frame rotation from k to k+1 (from the logged Euler truth) against the mean of
    // the true rates at both ends; binned by attitude to show every regime is covered.
    let (mut worst, mut n_vert, mut n_inv) = (0.0f64, 0, 0);
    for k in 0..rows.len() - 1 {
        let dt = rows[k + 1].t - rows[k].t;
        let a = q(k);
        let d = rot::quat_mul([a[0], -a[1], -a[2], -a[3]], q(k + 1));
        let d = if d[0] < 0.0 { d.map(|x| -x) } else { d };
        let ang = 2.0 * rot::norm([d[1], d[2], d[3]]).atan2(d[0]);
        let s = rot::norm([d[1], d[2], d[3]]);
        let w_fd = if s > 0.0 { [d[1], d[2], d[3]].map(|x| x / s * ang / dt) } else { [0.0; 3] };
        let w = rot::scale(rot::add(o.truth[k].body_rates, o.truth[k + 1].body_rates), 0.5);
        worst = worst.max(rot::norm(rot::sub(w_fd, w)));
        let e = rows[k].truth.unwrap();
        n_vert += (e[1].abs() > 80f64.to_radians()) as usize;
        n_inv += (e[0].abs() > 170f64.to_radians() && e[1].abs() < 10f64.to_radians()) as usize;
    }
    let wmax = o.truth.iter().map(|x| rot::norm(x.body_rates)).fold(0.0, f64::max);
    println!("aerobatics: max |ω_fd − ω_true| {worst:.2e} rad/s (|ω| up to {wmax:.2}); {n_vert} samples beyond ±80° pitch, {n_inv} inverted");
    assert!(worst < 2e-3, "gyro truth is not the attitude's rotation");
    assert!(n_vert > 500 && n_inv > 5000, "the sequence reaches vertical and sustained inverted");
}

#[test]
fn kinematic_specific_force_matches_differentiated_ground_velocity() {
    for name in ["aerobatics", "aerobatics_wind5"] {
        let o = fly_aerobatics_1khz(name, 8);
        let (mean, sd, max) = mean_sd_max(&trapezoid_residuals(&o, |k| o.truth[k].specific_force));
        let fmax = o.truth.iter().map(|x| rot::norm(x.specific_force)).fold(0.0, f64::max);
        println!("{name}: dv/dt vs trapezoid of R_NB·f + g: mean {mean:+.1e} std {sd:.1e} max {max:.1e} m/s² (|f| up to {fmax:.0})");
        assert!(
            sd < 1e-4 && max < 0.02,
            "{name}: specific force inconsistent with ground velocity"
        );
        // Ground velocity = air-relative velocity + wind, with the airspeed truth.
        let worst = o
            .truth
            .iter()
            .map(|x| (rot::norm(rot::sub(x.velocity_ned, x.wind_ned)) - x.airspeed).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{name}: airspeed is |v_ground − wind|");
    }
}
