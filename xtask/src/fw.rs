//! Firmware build, size report, and the QEMU demo/bench drivers.
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;


/// Which board the firmware is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Board {
    /// QEMU mps2-an386 (default; CI, demo, HIL).
    Qemu,
    /// STM32F405 flight controller.
    F405,
}

impl Board {
    /// `--board qemu|f405` (default qemu).
    pub fn from_args(args: &[String]) -> Result<Board> {
        match args.iter().position(|a| a == "--board") {
            None => Ok(Board::Qemu),
            Some(i) => match args.get(i + 1).map(String::as_str) {
                Some("qemu") => Ok(Board::Qemu),
                Some("f405") => Ok(Board::F405),
                other => bail!("--board expects qemu or f405, got {other:?}"),
            },
        }
    }
    fn feature(self) -> &'static str {
        match self {
            Board::Qemu => "board-qemu",
            Board::F405 => "board-f405",
        }
    }
}

/// The workspace root (xtask lives one level below it).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("workspace root").to_path_buf()
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Builds the firmware ELF for `board` (release profile) with the automatically
/// chosen Cortex-M toolchain and returns its path.
pub fn build(board: Board) -> Result<PathBuf> {
    let cross = crate::toolchain::Cross::ensure(&root())?;
    let mut c = cross.cargo("build");
    c.args(["--release", "-p", "wing-ahrs", "--bin", "wing-ahrs-fw"]).args(["--features", &format!("firmware,{}", board.feature())]);
    crate::run(c).context("firmware build failed")?;
    Ok(cross.artifact("release", "wing-ahrs-fw"))
}

/// Builds the host harness (release) and returns the path of its binary.
pub fn build_harness() -> Result<PathBuf> {
    let root = root();
    let status = cargo().current_dir(&root).args(["build", "--release", "-p", "sim-harness"]).status().context("building sim-harness")?;
    if !status.success() {
        bail!("sim-harness build failed");
    }
    let dir = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root.join("target"));
    Ok(dir.join("release").join("sim-harness"))
}

/// `cargo xtask demo [LOG.csv]`: firmware in QEMU flying a simulated flight, live.
pub fn demo(args: &[String]) -> Result<()> {
    let elf = build(Board::Qemu)?;
    let harness = build_harness()?;
    let mut cmd = Command::new(harness);
    cmd.arg("hil").arg("--firmware").arg(&elf).arg("--live");
    cmd.args(args);
    let st = cmd.status().context("running sim-harness hil")?;
    if !st.success() {
        bail!("demo failed");
    }
    Ok(())
}

/// `cargo xtask bench-fw [LOG.csv]`: cost and size figures as `key: value` lines.
pub fn bench(args: &[String]) -> Result<()> {
    let elf = build(Board::Qemu)?;
    let sizes = crate::qemu::sizes(&elf)?;
    let harness = build_harness()?;
    let st = Command::new(harness).arg("hil").arg("--firmware").arg(&elf).arg("--bench").args(args).status().context("running sim-harness hil --bench")?;
    if !st.success() {
        bail!("bench flight failed");
    }
    println!("fw_flash_bytes: {}", sizes.flash);
    println!("fw_static_ram_bytes: {}", sizes.ram);
    Ok(())
}
