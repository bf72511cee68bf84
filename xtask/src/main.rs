//! `cargo xtask` — build orchestration for wing-ahrs.
//!
//! - `cargo xtask demo`  — the main job (see README).
//! - `cargo xtask test`  — every test: host workspace, Cortex-M builds, QEMU tests.
//! - `cargo xtask toolchain` — choose/install the Cortex-M toolchain and say which.
//! - `cargo xtask build-lib` — build the core library for `thumbv7em-none-eabihf`.

mod toolchain;

use anyhow::{bail, Context, Result};
use std::path::PathBuf;
use std::process::Command;
use toolchain::{cargo_bin, Cross};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask lives in the workspace").to_path_buf()
}

fn run(mut c: Command) -> Result<()> {
    eprintln!("xtask: {:?}", c);
    let st = c.status().with_context(|| format!("could not start {:?}", c.get_program()))?;
    if !st.success() {
        bail!("command failed ({st}): {:?}", c);
    }
    Ok(())
}

fn usage() -> ! {
    eprintln!("usage: cargo xtask <demo | test | toolchain | build-lib>");
    std::process::exit(2);
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let res = match args.first().map(String::as_str) {
        Some("demo") => demo(&args[1..]),
        Some("test") => test(),
        Some("toolchain") => Cross::ensure(&root()).map(|c| println!("toolchain: {:?} (artifacts in {})", c.kind, c.target_dir().display())),
        Some("build-lib") => build_lib().map(|_| ()),
        _ => usage(),
    };
    if let Err(e) = res {
        eprintln!("xtask: error: {e:#}");
        std::process::exit(1);
    }
}

/// The core library for the MCU, release profile.
fn build_lib() -> Result<Cross> {
    let cross = Cross::ensure(&root())?;
    let mut c = cross.cargo("build");
    c.args(["-p", "wing-ahrs", "--lib", "--release"]);
    run(c)?;
    Ok(cross)
}

/// The main job.
fn demo(extra: &[String]) -> Result<()> {
    let mut c = Command::new(cargo_bin());
    c.current_dir(root()).args(["run", "--release", "-q", "-p", "sim-harness", "--", "demo"]).args(extra);
    run(c)
}

/// Everything CI runs.
fn test() -> Result<()> {
    let r = root();
    // 1. Host: the whole workspace (core, harness, xtask).
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["test", "--workspace", "--release"]);
    run(c)?;
    // 2. The core builds for the Cortex-M4F, through the automatic toolchain choice.
    let cross = build_lib()?;
    println!("xtask: core library builds for {} with the {:?} toolchain", toolchain::TARGET, cross.kind);
    Ok(())
}
