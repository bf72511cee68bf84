//! `cargo xtask bench-peers [SCENARIO]`: the cost of ours and of fusion-nav on the
//! Cortex-M4F, on the same simulated flight (default `aggressive`, seed 1), counted by the
//! same SysTick stopwatch as `bench-fw` under QEMU `-icount shift=0` — instructions, not
//! cycles. One `bench-peers` ELF per estimator (so flash, static RAM and stack are its own),
//! each fed every sample from an embedded buffer (`bench-peers/build.rs`). Prints
//! `key: value` lines and writes them to `target/bench-peers.txt` (read by
//! `sim-harness compare --headline`). Flash excludes the embedded flight; the estimator's
//! state sits on the stack, so `stack_bytes` includes `state_bytes`.
//!
//! PX4 EKF2 is not in it: see [`EKF2_STATUS`].

use crate::fw::{build_harness, root};
use crate::qemu::{base_args, sizes};
use crate::toolchain::{ensure_qemu, Cross, TARGET};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// The estimators benched, as `bench-peers` cargo features (= key prefixes).
const PEERS: [&str; 2] = ["ours", "fusion-nav"];

/// Why EKF2 has no M4F figures yet (printed, and written into the figures file).
pub const EKF2_STATUS: &str = "ekf2.status: not benched on the M4F in this revision: not attempted (it needs ekf2-sys cross-compiled by bindgen + arm-none-eabi-g++ with newlib's libstdc++, and a heap allocator in the bench firmware)";

/// Runs the bench and prints its figures.
pub fn run(args: &[String]) -> Result<()> {
    let scenario = args.first().map_or("aggressive", String::as_str);
    let r = root();
    let cross = Cross::ensure(&r)?;
    ensure_qemu()?;
    let dir = r.join("target/bench-peers");
    std::fs::create_dir_all(&dir)?;
    let log = dir.join(format!("{scenario}.csv"));
    let st = Command::new(build_harness()?)
        .args(["simulate", scenario, "--seed", "1", "--out"])
        .arg(&log)
        .status()
        .context("running sim-harness simulate")?;
    if !st.success() {
        bail!("simulating {scenario} failed");
    }
    let mut lines = vec![format!("flight: {scenario} (seed 1, sim-harness simulate)")];
    for peer in PEERS {
        let mut c = cross.cargo("build");
        c.arg("--manifest-path").arg(r.join("bench-peers/Cargo.toml"));
        c.args(["--release", "--features", peer, "--target-dir"]).arg(&dir);
        c.env("BENCH_PEERS_LOG", &log);
        crate::run(c)?;
        let built = dir.join(TARGET).join("release/bench-peers");
        let elf = dir.join(format!("bench-{peer}.elf"));
        std::fs::copy(&built, &elf).with_context(|| format!("copying {}", built.display()))?;
        let out = run_qemu(&elf)?;
        let s = sizes(&elf)?;
        lines.extend(out.lines().filter(|l| l.contains(':')).map(str::to_string));
        let flight: u64 = out
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{peer}.embedded_flight_bytes: ")))
            .and_then(|v| v.trim().parse().ok())
            .context("the bench printed no embedded_flight_bytes")?;
        // Flash of the program: the ELF's minus the embedded flight.
        lines.push(format!("{peer}.flash_bytes: {}", s.flash - flight));
        lines.push(format!("{peer}.static_ram_bytes: {}", s.ram));
    }
    lines.push(EKF2_STATUS.to_string());
    let text = lines.join("\n") + "\n";
    print!("{text}");
    let file = r.join("target/bench-peers.txt");
    std::fs::write(&file, &text).with_context(|| format!("writing {}", file.display()))?;
    eprintln!("xtask: wrote {} (instructions, not cycles)", file.display());
    Ok(())
}

/// Runs one bench ELF under QEMU with instruction counting; returns its semihosting output.
fn run_qemu(elf: &Path) -> Result<String> {
    let mut q = Command::new("qemu-system-arm");
    q.args(base_args(elf)).args(["-icount", "shift=0,sleep=off", "-serial", "null"]);
    q.stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::inherit());
    let mut child = q.spawn().context("starting qemu-system-arm")?;
    let start = Instant::now();
    loop {
        if let Some(st) = child.try_wait()? {
            let mut out = String::new();
            if let Some(mut o) = child.stdout.take() {
                use std::io::Read;
                o.read_to_string(&mut out)?;
            }
            if !st.success() {
                bail!("{} exited with {st}: {out}", elf.display());
            }
            return Ok(out);
        }
        if start.elapsed() > Duration::from_secs(600) {
            let _ = child.kill();
            bail!("{} did not finish in 600 s", elf.display());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}
