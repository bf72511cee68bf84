//! `cargo xtask bench-host`: host cost per IMU sample in x86 instructions (callgrind), for
//! ours, fusion-nav and PX4 EKF2 on the same logs. Unlike `compare`'s ns (fastest of 15 passes
//! on a shared machine, ±25 % between runs), an instruction count repeats to the instruction,
//! so the estimator issue's "≤ 1/20 of fusion-nav's cost" can be checked, not just read.
//!
//! Per sample = (count of 3 passes − count of 1 pass) / (2 × rows): log generation, start-up
//! and exit cancel. The harness adapter (f64 row → f32 call) is counted for every estimator.

use crate::fw::{root, write_between};
use crate::toolchain::{cargo_bin, ensure_apt, have};
use anyhow::{bail, Context, Result};
use std::process::Command;

/// The estimators, as `cost_profile` finds them (a substring of compare's row name).
const ESTIMATORS: [(&str, &str); 3] =
    [("wing-ahrs", "ours"), ("fusion-nav", "fusion-nav 0.1"), ("PX4 EKF2", "PX4 EKF2")];

/// Default logs: still air, wind, aerobatics, the kinematic turns; two JSBSim flights and the
/// real logs when present (`cargo run -p sim-harness -- jsbsim`, `../shared/data`), else
/// reported as not run.
const DEFAULT_LOGS: [&str; 10] = [
    "level",
    "aggressive",
    "flight2+wind=6@90",
    "aerobatics",
    "aerobatics_wind5",
    "turns",
    "jsbsim:c172_turns",
    "jsbsim:t6_aerobatics",
    "real_a",
    "real_b",
];

/// The goal: ours ≤ this fraction of fusion-nav's instructions per sample.
const GOAL: f64 = 1.0 / 20.0;

const DOC: &str = "docs/host-cost.md";
const DOC_BEGIN: &str = "<!-- bench-host:begin -->";
const DOC_END: &str = "<!-- bench-host:end -->";

/// One log's counts, instructions per sample, in `ESTIMATORS` order.
struct Row {
    log: String,
    per_sample: Vec<f64>,
}

/// `cargo xtask bench-host [--doc] [--check] [LOG…]`: prints a table; `--doc` writes it into
/// docs/host-cost.md; `--check` fails if ours is over 1/20 of fusion-nav on any log.
pub fn run(args: &[String]) -> Result<()> {
    let doc = args.iter().any(|a| a == "--doc");
    let check = args.iter().any(|a| a == "--check");
    let mut logs: Vec<String> = args.iter().filter(|a| !a.starts_with("--")).cloned().collect();
    if let Some(bad) = args.iter().find(|a| a.starts_with("--") && *a != "--doc" && *a != "--check")
    {
        bail!("bench-host: unknown option `{bad}` (usage: bench-host [--doc] [--check] [LOG…])");
    }
    if logs.is_empty() {
        logs = DEFAULT_LOGS.iter().map(|s| s.to_string()).collect();
    }
    ensure_apt(
        "valgrind (callgrind counts the host instructions)",
        || have("valgrind"),
        &["valgrind"],
    )?;
    let exe = build_profiler()?;
    let mut rows = Vec::new();
    for log in &logs {
        let mut per_sample = Vec::new();
        for (name, _) in ESTIMATORS {
            let (i1, n) = match count(&exe, log, 1, name)? {
                Counted::Done(i, n) => (i, n),
                Counted::Unavailable(why) => {
                    println!("bench-host: {log}: not run ({why})");
                    break;
                }
            };
            let Counted::Done(i3, _) = count(&exe, log, 3, name)? else {
                bail!("{log} was there for one pass and not for three")
            };
            per_sample.push(i3.saturating_sub(i1) as f64 / (2 * n) as f64);
        }
        if per_sample.len() < ESTIMATORS.len() {
            continue;
        }
        println!(
            "bench-host: {log}: ours {:.0}, fusion-nav {:.0}, PX4 EKF2 {:.0} instructions/sample (ours = 1/{:.1} of fusion-nav)",
            per_sample[0],
            per_sample[1],
            per_sample[2],
            per_sample[1] / per_sample[0]
        );
        rows.push(Row { log: log.clone(), per_sample });
    }
    let table = table(&rows);
    print!("{table}");
    if doc {
        write_between(&root().join(DOC), DOC_BEGIN, DOC_END, &table)?;
    }
    let over: Vec<&str> = rows
        .iter()
        .filter(|r| r.per_sample[0] > GOAL * r.per_sample[1])
        .map(|r| r.log.as_str())
        .collect();
    if check && !over.is_empty() {
        bail!("host cost over 1/20 of fusion-nav's instructions on: {}", over.join(", "));
    }
    Ok(())
}

/// Builds the harness's `cost_profile` example (release, with debug info) and returns it.
fn build_profiler() -> Result<std::path::PathBuf> {
    let r = root();
    let mut c = Command::new(cargo_bin());
    c.current_dir(&r).args(["build", "--release", "-q", "-p", "sim-harness", "--example"]);
    c.arg("cost_profile");
    crate::run(c)?;
    let exe = r.join("target/release/examples/cost_profile");
    if !exe.exists() {
        bail!("built cost_profile but {} is not there", exe.display());
    }
    Ok(exe)
}

/// What one callgrind run gave.
enum Counted {
    /// Total instructions and the log's rows.
    Done(u64, u64),
    /// The log is not available here (no JSBSim output, no ../shared/data): why.
    Unavailable(String),
}

/// Callgrind's total instruction count of `passes` passes of `estimator` over `log`.
fn count(exe: &std::path::Path, log: &str, passes: u32, estimator: &str) -> Result<Counted> {
    let out = Command::new("valgrind")
        .args(["--tool=callgrind", "--callgrind-out-file=/dev/null"])
        .arg(exe)
        .args([log, &passes.to_string(), estimator])
        .output()
        .context("could not start valgrind")?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(3) {
        return Ok(Counted::Unavailable(last_line(&stderr).to_string()));
    }
    if !out.status.success() {
        bail!("cost_profile {log} {passes} `{estimator}` failed: {}", last_line(&stderr));
    }
    let refs = stderr
        .lines()
        .find_map(|l| l.split_once("I   refs:").map(|(_, v)| v.trim().replace(',', "")))
        .and_then(|v| v.parse::<u64>().ok())
        .with_context(|| format!("no `I refs` in callgrind's output for {log}"))?;
    let rows = stdout
        .split_once(": ")
        .and_then(|(_, r)| r.split_whitespace().next())
        .and_then(|n| n.parse::<u64>().ok())
        .filter(|n| *n > 0)
        .with_context(|| format!("cost_profile printed no row count for {log}: {stdout}"))?;
    Ok(Counted::Done(refs, rows))
}

fn last_line(s: &str) -> &str {
    s.lines().rev().find(|l| !l.trim().is_empty() && !l.starts_with("==")).unwrap_or("")
}

/// The markdown table, with the goal line per log.
fn table(rows: &[Row]) -> String {
    let mut t = format!(
        "Printed by `cargo xtask bench-host --doc` for commit {} (x86-64 instructions per IMU sample counted by callgrind, the harness adapter included; deterministic, unlike ns):\n\n| log | ours | fusion-nav 0.1 | PX4 EKF2 | ours / fusion-nav | goal ≤ 1/20 |\n|---|---|---|---|---|---|\n",
        crate::fw::commit()
    );
    for r in rows {
        let [o, f, e] = [r.per_sample[0], r.per_sample[1], r.per_sample[2]];
        let pass = if o <= GOAL * f { "PASS" } else { "FAIL" };
        t.push_str(&format!(
            "| `{}` | {o:.0} | {f:.0} | {e:.0} | 1/{:.1} | {pass} |\n",
            r.log,
            f / o
        ));
    }
    t
}
