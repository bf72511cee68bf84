//! PX4 EKF2's start-up on one log, every 15 s: tilt and yaw error, the truth's roll and
//! pitch, whether it fuses GNSS velocity and airspeed or holds a fake position; then when
//! its yaw aligned and how often its yaw jumped by more than 11° (Gaussian-sum yaw resets).
//! The evidence of docs/peers.md, "Where a peer diverges".
//! `cargo run --release -p sim-harness --example px4_ekf2_startup -- LOG.csv [defaults|matched]`
use anyhow::{bail, Context, Result};
use ekf2::params::ControlStatus;
use sim_harness::compare::nominal_dt;
use sim_harness::metrics::{tilt_error, wrap};
use sim_harness::peers::px4_ekf2::Px4Ekf2;
use sim_harness::peers::setup::{SensorFigures, Setup, Tuning};
use sim_harness::peers::Estimator;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        bail!("usage: px4_ekf2_startup LOG.csv [defaults|matched] (a log with truth, e.g. target/jsbsim/rand2.csv)");
    };
    let tuning = match args.get(1).map(String::as_str) {
        None | Some("defaults") => Tuning::Defaults,
        Some("matched") => Tuning::Matched,
        Some(o) => bail!("configuration {o:?}: use defaults or matched"),
    };
    let log = sim_harness::csv::read_log(std::path::Path::new(path))
        .with_context(|| format!("reading {path}"))?;
    let setup = Setup::for_log(&log, nominal_dt(&log), tuning, SensorFigures::thesis());
    let mut e = Px4Ekf2::with_setup(&setup);
    let (mut yaw_at, mut next, mut jumps, mut prev_yaw) = (None, 0.0, 0, 0.0);
    for row in &log.rows {
        e.step(row);
        let Some(truth) = row.truth else { bail!("{path}: no truth attitude") };
        let s = e.ekf().control_status();
        if yaw_at.is_none() && s.contains(ControlStatus::YAW_ALIGN) {
            yaw_at = Some(row.t);
        }
        let a = e.attitude();
        jumps += usize::from(wrap(a[2] - prev_yaw).abs() > 0.2);
        prev_yaw = a[2];
        if row.t >= next {
            next += 15.0;
            let flag = |f| u8::from(s.contains(f));
            println!(
                "t {:6.1} tilt {:6.2}° yaw err {:7.2}° | truth roll {:7.1}° pitch {:6.1}° | GNSS vel {} airspeed {} fake pos {}",
                row.t,
                tilt_error(a, truth).to_degrees(),
                wrap(a[2] - truth[2]).to_degrees(),
                truth[0].to_degrees(),
                truth[1].to_degrees(),
                flag(ControlStatus::GNSS_VEL),
                flag(ControlStatus::FUSE_ASPD),
                flag(ControlStatus::FAKE_POS),
            );
        }
    }
    println!("yaw aligned at {yaw_at:?} s; yaw jumps > 11° between samples: {jumps}");
    Ok(())
}
