//! `cargo xtask` — build orchestration for wing-ahrs.
//!
//! - `demo` — the main job (README): the firmware in QEMU flying a simulated flight, live.
//! - `test` — every test CI runs: host workspace, Cortex-M builds, QEMU tests.
//! - `toolchain` — choose/install the Cortex-M toolchain and say which.
//! - `build-lib` — the core library for `thumbv7em-none-eabihf`.
//! - `build-fw [--board qemu|f405]` — the firmware ELF (release).
//! - `run-fw` — boot the QEMU firmware alone and show its defmt log.
//! - `bench-fw [LOG.csv]` — instruction counts, flash/RAM/stack as `key: value` lines.

mod fw;
mod qemu;
mod toolchain;

use anyhow::{bail, Context, Result};
use std::process::Command;
use toolchain::{cargo_bin, Cross};

const USAGE: &str = "usage: cargo xtask <demo | test | toolchain | build-lib | build-fw [--board qemu|f405] | run-fw | bench-fw [LOG.csv]>";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(cmd) = args.first() else {
        println!("{USAGE}");
        return;
    };
    let rest = &args[1..];
    let res = match cmd.as_str() {
        "demo" => demo(rest),
        "test" => test(),
        "toolchain" => Cross::ensure(&fw::root()).map(|c| println!("toolchain: {:?} (artifacts in {})", c.kind, c.target_dir().display())),
        "build-lib" => build_lib().map(|_| ()),
        "build-fw" => fw::Board::from_args(rest).and_then(fw::build).and_then(|elf| {
            println!("{}", elf.display());
            let sizes = qemu::sizes(&elf)?;
            println!("fw_flash_bytes: {}\nfw_static_ram_bytes: {}", sizes.flash, sizes.ram);
            Ok(())
        }),
        "run-fw" => fw::build(fw::Board::Qemu).and_then(|elf| qemu::run_alone(&elf)),
        "bench-fw" => fw::bench(rest),
        other => Err(anyhow::anyhow!("unknown subcommand `{other}`\n{USAGE}")),
    };
    if let Err(e) = res {
        eprintln!("xtask: error: {e:#}");
        std::process::exit(1);
    }
}

/// Runs a command, failing with its command line if it fails.
pub fn run(mut c: Command) -> Result<()> {
    eprintln!("xtask: {c:?}");
    let st = c.status().with_context(|| format!("could not start {:?}", c.get_program()))?;
    if !st.success() {
        bail!("command failed ({st}): {c:?}");
    }
    Ok(())
}

/// The core library for the MCU, release profile.
fn build_lib() -> Result<Cross> {
    let cross = Cross::ensure(&fw::root())?;
    let mut c = cross.cargo("build");
    c.args(["-p", "wing-ahrs", "--lib", "--release"]);
    run(c)?;
    Ok(cross)
}

/// The main job. Until `sim-harness hil` lands, the host replay demo.
fn demo(extra: &[String]) -> Result<()> {
    let mut c = Command::new(cargo_bin());
    c.current_dir(fw::root()).args(["run", "--release", "-q", "-p", "sim-harness", "--", "demo"]).args(extra);
    run(c)
}

/// Everything CI runs.
fn test() -> Result<()> {
    let r = fw::root();
    // 1. Host: the whole workspace (core, harness, xtask).
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["test", "--workspace", "--release"]);
    run(c)?;
    // 2. The core and both firmware boards build for the Cortex-M4F, through the
    //    automatic toolchain choice.
    let cross = build_lib()?;
    println!("xtask: core library builds for {} with the {:?} toolchain", toolchain::TARGET, cross.kind);
    for board in [fw::Board::Qemu, fw::Board::F405] {
        let elf = fw::build(board)?;
        println!("xtask: firmware for {board:?} built: {}", elf.display());
    }
    Ok(())
}
