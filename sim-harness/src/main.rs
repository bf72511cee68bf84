//! `sim-harness` command line.
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "sim-harness", version, about = "Simulate, replay, measure and check the wing-ahrs estimator")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Short built-in demo: replay a synthetic coordinated turn and print the attitude.
    Demo,
    /// Hardware in the loop: stream a flight log into the QEMU firmware and write the
    /// estimate CSV from its MAVLink telemetry (same columns as `replay`).
    Hil(sim_harness::hil::cli::HilArgs),
    /// Bench telemetry check: decode MAVLink from a serial port, TCP socket or the QEMU
    /// firmware; rates, CRC errors, drops, pass/fail; `--record` a flight-log CSV.
    Telemetry(sim_harness::telemetry::cli::TelemetryArgs),
}

fn main() {
    let cli = Cli::parse();
    let res = match cli.cmd {
        Cmd::Demo => demo(),
        Cmd::Hil(a) => sim_harness::hil::cli::main(a),
        Cmd::Telemetry(a) => sim_harness::telemetry::cli::main(a),
    };
    if let Err(e) = res {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn demo() -> anyhow::Result<()> {
    println!("demo: not yet wired");
    Ok(())
}
