//! `cargo xtask bench-peers [SCENARIO] [--check]`: the cost of ours, fusion-nav and PX4 EKF2
//! on the Cortex-M4F, on the same simulated flight (default `aggressive`, seed 1), counted by
//! the same SysTick stopwatch as `bench-fw` under QEMU `-icount shift=0` — instructions, not
//! cycles. One `bench-peers` ELF per estimator (so flash, static RAM and stack are its own),
//! each fed every sample from an embedded buffer (`bench-peers/build.rs`). Prints
//! `key: value` lines and writes them to `target/bench-peers.txt` (read by
//! `sim-harness compare --headline`). Flash excludes the embedded flight (and EKF2's
//! embedded host reference); static RAM excludes EKF2's heap arena, which is reported as
//! `heap_*`; the estimator's state sits on the stack, so `stack_bytes` includes
//! `state_bytes` (EKF2's object is on the heap instead).
//!
//! `--check` (a step of `cargo xtask test`) then asserts what the run must show: every
//! bench ran every sample of the flight, its attitudes were all finite and agree with the
//! simulator's truth within [`TRUTH_BOUNDS`], the M4F EKF2 computes the host's EKF2, and
//! ours costs at most 1/[`COST_RATIO`] of each peer's mean instructions per sample (issue
//! 13's cost goal).
//!
//! EKF2's C++ is cross-compiled by the `ekf2-sys` build script with Debian's
//! `arm-none-eabi-g++` and its newlib and libstdc++ headers (installed here); no C or C++
//! library is linked (the C++'s libm calls resolve to Rust's `compiler-builtins`).

use crate::fw::{build_harness, root};
use crate::qemu::{base_args, sizes};
use crate::toolchain::{ensure_arm_cxx, ensure_qemu, Cross, TARGET};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// The estimators benched, as `bench-peers` cargo features (= key prefixes).
const PEERS: [&str; 3] = ["ours", "fusion-nav", "ekf2"];

/// Ours must cost at most 1/this of each peer's mean instructions per sample (`--check`).
const COST_RATIO: u64 = 20;

/// Largest error against truth `--check` accepts, degrees, for every estimator: RMS and
/// maximum of (roll, pitch, yaw) from 20 s into the flight (`bench-peers/src/truth.rs`).
/// Sanity bounds, not accuracy goals (those are `sim-harness compare`'s): on the default
/// flight the three stay within 0.4° RMS and 1.4° max in roll and pitch; a filter that
/// stalls drifts with the thesis sensors' 1.5°/s gyro bias, and one that stops fusing GNSS
/// is pulled towards wings-level in the flight's 40–50° banks, far beyond them.
const TRUTH_BOUNDS: TruthBounds = TruthBounds { rms: [2.0, 2.0, 5.0], max: [5.0, 5.0, 20.0] };

/// Where the comparison with truth starts, µs into the flight (`truth::FROM_US` of the bench).
const TRUTH_FROM_US: i64 = 20_000_000;

/// Largest rotation angle between the M4F EKF2 and the host's EKF2 `--check` accepts,
/// degrees (documented: 0.0002°).
const HOST_AGREEMENT_MAX_DEG: f64 = 0.01;

struct TruthBounds {
    rms: [f64; 3],
    max: [f64; 3],
}

/// Runs the bench and prints its figures; with `--check`, then asserts them.
pub fn run(args: &[String]) -> Result<()> {
    let mut scenario = None;
    let mut check = false;
    for a in args {
        match a.as_str() {
            "--check" => check = true,
            flag if flag.starts_with('-') => {
                bail!("bench-peers: unknown option `{flag}` (usage: bench-peers [SCENARIO] [--check])")
            }
            name if scenario.is_none() => scenario = Some(name),
            extra => bail!("bench-peers: one scenario only, got a second: `{extra}`"),
        }
    }
    let scenario = scenario.unwrap_or("aggressive");
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
    if check {
        let (rows, rows_late) = flight_rows(&log)?;
        check_figures(&lines, rows, rows_late)?;
    }
    Ok(())
}

/// `--check`: asserts the run's figures (see the module documentation) for a flight of
/// `rows` samples, `rows_late` of them from 20 s on; prints the derived figures as
/// `key: value` lines and names every failed property.
fn check_figures(lines: &[String], rows: usize, rows_late: usize) -> Result<()> {
    let get = |peer: &str, k: &str| -> Option<&str> {
        let key = format!("{peer}.{k}: ");
        lines.iter().find_map(|l| l.strip_prefix(key.as_str())).map(str::trim)
    };
    // The first `n` numbers of a figure (a value may be followed by a note in parentheses).
    let numbers = |peer: &str, k: &str, n: usize| -> Option<Vec<f64>> {
        let v: Vec<f64> = get(peer, k)?
            .split_whitespace()
            .take(n)
            .map(|x| x.parse().ok())
            .collect::<Option<_>>()?;
        (v.len() == n).then_some(v)
    };
    let mut failed = Vec::new();
    let mut fail = |msg: String| {
        eprintln!("xtask: check failed: {msg}");
        failed.push(msg);
    };
    for peer in PEERS {
        let one = |k: &str| numbers(peer, k, 1).map(|v| v[0]);
        match one("samples") {
            Some(n) if n == rows as f64 => {}
            other => fail(format!("{peer}: {other:?} samples run, the flight has {rows}")),
        }
        match numbers(peer, "final_attitude_deg", 3) {
            Some(a) if a.iter().all(|x| x.is_finite()) => {}
            other => fail(format!("{peer}: final attitude {other:?} is not three finite angles")),
        }
        if one("nonfinite_attitudes") != Some(0.0) {
            fail(format!(
                "{peer}: {:?} attitudes were not finite",
                get(peer, "nonfinite_attitudes")
            ));
        }
        match one("truth_samples") {
            Some(n) if n == rows_late as f64 && n > 0.0 => {}
            other => fail(format!(
                "{peer}: {other:?} samples compared with truth, the flight has {rows_late} from 20 s on"
            )),
        }
        for (k, bound) in [("truth_rms_deg", TRUTH_BOUNDS.rms), ("truth_max_deg", TRUTH_BOUNDS.max)]
        {
            match numbers(peer, k, 3) {
                Some(e) if e.iter().zip(bound).all(|(e, b)| *e <= b) => {}
                other => fail(format!(
                    "{peer}: {k} (roll pitch yaw) {other:?} beyond the bound {bound:?}"
                )),
            }
        }
    }
    match numbers("ekf2", "host_agreement_max_deg", 1) {
        Some(a) if a[0] <= HOST_AGREEMENT_MAX_DEG => {}
        other => fail(format!(
            "ekf2: M4F vs host EKF2 {other:?}° apart, more than {HOST_AGREEMENT_MAX_DEG}°"
        )),
    }
    let mean = |peer: &str| numbers(peer, "mean_instr", 1).map(|v| v[0]);
    match mean("ours") {
        Some(ours) if ours > 0.0 => {
            for peer in ["fusion-nav", "ekf2"] {
                let Some(theirs) = mean(peer) else {
                    fail(format!("{peer}: no mean_instr"));
                    continue;
                };
                println!("check.{peer}_per_ours_mean_instr: {:.1}", theirs / ours);
                if ours * COST_RATIO as f64 > theirs {
                    fail(format!(
                        "ours costs {ours} instructions per sample, more than 1/{COST_RATIO} of {peer}'s {theirs}"
                    ));
                }
            }
        }
        other => fail(format!("ours: mean_instr {other:?}")),
    }
    if !failed.is_empty() {
        bail!(
            "bench-peers --check: {} of its properties failed:\n  {}",
            failed.len(),
            failed.join("\n  ")
        );
    }
    println!(
        "check.result: pass ({} estimators × {rows} samples; attitudes finite and within {:?}° RMS / {:?}° max of truth from 20 s; M4F EKF2 = host EKF2 within {HOST_AGREEMENT_MAX_DEG}°; ours ≤ 1/{COST_RATIO} of each peer's mean instructions)",
        PEERS.len(),
        TRUTH_BOUNDS.rms,
        TRUTH_BOUNDS.max
    );
    Ok(())
}

/// Rows of a flight-log CSV, and the rows from 20 s after its first on (the samples
/// `bench-peers/src/truth.rs` compares, to the µs its build script rounds to).
fn flight_rows(log: &Path) -> Result<(usize, usize)> {
    let text =
        std::fs::read_to_string(log).with_context(|| format!("reading {}", log.display()))?;
    if text.lines().next().and_then(|h| h.split(',').next()) != Some("t") {
        bail!("{}: not a flight-log CSV (its first column is not `t`)", log.display());
    }
    let mut t0 = None;
    let (mut rows, mut late) = (0, 0);
    for (i, line) in text.lines().skip(1).filter(|l| !l.trim().is_empty()).enumerate() {
        let t: f64 =
            line.split(',').next().and_then(|t| t.trim().parse().ok()).with_context(|| {
                format!("{}: row {}: no time in its first column", log.display(), i + 1)
            })?;
        let us = (t * 1e6).round() as i64;
        let t0 = *t0.get_or_insert(us);
        rows += 1;
        if us - t0 >= TRUTH_FROM_US {
            late += 1;
        }
    }
    Ok((rows, late))
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

#[cfg(test)]
mod tests {
    use super::check_figures;

    /// The figures of a run that passes (a 100 s flight, the check's own derived keys aside).
    fn good() -> Vec<String> {
        let mut l = Vec::new();
        for (peer, mean) in [("ours", 870), ("fusion-nav", 60027), ("ekf2", 110667)] {
            l.push(format!("{peer}.samples: 10001"));
            l.push(format!("{peer}.mean_instr: {mean}"));
            l.push(format!("{peer}.final_attitude_deg: 0.23 -0.28 6.83"));
            l.push(format!("{peer}.truth_rms_deg: 0.3 0.2 0.8 (roll pitch yaw …, from 20 s)"));
            l.push(format!("{peer}.truth_max_deg: 1.3 1.1 2.8"));
            l.push(format!("{peer}.truth_samples: 8001"));
            l.push(format!("{peer}.nonfinite_attitudes: 0"));
        }
        l.push("ekf2.host_agreement_max_deg: 0.0001 (at 49 s; …)".into());
        l
    }

    fn with(key: &str, value: &str) -> Vec<String> {
        let mut l = good();
        let line = l.iter_mut().find(|l| l.starts_with(&format!("{key}: "))).expect("key");
        *line = format!("{key}: {value}");
        l
    }

    fn fails(lines: &[String], why: &str) {
        let e = check_figures(lines, 10001, 8001).expect_err("must fail").to_string();
        assert!(e.contains(why), "{e}");
    }

    #[test]
    fn a_good_run_passes() {
        check_figures(&good(), 10001, 8001).expect("passes");
    }

    #[test]
    fn each_property_fails_on_its_own() {
        fails(&with("fusion-nav.samples", "9000"), "fusion-nav: Some(9000.0) samples run");
        fails(&with("ekf2.final_attitude_deg", "NaN 0 0"), "ekf2: final attitude");
        fails(&with("ours.nonfinite_attitudes", "3"), "ours: Some(\"3\") attitudes");
        fails(&with("ours.truth_samples", "100"), "samples compared with truth");
        fails(&with("fusion-nav.truth_rms_deg", "0.3 2.5 0.8"), "fusion-nav: truth_rms_deg");
        fails(&with("ekf2.truth_max_deg", "1 1 45"), "ekf2: truth_max_deg");
        fails(&with("ekf2.host_agreement_max_deg", "0.5 (at 30 s)"), "M4F vs host EKF2");
        // 1/19 of fusion-nav's cost: the goal is 1/20.
        fails(&with("ours.mean_instr", "3160"), "more than 1/20 of fusion-nav");
        let mut missing = good();
        missing.retain(|l| !l.starts_with("ekf2.mean_instr"));
        fails(&missing, "ekf2: no mean_instr");
    }

    #[test]
    fn the_flight_length_is_the_logs() {
        check_figures(&good(), 10001, 8001).expect("passes");
        let e = check_figures(&good(), 10002, 8002).expect_err("a longer log").to_string();
        assert!(e.contains("the flight has 10002"), "{e}");
    }
}
