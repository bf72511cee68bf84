//! `sim-harness telemetry`: the command line of the bench telemetry check.

use super::check::{analyze, capture, capture_qemu, print, verdict, Limits, Source};
use anyhow::{bail, Result};
use std::path::PathBuf;

/// Arguments of `sim-harness telemetry`.
#[derive(clap::Args, Debug)]
pub struct TelemetryArgs {
    /// Serial port of the board (e.g. /dev/ttyUSB0).
    #[arg(long)]
    pub port: Option<String>,
    /// Baud rate of the serial port.
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// TCP endpoint carrying the telemetry (host:port).
    #[arg(long)]
    pub tcp: Option<String>,
    /// Boot this firmware ELF in QEMU on a flat, still bench instead.
    #[arg(long)]
    pub qemu: Option<PathBuf>,
    /// Session length, s.
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Configured ATTITUDE rate to check against, Hz.
    #[arg(long, default_value_t = 50)]
    pub attitude_hz: u16,
    /// Write the raw IMU/GPS telemetry to this flight-log CSV (for `replay`).
    #[arg(long)]
    pub record: Option<PathBuf>,
}

/// Runs the command; a failed bench check is an error (exit code 1).
pub fn main(a: TelemetryArgs) -> Result<()> {
    if !(a.seconds > 0.0) {
        bail!("--seconds must be positive");
    }
    let bytes = match (&a.port, &a.tcp, &a.qemu) {
        (Some(p), None, None) => capture(&Source::Serial(p.clone(), a.baud), a.seconds)?,
        (None, Some(t), None) => capture(&Source::Tcp(t.clone()), a.seconds)?,
        (None, None, Some(fw)) => capture_qemu(
            fw.clone(),
            a.seconds,
            a.attitude_hz,
            if a.record.is_some() { 100 } else { 0 },
        )?,
        _ => bail!("give exactly one of --port, --tcp, --qemu"),
    };
    let r = analyze(&bytes);
    print(&r);
    if let Some(p) = &a.record {
        crate::csv::write_log_file(p, &r.recorded)?;
        println!("recorded {} IMU rows to {}", r.recorded.rows.len(), p.display());
    }
    let (ok, lines) = verdict(
        &r,
        &Limits { max_tilt_deg: 2.0, attitude_hz: a.attitude_hz as f64, rate_tol: 0.10 },
    );
    for l in &lines {
        println!("{l}");
    }
    if !ok {
        bail!("bench check failed");
    }
    Ok(())
}
