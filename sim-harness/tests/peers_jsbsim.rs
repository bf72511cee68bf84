//! The JSBSim export applies our sensor models to an outside simulator's truth: fed a
//! truth file of a known steady banked climb written here (the forward model of docs/design.md, "Conventions":
//! specific force = R_NBᵀ(a − g), a = 0), the log carries that truth, the IMU reads it
//! through the thesis sensors (bias included), GPS fixes arrive at 10 Hz with the truth's
//! position at their epoch, and our filter recovers the attitude.

use sim_harness::sim::sensors::SensorParams;
use std::fmt::Write as _;

#[test]
fn export_applies_our_sensors_to_outside_truth() {
    let dir = std::env::temp_dir().join(format!("wing-jsbsim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (roll, pitch, yaw) = (10f64.to_radians(), 4f64.to_radians(), 1.0f64);
    let r = sim_harness::peers::dcm_gps::r_nb(roll, pitch, yaw);
    let g = 9.80665;
    // Specific force in body axes: −R_NBᵀ g_N with g_N = (0, 0, g).
    let f: Vec<f64> = (0..3).map(|j| -r[2][j] * g).collect();
    let v = [20.0 * yaw.cos(), 20.0 * yaw.sin(), -1.0];
    let mut s = String::from(
        "t,roll,pitch,yaw,p,q,r,fx,fy,fz,vn,ve,vd,lat,lon,alt,va,wind_n,wind_e,wind_d\n",
    );
    for k in 0..6001 {
        let t = k as f64 * 0.01;
        let lla = [47.0 + v[0] * t / 6.37e6 * 57.29578, 8.0, 500.0 - v[2] * t];
        let _ = writeln!(
            s,
            "{t},{roll},{pitch},{yaw},0,0,0,{},{},{},{},{},{},{},{},{},20,0,0,0",
            f[0], f[1], f[2], v[0], v[1], v[2], lla[0], lla[1], lla[2]
        );
    }
    let truth = dir.join("steady.truth.csv");
    std::fs::write(&truth, s).unwrap();
    let log = sim_harness::jsbsim::export(&truth, &SensorParams::thesis(), 4).unwrap();
    assert_eq!(log.rows.len(), 6001);
    let fixes: Vec<_> = log.rows.iter().filter_map(|r| r.gps).collect();
    assert!((fixes.len() as i64 - 600).abs() <= 1, "{} fixes in 60 s at 10 Hz", fixes.len());
    for g in &fixes {
        let lla = g.lla.expect("fix position");
        assert!((lla[2] - (500.0 + g.t)).abs() < 1e-6, "height at the epoch {}: {}", g.t, lla[2]);
    }
    let r0 = &log.rows[3000];
    assert_eq!(r0.truth, Some([roll, pitch, yaw]));
    // The gyro reads the turn-on bias the log reports (rates are zero), within its noise.
    let b = r0.truth_bias.unwrap();
    for i in 0..3 {
        assert!((r0.gyro[i] - b[i]).abs() < 5e-3, "gyro {i}: {} vs bias {}", r0.gyro[i], b[i]);
    }
    let ahrs = sim_harness::replay::run(&log, wing_ahrs::Config::default(), |_, _| {});
    let e = ahrs.attitude();
    let err = [e.roll as f64 - roll, e.pitch as f64 - pitch];
    assert!(err.iter().all(|x| x.to_degrees().abs() < 0.5), "attitude error {err:?} rad");
    let _ = std::fs::remove_dir_all(&dir);
}

/// JSBSim's row k holds the rates that carry the state from t_k to t_k+1 (checked on its
/// output: the attitude differences match them forward, to 3e-4 rad/s in an axial roll). An
/// IMU sample at t_k reads the interval before t_k, so the export gives row k row k−1's rate:
/// a one-row lead would put every estimator 2° ahead of truth in a 200°/s roll.
#[test]
fn the_gyro_at_a_row_reads_the_step_into_it() {
    let dir = std::env::temp_dir().join(format!("wing-jsbsim-step-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut s = String::from(
        "t,roll,pitch,yaw,p,q,r,fx,fy,fz,vn,ve,vd,lat,lon,alt,va,wind_n,wind_e,wind_d\n",
    );
    let (dt, mut roll) = (0.01, 0.0f64);
    for k in 0..200 {
        let p = 0.02 * k as f64; // roll acceleration 2 rad/s², so rows differ by 0.02 rad/s
        let _ = writeln!(
            s,
            "{},{roll},0,0,{p},0,0,0,0,-9.80665,20,0,0,47,8,500,20,0,0,0",
            k as f64 * dt
        );
        roll += p * dt; // forward, as JSBSim's rows are
    }
    let truth = dir.join("roll.truth.csv");
    std::fs::write(&truth, s).unwrap();
    let log = sim_harness::jsbsim::export(&truth, &SensorParams::thesis(), 4).unwrap();
    for k in [50, 100, 150] {
        let r = &log.rows[k];
        let read = r.gyro[0] - r.truth_bias.unwrap()[0];
        let before = 0.02 * (k - 1) as f64;
        assert!((read - before).abs() < 5e-3, "row {k}: gyro {read} vs the step into it {before}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
