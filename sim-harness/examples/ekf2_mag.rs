//! PX4 EKF2 on an ArduPilot DataFlash log with and without the log's own magnetometer, and
//! other suspects one at a time (on `flightdata_c6_on_0001` none was the cause: that was the
//! prediction period, `ekf2_real`; CHANGELOG.md). A diagnostic, not a table entry:
//! `compare` gives every estimator the same inputs, and ours takes no magnetometer.
//!
//! `cargo run --release -p sim-harness --features ekf2-magnetometer --example ekf2_mag -- LOG.BIN`
//!
//! The magnetometer is the log's `MAG` message, instance 0 (`MAG` with `I` = 0, or the
//! unnumbered `MAG` of older logs beside `MAG2`): `MagX/Y/Z`, milligauss, body FRD
//! (ArduPilot's log documentation; the field after its offsets and scaling), handed to EKF2
//! in gauss at its own time stamp on the IMU's clock. EKF2 is otherwise as `compare` runs it
//! on a real log (as shipped, epochs at the measured latency), its magnetometer parameters
//! PX4's (`EKF2_MAG_TYPE` automatic: 3-axis fusion in flight, declination from its world
//! magnetic model at the first fix). Printed over `compare`'s statistics window: tilt, roll,
//! pitch and yaw agreement with the autopilot's attitude, how often the yaw jumped by more
//! than 11° between samples (its yaw estimator's resets, and Euler yaw through the vertical:
//! ours is counted too), and the share of the window EKF2 fused the magnetometer in 3-D, as
//! a heading, or flagged it faulty. Ours for scale. Also: the field through the
//! autopilot's attitude (a usable magnetometer gives one declination and inclination), the
//! yaw reset to the autopilot's each second when near level, and other suspects one at a
//! time; `--segments` prints ours and EKF2's disagreement per 30 s.
use anyhow::{bail, Context, Result};
use ardupilot_binlog::Reader;
use ekf2::params::MagFusionType;
use ekf2::types::MagSample;
use sim_harness::compare::nominal_dt;
use sim_harness::log::FlightLog;
use sim_harness::metrics::{tilt_error, wrap};
use sim_harness::peers::gnss_feed::micros;
use sim_harness::peers::px4_ekf2::Px4Ekf2;
use sim_harness::peers::setup::{SensorFigures, Setup, Tuning};
use sim_harness::peers::wing::Wing;
use sim_harness::peers::Estimator;

/// The log's magnetometer, instance 0: (time on the IMU clock, µs since boot; field, gauss).
fn read_mag(path: &std::path::Path) -> Result<Vec<(u64, [f32; 3])>> {
    let file = std::fs::File::open(path).with_context(|| format!("{}", path.display()))?;
    let mut out = Vec::new();
    for e in Reader::new(std::io::BufReader::new(file)).flatten() {
        let inst = match e.name.as_str() {
            "MAG" => e.get_i64("I").unwrap_or(0),
            _ => continue,
        };
        let (Some(t), 0) = (e.timestamp_usec, inst) else { continue };
        if let (Some(x), Some(y), Some(z)) =
            (e.get_f64("MagX"), e.get_f64("MagY"), e.get_f64("MagZ"))
        {
            out.push((t, [x, y, z].map(|m| (m * 1e-3) as f32)));
        }
    }
    Ok(out)
}

/// A change to EKF2's parameters before its first sample.
type Tweak = fn(&mut ekf2::Ekf<'static>);

struct Score {
    ss: [f64; 4],
    n: usize,
    jumps: usize,
    /// EKF2's samples in the window fusing the magnetometer in 3-D, as heading, and with its
    /// magnetometer-fault flag.
    flags: [usize; 3],
}

/// Runs `est` over `log` (the magnetometer `mag`, log time s and gauss, handed to EKF2 before
/// each row it precedes), scoring between `from` and `to`.
fn score(
    log: &FlightLog,
    est: &mut dyn Estimator,
    mut ekf2: Option<&mut Px4Ekf2>,
    mag: &[(f64, [f32; 3])],
    heading: bool,
    from: f64,
    to: f64,
) -> Score {
    let mut s = Score { ss: [0.0; 4], n: 0, jumps: 0, flags: [0; 3] };
    let (mut k, mut prev) = (0usize, None::<f64>);
    let mut next_reset = log.rows[0].t + 1.0;
    let mut history: std::collections::VecDeque<(f64, f64)> = Default::default();
    for row in &log.rows {
        if let Some(r) = row.reference {
            // Only near-level attitudes: Euler yaw is no heading near the vertical, and EKF2
            // resets yaw in its 321 or 312 sequence by attitude.
            let level = r[0].abs() < 30f64.to_radians() && r[1].abs() < 20f64.to_radians();
            history.push_back((row.t, if level { r[2] } else { f64::NAN }));
        }
        let a = if let Some(e) = ekf2.as_deref_mut() {
            while k < mag.len() && mag[k].0 <= row.t {
                let m =
                    MagSample { time_us: micros(mag[k].0), mag: mag[k].1, reset: 0, _pad: [0; 3] };
                e.ekf_mut().set_mag_data(&m);
                k += 1;
            }
            e.step(row);
            if heading && row.t >= next_reset {
                // EKF2's states lie at its delayed fusion horizon, EKF2_DELAY_MAX behind.
                let delay = f64::from(e.ekf().params().delay_max_ms()) * 1e-3;
                while history.len() > 2 && history[1].0 <= row.t - delay {
                    history.pop_front();
                }
                if let Some(&(_, y)) = history.front().filter(|h| h.1.is_finite()) {
                    e.ekf_mut().reset_heading_to_external_observation(y as f32, 0.05);
                }
                next_reset += 1.0;
            }
            if row.t >= from && row.t <= to {
                use ekf2::params::ControlStatus as C;
                let c = e.ekf().control_status();
                s.flags[0] += usize::from(c.contains(C::MAG_3D));
                s.flags[1] += usize::from(c.contains(C::MAG_HDG));
                s.flags[2] += usize::from(c.contains(C::MAG_FAULT));
            }
            e.attitude()
        } else {
            est.step(row);
            est.attitude()
        };
        let Some(want) = row.reference else { continue };
        if row.t < from || row.t > to {
            continue;
        }
        if let Some(p) = prev {
            s.jumps += usize::from(wrap(a[2] - p).abs() > 0.2);
        }
        prev = Some(a[2]);
        let e =
            [tilt_error(a, want), wrap(a[0] - want[0]), wrap(a[1] - want[1]), wrap(a[2] - want[2])];
        for i in 0..4 {
            s.ss[i] += e[i] * e[i];
        }
        s.n += 1;
    }
    s
}

fn print(name: &str, s: &Score) {
    let r = |i: usize| (s.ss[i] / s.n.max(1) as f64).sqrt().to_degrees();
    let pc = |k: usize| 100.0 * s.flags[k] as f64 / s.n.max(1) as f64;
    println!(
        "| {name} | {:.2}° | {:.2}° | {:.2}° | {:.1}° | {} | {:.0} % / {:.0} % / {:.0} % |",
        r(0),
        r(1),
        r(2),
        r(3),
        s.jumps,
        pc(0),
        pc(1),
        pc(2)
    );
}

fn main() -> Result<()> {
    let Some(path) = std::env::args().nth(1) else {
        bail!("usage: ekf2_mag LOG.BIN (an ArduPilot DataFlash log with MAG messages)");
    };
    let path = std::path::PathBuf::from(path);
    let (log, summary) = sim_harness::import::import(&path)?;
    let mag: Vec<(f64, [f32; 3])> = read_mag(&path)?
        .into_iter()
        .filter(|(t, _)| *t >= summary.t0_us)
        .map(|(t, m)| ((t - summary.t0_us) as f64 * 1e-6, m))
        .collect();
    if mag.is_empty() {
        bail!("{}: no MAG messages", path.display());
    }
    let dt = nominal_dt(&log);
    // As `compare` on a real log: no spec, every filter as shipped.
    let setup = Setup::for_log(&log, dt, Tuning::Defaults, SensorFigures::realistic());
    let t0 = log.rows[0].t;
    let (mut from, mut to) = (t0 + 30.0, f64::INFINITY);
    let (takeoff, landing) = sim_harness::real_logs::airborne(&log);
    if let Some(t) = takeoff {
        from = from.max(t + sim_harness::real_logs::AFTER_TAKEOFF);
    }
    to = landing.unwrap_or(to);
    let norm: f64 = mag
        .iter()
        .map(|(_, m)| m.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt())
        .sum::<f64>()
        / mag.len() as f64;
    println!(
        "{}: {} rows, {} MAG samples ({:.1} Hz, mean |B| {:.3} G), window {from:.0}–{to:.0} s",
        path.display(),
        log.rows.len(),
        mag.len(),
        mag.len() as f64 / (mag[mag.len() - 1].0 - mag[0].0),
        norm
    );
    // The field in NED through the autopilot's attitude: a usable magnetometer gives one
    // declination and inclination whatever the aircraft does.
    let (mut decl, mut incl) = (Vec::new(), Vec::new());
    let mut r = 0usize;
    for (t, m) in &mag {
        while r + 1 < log.rows.len() && log.rows[r + 1].t <= *t {
            r += 1;
        }
        let (Some(a), true) = (log.rows[r].reference, log.rows[r].t >= from && log.rows[r].t <= to)
        else {
            continue;
        };
        let (sr, cr, sp, cp, sy, cy) =
            (a[0].sin(), a[0].cos(), a[1].sin(), a[1].cos(), a[2].sin(), a[2].cos());
        let b = m.map(f64::from);
        // Body → NED (ZYX).
        let n = cp * cy * b[0] + (sr * sp * cy - cr * sy) * b[1] + (cr * sp * cy + sr * sy) * b[2];
        let e = cp * sy * b[0] + (sr * sp * sy + cr * cy) * b[1] + (cr * sp * sy - sr * cy) * b[2];
        let d = -sp * b[0] + sr * cp * b[1] + cr * cp * b[2];
        decl.push(e.atan2(n).to_degrees());
        incl.push(d.atan2(n.hypot(e)).to_degrees());
    }
    let stats = |v: &[f64]| {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let q = |p: f64| s[((s.len() - 1) as f64 * p) as usize];
        (q(0.5), q(0.1), q(0.9))
    };
    let (dm, d10, d90) = stats(&decl);
    let (im, i10, i90) = stats(&incl);
    println!(
        "MAG through the autopilot's attitude, in the window: declination {dm:.1}° (10–90 %: {d10:.1}° … {d90:.1}°), inclination {im:.1}° ({i10:.1}° … {i90:.1}°)"
    );
    println!("| estimator | tilt | roll | pitch | yaw | yaw jumps > 11° | EKF2 magnetometer 3-D / heading / fault |");
    println!("|---|---|---|---|---|---|---|");
    print("ours", &score(&log, &mut Wing::ekf1_with(&setup), None, &[], false, from, to));
    let mut dummy = Wing::ekf1_with(&setup);
    let mut e = Px4Ekf2::with_setup(&setup);
    print(
        "EKF2 as in compare (no magnetometer; built with it)",
        &score(&log, &mut dummy, Some(&mut e), &[], false, from, to),
    );
    let mut e = Px4Ekf2::with_setup(&setup);
    print(
        "EKF2 + the log's magnetometer (EKF2_MAG_TYPE automatic)",
        &score(&log, &mut dummy, Some(&mut e), &mag, false, from, to),
    );
    let mut e = Px4Ekf2::with_setup(&setup);
    e.ekf_mut().params_mut().set_mag_fusion_type(MagFusionType::Heading);
    e.ekf_mut().update_parameters();
    print(
        "EKF2 + the log's magnetometer, heading only (EKF2_MAG_TYPE 1)",
        &score(&log, &mut dummy, Some(&mut e), &mag, false, from, to),
    );
    let mut e = Px4Ekf2::with_setup(&setup);
    print(
        "EKF2, yaw reset to the autopilot's each 1 s when near level (no magnetometer)",
        &score(&log, &mut dummy, Some(&mut e), &[], true, from, to),
    );
    // Other suspects, one at a time (no magnetometer).
    let tweaks: [(&str, Tweak); 7] = [
        ("EKF2, accelerometer-bias states frozen (EKF2_ACC_B_NOISE 0, ABIAS_INIT 0)", |k| {
            k.params_mut().set_accel_bias_noise(0.0);
            k.params_mut().set_accel_bias_init(0.0);
        }),
        ("EKF2, accel-bias learning limits off (EKF2_ABL_ACCLIM 200, GYRLIM 50)", |k| {
            k.params_mut().set_accel_bias_learning_accel_limit_m_s2(200.0);
            k.params_mut().set_accel_bias_learning_gyro_limit_rad_s(50.0);
        }),
        ("EKF2, 3x its IMU noise (EKF2_GYR_NOISE 0.045, ACC_NOISE 1.05)", |k| {
            k.params_mut().set_gyro_noise(0.045);
            k.params_mut().set_accel_noise(1.05);
        }),
        ("EKF2, 10x its IMU noise (EKF2_GYR_NOISE 0.15, ACC_NOISE 3.5)", |k| {
            k.params_mut().set_gyro_noise(0.15);
            k.params_mut().set_accel_noise(3.5);
        }),
        ("EKF2, height from the barometer (EKF2_HGT_REF 0, the C++ struct's; PX4's is GNSS)", |k| {
            k.params_mut().set_hgt_ref(ekf2::params::HeightReference::Baro);
        }),
        (
            "EKF2, the C++ struct's where PX4's parameter file differs (ACC_B_NOISE 1e-2, WIND_NSD 0.01, BARO_NOISE 2.0, HGT_REF baro)",
            |k| {
                let mut p = k.params_mut();
                p.set_accel_bias_noise(1e-2);
                p.set_wind_nsd(1e-2);
                p.set_baro_noise(2.0);
                p.set_hgt_ref(ekf2::params::HeightReference::Baro);
            },
        ),
        ("EKF2, 3x its IMU noise and accelerometer-bias states frozen", |k| {
            k.params_mut().set_gyro_noise(0.045);
            k.params_mut().set_accel_noise(1.05);
            k.params_mut().set_accel_bias_noise(0.0);
            k.params_mut().set_accel_bias_init(0.0);
        }),
    ];
    for (name, f) in tweaks {
        let mut e = Px4Ekf2::with_setup(&setup);
        f(e.ekf_mut());
        e.ekf_mut().update_parameters();
        print(name, &score(&log, &mut dummy, Some(&mut e), &[], false, from, to));
    }
    // Where EKF2's disagreement lies: 30 s segments of the window, ours against EKF2, with
    // the autopilot's largest bank and pitch and EKF2's airspeed/sideslip test ratios.
    if std::env::args().any(|a| a == "--segments") {
        println!("| from | ours tilt | EKF2 tilt | EKF2 yaw | max |roll| | max |pitch| | EKF2 hvel / tas / beta ratio (mean) |");
        println!("|---|---|---|---|---|---|---|");
        let mut w = Wing::ekf1_with(&setup);
        let mut e = Px4Ekf2::with_setup(&setup);
        let mut seg = from;
        let mut acc = [0.0f64; 9];
        for row in &log.rows {
            w.step(row);
            e.step(row);
            let Some(want) = row.reference else { continue };
            if row.t < from || row.t > to {
                continue;
            }
            if row.t >= seg + 30.0 {
                let n = acc[8].max(1.0);
                println!(
                    "| {seg:.0} | {:.2}° | {:.2}° | {:.1}° | {:.0}° | {:.0}° | {:.2} / {:.2} / {:.2} |",
                    (acc[0] / n).sqrt().to_degrees(),
                    (acc[1] / n).sqrt().to_degrees(),
                    (acc[2] / n).sqrt().to_degrees(),
                    acc[3].to_degrees(),
                    acc[4].to_degrees(),
                    acc[5] / n,
                    acc[6] / n,
                    acc[7] / n
                );
                seg += 30.0;
                acc = [0.0; 9];
            }
            let (a, b) = (w.attitude(), e.attitude());
            acc[0] += tilt_error(a, want).powi(2);
            acc[1] += tilt_error(b, want).powi(2);
            acc[2] += wrap(b[2] - want[2]).powi(2);
            acc[3] = acc[3].max(want[0].abs());
            acc[4] = acc[4].max(want[1].abs());
            let k = e.ekf();
            let f = |x: f32| if x.is_finite() { f64::from(x) } else { 0.0 };
            acc[5] += f(k.horiz_vel_innov_test_ratio());
            acc[6] += f(k.airspeed_innov_test_ratio());
            acc[7] += f(k.sideslip_innov_test_ratio());
            acc[8] += 1.0;
        }
    }
    Ok(())
}
