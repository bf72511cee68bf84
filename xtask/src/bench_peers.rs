//! `cargo xtask bench-peers [SCENARIO]`: the cost of ours, fusion-nav and PX4 EKF2 on the
//! Cortex-M4F, on the same simulated flight (default `aggressive`, seed 1), counted by the
//! same SysTick stopwatch as `bench-fw` under QEMU `-icount shift=0` — instructions, not
//! cycles. One `bench-peers` ELF per estimator (so flash, static RAM and stack are its own),
//! each fed every sample from an embedded buffer (`bench-peers/build.rs`). Prints
//! `key: value` lines and writes them to `target/bench-peers.txt` (read by
//! `sim-harness compare --headline`). Flash excludes the embedded flight (and EKF2's
//! embedded host reference); static RAM excludes EKF2's heap arena, which is reported as
//! `heap_*`; the estimator's state sits on the stack, so `stack_bytes` includes
//! `state_bytes` (EKF2's object is on the heap instead).
//!
//! EKF2's C++ is cross-compiled by the `ekf2-sys` build script with Debian's
//! `arm-none-eabi-g++` (installed here) and linked with newlib's libm (`bench-peers/build.rs`).

use crate::fw::{build_harness, root};
use crate::qemu::{base_args, sizes};
use crate::toolchain::{ensure_arm_cxx, ensure_qemu, Cross, TARGET};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// The estimators benched, as `bench-peers` cargo features (= key prefixes).
const PEERS: [&str; 3] = ["ours", "fusion-nav", "ekf2"];

/// Runs the bench and prints its figures.
pub fn run(args: &[String]) -> Result<()> {
    let scenario = args.first().map_or("aggressive", String::as_str);
    let r = root();
    let cross = Cross::ensure(&r)?;
    ensure_qemu()?;
    ensure_arm_cxx()?;
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
    let bindgen_args = arm_system_includes()?
        .iter()
        .map(|d| format!("-isystem{}", d.display()))
        .collect::<Vec<_>>()
        .join(" ");
    let mut lines = vec![format!("flight: {scenario} (seed 1, sim-harness simulate)")];
    for peer in PEERS {
        // EKF2 (its allocator API) needs `alloc`.
        let std_crates = if peer == "ekf2" { "core,alloc" } else { "core" };
        let mut c = cross.cargo_std("build", std_crates);
        c.arg("--manifest-path").arg(r.join("bench-peers/Cargo.toml"));
        c.args(["--release", "--features", peer, "--target-dir"]).arg(&dir);
        c.env("BENCH_PEERS_LOG", &log);
        // ekf2-sys's cc and bindgen read the target-scoped variables (the host build of
        // sim-harness's EKF2, a build dependency, keeps the host compiler).
        c.env("CXX_thumbv7em_none_eabihf", "arm-none-eabi-g++")
            .env("CC_thumbv7em_none_eabihf", "arm-none-eabi-gcc")
            .env("AR_thumbv7em_none_eabihf", "arm-none-eabi-ar")
            .env("BINDGEN_EXTRA_CLANG_ARGS_thumbv7em_none_eabihf", &bindgen_args);
        crate::run(c)?;
        let built = dir.join(TARGET).join("release/bench-peers");
        let elf = dir.join(format!("bench-{peer}.elf"));
        std::fs::copy(&built, &elf).with_context(|| format!("copying {}", built.display()))?;
        let out = run_qemu(&elf)?;
        let s = sizes(&elf)?;
        lines.extend(out.lines().filter(|l| l.contains(':')).map(str::to_string));
        let figure = |k: &str| -> u64 {
            out.lines()
                .find_map(|l| l.strip_prefix(&format!("{peer}.{k}: ")))
                .and_then(|v| v.trim().parse().ok())
                .unwrap_or(0)
        };
        let flight = figure("embedded_flight_bytes");
        if flight == 0 {
            bail!("the {peer} bench printed no embedded_flight_bytes");
        }
        // Flash of the program: the ELF's minus the embedded flight and reference.
        let embedded = flight + figure("embedded_reference_bytes");
        lines.push(format!("{peer}.flash_bytes: {}", s.flash - embedded));
        lines.push(format!("{peer}.static_ram_bytes: {}", s.ram - figure("heap_arena_bytes")));
    }
    let text = lines.join("\n") + "\n";
    print!("{text}");
    let file = r.join("target/bench-peers.txt");
    std::fs::write(&file, &text).with_context(|| format!("writing {}", file.display()))?;
    println!("\n{}", table(&lines));
    eprintln!("xtask: wrote {} (instructions, not cycles)", file.display());
    Ok(())
}

/// The figures side by side, as the markdown table of docs/peers.md.
fn table(lines: &[String]) -> String {
    let get = |peer: &str, k: &str| {
        let key = format!("{peer}.{k}: ");
        lines.iter().find_map(|l| l.strip_prefix(&key)).map_or("—".into(), |v| v.to_string())
    };
    let mut t = String::from(
        "| estimator | mean / sample | GPS-update sample (mean) | max | flash | static RAM | heap (peak) | stack | state |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for peer in PEERS {
        let heap = get(peer, "heap_peak_bytes");
        let heap = if heap == "—" { "0".to_string() } else { heap };
        t += &format!(
            "| {peer} | {} | {} | {} | {} | {} | {heap} | {} | {} |\n",
            get(peer, "mean_instr"),
            get(peer, "gps_instr"),
            get(peer, "max_instr"),
            get(peer, "flash_bytes"),
            get(peer, "static_ram_bytes"),
            get(peer, "stack_bytes"),
            get(peer, "state_bytes"),
        );
    }
    t + "(instructions per IMU sample under QEMU -icount, not cycles; bytes)"
}

/// `arm-none-eabi-gcc`'s system include directories (its own, then newlib's). bindgen's
/// libclang has no headers of its own for a bare-metal target (it finds `stddef.h` through
/// the host gcc on the host), so it is given the ones the C++ was compiled against.
fn arm_system_includes() -> Result<Vec<std::path::PathBuf>> {
    let out = Command::new("arm-none-eabi-gcc")
        .args(["-xc", "-E", "-v", "-"])
        .stdin(std::process::Stdio::null())
        .output()
        .context("running arm-none-eabi-gcc")?;
    let text = String::from_utf8_lossy(&out.stderr);
    let dirs: Vec<_> = text
        .lines()
        .skip_while(|l| !l.starts_with("#include <...>"))
        .skip(1)
        .take_while(|l| l.starts_with(' '))
        .map(|l| std::path::PathBuf::from(l.trim()))
        .collect();
    if dirs.is_empty() {
        bail!("arm-none-eabi-gcc -v printed no include search list");
    }
    Ok(dirs)
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
