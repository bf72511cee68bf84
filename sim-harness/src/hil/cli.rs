//! `sim-harness hil LOG.csv --out EST.csv`: the command line of the QEMU HIL run.

use super::{estimates, plan, reference, run, Options};
use crate::estimate::{EstimateRow, EstimateWriter};
use crate::log::FlightLog;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `sim-harness hil`.
#[derive(clap::Args, Debug)]
pub struct HilArgs {
    /// Flight-log CSV (docs/formats.md). Omitted: `--scenario`, else the built-in synthetic flight.
    pub log: Option<PathBuf>,
    /// Simulate this scenario (built-in name such as flight1, flight2, aggressive, or a TOML path).
    #[arg(long)]
    pub scenario: Option<String>,
    /// Seed of the simulated sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Estimate CSV to write (same columns as `replay`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Firmware ELF (default: target/thumbv7em-none-eabihf/release/wing-ahrs-fw; build with `cargo xtask build-fw`).
    #[arg(long)]
    pub firmware: Option<PathBuf>,
    /// Show live attitude vs truth while streaming (at real time with a ground-station link).
    #[arg(long)]
    pub live: bool,
    /// Pace the flight at real time × this factor (default: 1 with a ground-station link,
    /// 4 with --live alone, else as fast as flow control allows).
    #[arg(long)]
    pub speed: Option<f64>,
    /// Length of the built-in synthetic flight, s.
    #[arg(long, default_value_t = 90.0)]
    pub seconds: f64,
    /// Cost benchmark: deterministic instruction counting (-icount), lock-step
    /// streaming; prints `key: value` figures.
    #[arg(long)]
    pub bench: bool,
    /// GPS wire format on the GPS UART.
    #[arg(long, value_enum, default_value_t = super::GpsWire::Ubx)]
    pub gps: super::GpsWire,
    /// Ground-station link over UDP (QGroundControl and MAVProxy listen on 14550): the
    /// autopilot's telemetry profile at real time, one MAVLink frame per datagram.
    /// `HOST:PORT`, `off`, or `auto` (127.0.0.1:14550 with --live, else off).
    #[arg(long, default_value = "auto")]
    pub mavlink_udp: String,
    /// Also send the per-sample HIL records (component 25: ATTITUDE, DEBUG_VECT and
    /// WIND_COV every sample) to the ground station.
    #[arg(long)]
    pub gcs_hil_records: bool,
}

/// Default firmware path in the workspace's target directory.
pub fn default_firmware() -> PathBuf {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    target.join("thumbv7em-none-eabihf/release/wing-ahrs-fw-qemu")
}

fn load(args: &HilArgs) -> Result<(FlightLog, String)> {
    match (&args.log, &args.scenario) {
        (Some(_), Some(_)) => bail!("give either a LOG.csv or --scenario, not both"),
        (Some(p), None) => Ok((crate::csv::read_log(p)?, p.display().to_string())),
        (None, Some(name)) => {
            let sc = crate::sim::load_scenario(name)?;
            let out = crate::sim::run(&sc, args.seed)?;
            Ok((out.log, format!("simulated scenario `{name}` (seed {})", args.seed)))
        }
        (None, None) => {
            if !(args.seconds > 0.0 && args.seconds <= 3600.0) {
                bail!("--seconds must be in (0, 3600]");
            }
            Ok((
                super::flight::synthetic(args.seconds, 1),
                format!("built-in synthetic flight ({} s)", args.seconds),
            ))
        }
    }
}

/// Largest |a − b| over attitude columns (wrapped to ±180°), rad, and the number of rows
/// bit-identical.
pub fn compare(a: &[EstimateRow], b: &[EstimateRow]) -> (f64, usize) {
    let mut max = 0.0f64;
    let mut same = 0;
    for (x, y) in a.iter().zip(b) {
        let mut eq = x.t == y.t;
        for i in 0..3 {
            // Wrapped: a yaw of +179.99° against −179.99° is 0.02° apart, not 359.98°.
            let d = (x.att[i] - y.att[i] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            max = max.max(d.abs());
            eq &= x.att[i].to_bits() == y.att[i].to_bits();
        }
        same += eq as usize;
    }
    (max, same)
}

/// Runs the command.
pub fn main(args: HilArgs) -> Result<()> {
    let (log, name) = load(&args)?;
    if log.rows.is_empty() {
        bail!("{name}: no rows");
    }
    // The link and the pace first: a wrong option fails before QEMU boots.
    let mavlink_udp = match args.mavlink_udp.as_str() {
        "auto" if args.live && !args.bench => udp_target("127.0.0.1:14550")?,
        "auto" => None,
        s => udp_target(s)?,
    };
    let pace = pace(&args, mavlink_udp.is_some())?;
    let firmware = args.firmware.clone().unwrap_or_else(default_firmware);
    if !super::qemu::available() {
        bail!("qemu-system-arm not found (apt-get install qemu-system-arm)");
    }
    let mut opts = Options::hil(firmware);
    opts.live = args.live;
    opts.mavlink_udp = mavlink_udp;
    opts.gcs_hil_records = args.gcs_hil_records;
    opts.pace = pace;
    if args.bench {
        opts.icount = true;
        opts.window = Some(1);
    }
    opts.timeout = Duration::from_secs(3600);
    if let Some(a) = opts.mavlink_udp {
        println!("hil: ground-station link udp://{a}: MAVLink at real time (--mavlink-udp off to disable)");
    }
    println!("hil: {name}: {} rows, firmware {}", log.rows.len(), opts.firmware.display());
    let out = run(&log, &plan(&log, args.gps), &opts)?;
    let est = estimates(&log, &out);
    if let Some(p) = &args.out {
        let f =
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?;
        let mut w = EstimateWriter::new(f)?;
        for r in &est {
            w.write(r)?;
        }
        w.finish()?;
        println!("wrote {} ({} rows)", p.display(), est.len());
    }
    let cfg = wing_ahrs::Config::default();
    let refr = reference(&log, cfg, args.gps);
    let (max_ref, same) = compare(&est, &refr);
    let (plain, _) = crate::estimate::replay_estimates(&log, cfg);
    let (max_plain, same_plain) = compare(&est, &plain);
    println!(
        "firmware vs host replay with the same (wire-decoded) fixes: {same}/{} rows bit-identical, max |Δattitude| {:.3e} rad",
        refr.len(),
        max_ref
    );
    let first = est
        .iter()
        .zip(&plain)
        .position(|(a, b)| a.att.iter().zip(&b.att).any(|(x, y)| x.to_bits() != y.to_bits()));
    let first = first.map_or("none".to_string(), |i| format!("row {i} (t = {} s)", est[i].t));
    println!(
        "firmware vs plain `replay` of the log: {same_plain}/{} rows bit-identical (first difference: {first}), max |Δattitude| {:.3e}°",
        plain.len(),
        max_plain.to_degrees()
    );
    match args.gps {
        super::GpsWire::Ubx => {
            let (wire_vel, _) = crate::estimate::replay_estimates(
                &super::with_wire_velocity(&log, super::GpsWire::Ubx),
                cfg,
            );
            let (_, same_wire) = compare(&est, &wire_vel);
            println!(
                "  cause: UBX NAV-PVT carries velocity and speed accuracy in whole mm/s — plain `replay` of the log with them in mm/s: {same_wire}/{} rows bit-identical",
                wire_vel.len()
            );
        }
        super::GpsWire::Nmea => {
            println!("  cause: NMEA carries speed (knots) and course only, no vertical velocity")
        }
    }
    if let Some(c) = crate::metrics::compare(&log, &est, 10.0) {
        println!("attitude error vs truth after t = 10 s (firmware, degrees):");
        println!("  {:<6} {:>8} {:>8} {:>8} {:>8}", "axis", "mean", "std", "rms", "max|e|");
        for (name, st) in ["roll", "pitch", "yaw"].iter().zip(&c.att) {
            let d = |x: f64| x.to_degrees();
            println!(
                "  {:<6} {:>8.3} {:>8.3} {:>8.3} {:>8.3}",
                name,
                d(st.mean),
                d(st.std),
                d(st.rms),
                d(st.max_abs)
            );
        }
    }
    println!(
        "link: {} frames, {} CRC errors, {} lost; wall {:.1} s",
        out.link.frames,
        out.link.crc_errors,
        out.link.seq_lost,
        out.wall.as_secs_f64()
    );
    // Cost counters are instruction counts only under -icount (--bench).
    let kv: Vec<String> = out
        .named
        .iter()
        .filter(|(k, _)| args.bench || !(k.starts_with("INS_") || k.starts_with("CAL_")))
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    println!("firmware health: {}", kv.join(" "));
    if args.bench {
        let g = |k: &str| out.named.get(k).copied().unwrap_or(-1);
        println!("fw_predict_instructions: {}", g("INS_PRED"));
        println!("fw_predict_max_instructions: {}", g("INS_PMAX"));
        println!("fw_predict_update_instructions: {}", g("INS_UPD"));
        println!("fw_isr_max_instructions: {}", g("INS_MAX"));
        // Stack high-water: the whole (boot and flight) is what must fit; the split
        // says where it goes (main's idle frame + nested handlers = the flight part).
        println!("fw_stack_bytes: {}", g("STACK"));
        println!("fw_stack_boot_bytes: {}", g("STACK_BOOT"));
        println!("fw_stack_main_idle_bytes: {}", g("STACK_MAIN"));
        println!("fw_stack_isr_bytes: {}", g("STACK_ISR"));
        println!("fw_attitude_step_instructions: {}", g("INS_STEP"));
        println!("fw_covariance_propagation_instructions: {}", g("INS_PROP"));
        println!("fw_sin_instructions: {}", g("INS_SINF"));
        println!("fw_atan2_instructions: {}", g("INS_ATAN2"));
        println!("fw_sqrt_instructions: {}", g("INS_SQRT"));
        println!("fw_sqrt_mismatches: {} (VSQRT vs libm sqrtf, every binade)", g("SQRT_MISS"));
        println!("fw_gps_accel_fuse_instructions: {}", g("INS_FUSE"));
        println!("gps_parser_instructions_per_byte_ubx: {}", g("INS_UBXB"));
        println!("gps_parser_instructions_per_byte_nmea: {}", g("INS_NMEAB"));
        println!("fw_stopwatch_calibration_instructions: {} (expected 20002)", g("CAL_20K"));
        println!("note: instructions counted by QEMU -icount shift=0 (SysTick 25 MHz = 40 instructions/tick), not cycles");
    }
    if est.len() != log.rows.len() {
        bail!("firmware answered {} of {} samples", est.len(), log.rows.len());
    }
    Ok(())
}

/// The pace of the flight. A ground station gets real time, and the live view shows what
/// it shows, so a link forbids any other speed.
fn pace(args: &HilArgs, gcs: bool) -> Result<Option<f64>> {
    match (args.speed, gcs) {
        (Some(s), _) if !(s > 0.0 && s.is_finite()) => bail!("--speed must be > 0, got {s}"),
        (Some(s), true) if s != 1.0 => bail!(
            "--speed {s} with a ground-station link: the link runs at real time, as an autopilot's does; use --speed 1 or --mavlink-udp off"
        ),
        (_, true) => Ok(Some(1.0)),
        (s, false) => Ok(s.or(if args.live { Some(4.0) } else { None })),
    }
}

/// `--mavlink-udp`: `off`/`none`, or an address.
pub fn udp_target(s: &str) -> anyhow::Result<Option<std::net::SocketAddr>> {
    use std::net::ToSocketAddrs;
    if s == "off" || s == "none" {
        return Ok(None);
    }
    let a = s
        .to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .ok_or_else(|| anyhow::anyhow!("--mavlink-udp must be HOST:PORT or off, got {s:?}"))?;
    Ok(Some(a))
}
