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
    /// Short name: `qemu` or `f405`.
    pub fn name(self) -> &'static str {
        match self {
            Board::Qemu => "qemu",
            Board::F405 => "f405",
        }
    }
    /// The Cargo feature that selects the board.
    pub fn feature(self) -> &'static str {
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
    build_with(board, &[])
}

/// Like [`build`], with extra Cargo features (e.g. `boot-bench`); the ELF is kept as
/// `wing-ahrs-fw-<board>[-<feature>…]`.
pub fn build_with(board: Board, extra: &[&str]) -> Result<PathBuf> {
    let cross = crate::toolchain::Cross::ensure(&root())?;
    let mut c = cross.cargo("build");
    let mut features = format!("firmware,{}", board.feature());
    for f in extra {
        features.push(',');
        features.push_str(f);
    }
    // Without the default `euler` feature: the firmware runs the quaternion filter only.
    c.args(["--release", "-p", "wing-ahrs", "--bin", "wing-ahrs-fw", "--no-default-features"])
        .args(["--features", &features]);
    crate::run(c).context("firmware build failed")?;
    // Both boards build to the same cargo path: keep each board's ELF under its own name.
    let built = cross.artifact("release", "wing-ahrs-fw");
    let mut name = format!("wing-ahrs-fw-{}", board.name());
    for f in extra {
        name.push('-');
        name.push_str(f);
    }
    let kept = built.with_file_name(name);
    std::fs::copy(&built, &kept)
        .with_context(|| format!("copying {} to {}", built.display(), kept.display()))?;
    Ok(kept)
}

/// Builds the host harness (release) and returns the path of its binary.
pub fn build_harness() -> Result<PathBuf> {
    let root = root();
    let status = cargo()
        .current_dir(&root)
        .args(["build", "--release", "-p", "sim-harness"])
        .status()
        .context("building sim-harness")?;
    if !status.success() {
        bail!("sim-harness build failed");
    }
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    Ok(dir.join("release").join("sim-harness"))
}

/// `cargo xtask demo [LOG.csv]`: firmware in QEMU flying a simulated flight, live.
pub fn demo(args: &[String]) -> Result<()> {
    let elf = build(Board::Qemu)?;
    let harness = build_harness()?;
    let mut cmd = Command::new(harness);
    cmd.arg("hil").arg("--firmware").arg(&elf).arg("--live");
    if args.is_empty() {
        // Default: the simulator's general flight (thesis Flight 1), at real time with its
        // ground-station link on 127.0.0.1:14550 (`--mavlink-udp off --speed 4`: faster).
        cmd.args(["--scenario", "flight1"]);
    }
    cmd.args(args);
    let st = cmd.status().context("running sim-harness hil")?;
    if !st.success() {
        bail!("demo failed");
    }
    Ok(())
}

/// The deterministic Cortex-M4F budgets `cargo xtask test` asserts on the default bench flight
/// (key, largest allowed value): instructions under QEMU `-icount`, bytes.
pub const BUDGETS: &[(&str, u64)] = &[
    ("fw_predict_instructions", 600),
    ("fw_predict_update_instructions", 4_000),
    ("fw_stack_bytes", 4_096),
    // The static worst case: every handler preempting the next (`cargo xtask stack-bound`).
    ("fw_stack_isr_bound_bytes", 4_096),
    ("fw_flash_bytes", 128 * 1024),
    ("fw_static_ram_bytes", 16 * 1024),
    // Not a cost: the FPU's √ must give libm's bits, or firmware and host part (`costs.rs`).
    ("fw_sqrt_mismatches", 0),
];

/// The figures of a bench run, by key (the first number after `key:`).
pub type Figures = std::collections::BTreeMap<String, u64>;

/// Records a `key: value …` line's number.
fn note(figures: &mut Figures, line: &str) {
    if let Some((k, v)) = line.split_once(": ") {
        let num = v.split_whitespace().next().and_then(|n| n.parse().ok());
        if let (true, Some(n)) = (k.starts_with("fw_"), num) {
            figures.insert(k.to_string(), n);
        }
    }
}

/// Fails naming every budget exceeded or missing from `figures`.
pub fn check_budgets(figures: &Figures) -> Result<()> {
    let mut bad = Vec::new();
    for &(key, max) in BUDGETS {
        match figures.get(key) {
            Some(&v) if v <= max => println!("xtask: budget {key}: {v} ≤ {max}"),
            Some(&v) => bad.push(format!("{key} = {v} exceeds {max}")),
            None => bad.push(format!("{key} was not printed by the bench flight")),
        }
    }
    if !bad.is_empty() {
        bail!("firmware budgets: {}", bad.join("; "));
    }
    Ok(())
}

/// Where `bench-fw --doc` writes its table, between these markers.
const DOC: &str = "docs/firmware.md";
const DOC_BEGIN: &str = "<!-- bench-fw:begin -->";
const DOC_END: &str = "<!-- bench-fw:end -->";

/// `cargo xtask bench-fw [LOG.csv]`: cost and size figures as `key: value` lines; returns them.
/// `--doc` (default flight only): also writes them as a table into `docs/firmware.md`.
pub fn bench(args: &[String]) -> Result<Figures> {
    let doc = args.iter().any(|a| a == "--doc");
    if doc && args.len() > 1 {
        bail!(
            "bench-fw --doc takes no other arguments: the docs' figures are the default flight's"
        );
    }
    let lines = bench_lines(if doc { &[] } else { args })?;
    let mut figures = Figures::new();
    for l in &lines {
        note(&mut figures, l);
    }
    if doc {
        write_doc(&root().join(DOC), &lines)?;
    }
    Ok(figures)
}

/// Replaces the table between the markers of `path` with `lines` (`key: value (note)`),
/// the budget of each budgeted key beside it, and the commit measured.
fn write_doc(path: &Path, lines: &[String]) -> Result<()> {
    write_between(path, DOC_BEGIN, DOC_END, &doc_table(lines, &commit()))
}

/// Replaces what lies between the markers `begin` and `end` of the file `path` with `body`.
pub fn write_between(path: &Path, begin: &str, end: &str, body: &str) -> Result<()> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let (Some(a), Some(b)) = (text.find(begin), text.find(end)) else {
        bail!("{} has no {begin} … {end} markers", path.display());
    };
    let out = format!("{}{begin}\n{body}{}", &text[..a], &text[b..]);
    std::fs::write(path, out).with_context(|| format!("writing {}", path.display()))?;
    println!("xtask: wrote the figures into {}", path.display());
    Ok(())
}

/// The markdown table of the bench lines.
fn doc_table(lines: &[String], commit: &str) -> String {
    let mut t = format!(
        "Printed by `cargo xtask bench-fw --doc` for commit {commit} (aggressive flight, default configuration):\n\n| key | value | goal |\n|---|---|---|\n"
    );
    for l in lines {
        let Some((k, v)) = l.split_once(": ") else { continue };
        let goal = BUDGETS
            .iter()
            .find(|(b, _)| *b == k)
            .map_or("—".to_string(), |(_, m)| format!("≤ {m}"));
        t.push_str(&format!("| `{k}` | {} | {goal} |\n", v.replace('|', "\\|")));
    }
    t
}

/// What was measured: the short commit hash, "(with uncommitted changes)" if the tree is dirty.
pub fn commit() -> String {
    let git = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .current_dir(root())
            .output()
            .ok()
            .filter(|o| o.status.success())
    };
    let hash = git(&["rev-parse", "--short", "HEAD"])
        .map_or("unknown".into(), |o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    let dirty = git(&["status", "--porcelain", "--untracked-files=no"])
        .is_some_and(|o| !o.stdout.is_empty());
    if dirty {
        format!("{hash} (with uncommitted changes)")
    } else {
        hash
    }
}

/// Builds, flies the bench and prints its `key: value` lines as they come; returns the
/// `fw_*` and `gps_*` ones.
fn bench_lines(args: &[String]) -> Result<Vec<String>> {
    // Sizes of the shipped firmware; instruction counts from the same code plus the
    // boot-time micro-benchmarks.
    let shipped = build(Board::Qemu)?;
    let sizes = crate::qemu::sizes(&shipped)?;
    let elf = build_with(Board::Qemu, &["boot-bench"])?;
    let harness = build_harness()?;
    let mut cmd = Command::new(harness);
    cmd.arg("hil").arg("--firmware").arg(&elf).arg("--bench");
    if args.is_empty() {
        // Default: the aggressive simulated flight (worst-case ISR cost).
        cmd.args(["--scenario", "aggressive"]);
    }
    // Pass the output through as it comes and keep its figures.
    let mut child = cmd
        .args(args)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .context("running sim-harness hil --bench")?;
    let mut lines = Vec::new();
    let out = child.stdout.take().context("sim-harness hil --bench: no stdout")?;
    for line in std::io::BufRead::lines(std::io::BufReader::new(out)) {
        let line = line.context("reading sim-harness hil --bench output")?;
        println!("{line}");
        if line.starts_with("fw_") || line.starts_with("gps_") {
            lines.push(line);
        }
    }
    if !child.wait()?.success() {
        bail!("bench flight failed");
    }
    for l in
        [format!("fw_flash_bytes: {}", sizes.flash), format!("fw_static_ram_bytes: {}", sizes.ram)]
    {
        println!("{l}");
        lines.push(l);
    }
    // The measured stack figures (fw_stack_*) cover what this flight did; this is
    // the static worst case of every handler preempting the next, from the code.
    lines.extend(crate::stack::report(&shipped)?);
    Ok(lines)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doc_table_is_written_between_the_markers_only() {
        let dir = std::env::temp_dir().join(format!("xtask-doc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("firmware.md");
        let before = format!("# T\n\nintro\n{DOC_BEGIN}\nold table\n{DOC_END}\n\nafter\n");
        std::fs::write(&path, &before).unwrap();
        let lines = [
            "fw_predict_instructions: 554".to_string(),
            "fw_x_bytes: 7 (a | b)".into(),
            "noise".into(),
        ];
        write_doc(&path, &lines).unwrap();
        let out = std::fs::read_to_string(&path).unwrap();
        assert!(
            out.starts_with("# T\n\nintro\n") && out.ends_with(&format!("{DOC_END}\n\nafter\n"))
        );
        assert!(!out.contains("old table"));
        assert!(out.contains("| `fw_predict_instructions` | 554 | ≤ 600 |"), "{out}");
        assert!(out.contains("| `fw_x_bytes` | 7 (a \\| b) | — |"), "{out}");
        assert!(!out.contains("noise"));
        std::fs::write(&path, "no markers").unwrap();
        assert!(write_doc(&path, &lines).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bench_lines_are_parsed_and_budgets_fail_when_exceeded() {
        let mut f = Figures::new();
        for l in ["fw_predict_instructions: 476", "fw_stack_bytes: 3048 (boot 2532)", "hil: x: 1"] {
            note(&mut f, l);
        }
        assert_eq!(f.get("fw_predict_instructions"), Some(&476));
        assert_eq!(f.get("fw_stack_bytes"), Some(&3048));
        assert_eq!(f.len(), 2);
        // Missing keys fail; all within budget passes; one over fails.
        assert!(check_budgets(&f).is_err());
        for &(k, max) in BUDGETS {
            f.insert(k.into(), max);
        }
        assert!(check_budgets(&f).is_ok());
        f.insert("fw_predict_instructions".into(), 601);
        let e = check_budgets(&f).unwrap_err().to_string();
        assert!(e.contains("fw_predict_instructions = 601 exceeds 600"), "{e}");
    }
}
