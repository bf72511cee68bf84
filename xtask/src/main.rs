//! `cargo xtask …`: build orchestration for wing-ahrs.
//!
//! - `build-fw [--board qemu|f405]` — build the firmware ELF (thumbv7em-none-eabihf, release).
//! - `run-fw` — boot the QEMU firmware alone and show its defmt log (needs `defmt-print` to decode).
//! - `demo` — build the firmware, boot QEMU, stream a simulated flight in, show attitude vs truth.
//! - `bench-fw` — instruction counts, flash/RAM/stack of the QEMU firmware as `key: value` lines.
use anyhow::{bail, Result};

mod fw;
mod qemu;

fn main() {
    if let Err(e) = run() {
        eprintln!("xtask: error: {e:#}");
        std::process::exit(1);
    }
}

fn run() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(cmd) = args.first() else {
        println!("usage: cargo xtask <build-fw [--board qemu|f405] | run-fw | demo [LOG.csv] | bench-fw [LOG.csv]>");
        return Ok(());
    };
    let rest = &args[1..];
    match cmd.as_str() {
        "build-fw" => {
            let board = fw::Board::from_args(rest)?;
            let elf = fw::build(board)?;
            println!("{}", elf.display());
            let sizes = qemu::sizes(&elf)?;
            println!("fw_flash_bytes: {}", sizes.flash);
            println!("fw_static_ram_bytes: {}", sizes.ram);
            Ok(())
        }
        "run-fw" => qemu::run_alone(&fw::build(fw::Board::Qemu)?),
        "demo" => fw::demo(rest),
        "bench-fw" => fw::bench(rest),
        other => bail!("unknown subcommand `{other}` (build-fw, run-fw, demo, bench-fw)"),
    }
}
