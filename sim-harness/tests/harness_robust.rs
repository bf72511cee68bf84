//! Host tools never lose data or hide failure (issue 15, as a new user tried them): each
//! bad input gives a clear one-line error and exit 1, or a counted, stated skip — never a
//! panic, never an overwritten input, never a table of zeros with exit 0.
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sim-harness"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("harness_robust_{name}_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    bin().args(args).env("RUST_BACKTRACE", "1").output().unwrap()
}

/// Exit 1 with an `error:` line containing `needle`, no panic.
fn fails_with(o: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{needle}: {err}");
    assert!(err.starts_with("error: ") && !err.contains("panicked"), "{err}");
    assert!(err.contains(needle), "expected {needle:?} in: {err}");
}

/// A 20 s simulated flight (truth, GPS at 10 Hz, airspeed), as CSV text lines.
fn simulated(d: &Path) -> (PathBuf, Vec<String>) {
    let log = d.join("f1.csv");
    let o = bin()
        .args(["simulate", "flight1", "--duration", "20", "--seed", "5", "--out"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(o.status.success());
    let lines = std::fs::read_to_string(&log).unwrap().lines().map(String::from).collect();
    (log, lines)
}

fn col(header: &str, name: &str) -> usize {
    header.split(',').position(|c| c == name).unwrap()
}

fn replay(log: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut c = bin();
    c.arg("replay").arg(log).arg("--out").arg(out).args(extra);
    c.output().unwrap()
}

#[test]
fn output_over_an_input_is_refused_and_the_input_kept() {
    let d = dir("overwrite");
    let (log, _) = simulated(&d);
    let before = std::fs::read(&log).unwrap();
    fails_with(&replay(&log, &log, &[]), "is the input file");
    // The same file under another spelling.
    let other = d.join(".").join("f1.csv");
    fails_with(&replay(&log, &other, &[]), "is the input file");
    let o = run(&["import".as_ref(), log.as_os_str(), "--out".as_ref(), log.as_os_str()]);
    fails_with(&o, "is the input file");
    assert_eq!(std::fs::read(&log).unwrap(), before, "input changed");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn output_into_an_input_folder_is_refused() {
    // An InertialNav export is a folder of tables; writing into it would replace one.
    let d = dir("folder");
    let imu = d.join("IMU.txt");
    std::fs::write(&imu, " 0 0 0 0 0 0 0 -9.8\n 10 10 0 0 0 0 0 -9.8\n").unwrap();
    std::fs::write(d.join("GPSraw.txt"), " 5 47 8 400 0 0 0\n").unwrap();
    let o = run(&["import".as_ref(), d.as_os_str(), "--out".as_ref(), imu.as_os_str()]);
    fails_with(&o, "inside the input folder");
    let o = run(&["replay".as_ref(), d.as_os_str(), "--out".as_ref(), imu.as_os_str()]);
    fails_with(&o, "inside the input folder");
    assert!(std::fs::read_to_string(&imu).unwrap().starts_with(" 0 0 0"), "input changed");
    // A new file beside the tables overwrites nothing.
    let new = d.join("new.csv");
    let o = run(&["import".as_ref(), d.as_os_str(), "--out".as_ref(), new.as_os_str()]);
    assert!(o.status.success() && new.is_file(), "{}", String::from_utf8_lossy(&o.stderr));
    // A folder that is no export says so.
    let empty = dir("empty_folder");
    let o =
        run(&["import".as_ref(), empty.as_os_str(), "--out".as_ref(), d.join("x.csv").as_os_str()]);
    fails_with(&o, "not an InertialNav export");
    std::fs::remove_dir_all(&d).ok();
    std::fs::remove_dir_all(&empty).ok();
}

#[test]
fn closed_pipe_is_a_quiet_exit() {
    let mut child = bin()
        .args(["demo", "--duration", "30", "--pace-ms", "30"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    for _ in 0..2 {
        line.clear();
        out.read_line(&mut line).unwrap();
    }
    drop(out); // `| head -2`
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("panicked"), "{:?}: {err}", o.status);
}

#[test]
fn option_values_are_range_checked() {
    let d = dir("ranges");
    let (log, _) = simulated(&d);
    let out = d.join("e.csv");
    for (args, needle) in [
        (vec!["--bias-lambda=-1"], "--bias-lambda"),
        (vec!["--bias-lambda", "nan"], "--bias-lambda"),
        (vec!["--meas-sigma-deg", "0", "--fixed-r"], "--meas-sigma-deg"),
        (vec!["--noise-floor-deg", "nan"], "--noise-floor-deg"),
        (vec!["--gps-vel-sigma=-2"], "--gps-vel-sigma"),
        (vec!["--attitude-q", "inf"], "--attitude-q"),
        (vec!["--from", "nan"], "--from"),
    ] {
        fails_with(&replay(&log, &out, &args), needle);
    }
    // clap's own parse errors (exit 2) for values that are not numbers at all.
    let o = replay(&log, &out, &["--gps-latency", "7"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("auto, log or seconds"));
    fails_with(&run(&["demo".as_ref(), "--every".as_ref(), "0".as_ref()]), "--every");
    std::fs::remove_dir_all(&d).ok();
}

/// The GPS cells of each fix repeated on every following row until the next fix.
fn forward_filled(lines: &[String]) -> String {
    let h = &lines[0];
    let idx: Vec<usize> =
        ["gps_t", "vn", "ve", "vd", "gps_sacc"].iter().map(|c| col(h, c)).collect();
    let mut last: Option<Vec<String>> = None;
    let mut s = format!("{h}\n");
    for l in &lines[1..] {
        let mut f: Vec<String> = l.split(',').map(String::from).collect();
        if !f[idx[0]].is_empty() {
            last = Some(idx.iter().map(|&i| f[i].clone()).collect());
        } else if let Some(v) = &last {
            for (k, &i) in idx.iter().enumerate() {
                f[i] = v[k].clone();
            }
        }
        s.push_str(&f.join(","));
        s.push('\n');
    }
    s
}

fn health_gps(stdout: &str) -> usize {
    let h = stdout.lines().find(|l| l.starts_with("health:")).unwrap();
    let k = h.find("gps fixes ").unwrap() + "gps fixes ".len();
    h[k..].split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn forward_filled_gps_uses_each_epoch_once() {
    let d = dir("ffill");
    let (log, lines) = simulated(&d);
    let filled = d.join("filled.csv");
    std::fs::write(&filled, forward_filled(&lines)).unwrap();
    let n_fix = lines[1..]
        .iter()
        .filter(|l| !l.split(',').nth(col(&lines[0], "gps_t")).unwrap().is_empty())
        .count();
    let a = replay(&log, &d.join("a.csv"), &[]);
    let b = replay(&filled, &d.join("b.csv"), &[]);
    assert!(a.status.success() && b.status.success());
    let (sa, sb) = (String::from_utf8_lossy(&a.stdout), String::from_utf8_lossy(&b.stdout));
    assert_eq!(health_gps(&sa), n_fix);
    assert_eq!(health_gps(&sb), n_fix, "{sb}");
    let err = String::from_utf8_lossy(&b.stderr);
    assert!(err.contains(&format!("{} rows repeat", lines.len() - 1 - n_fix)), "{err}");
    // Same estimate as the clean log: identical tables.
    let table = |s: &str| {
        s.lines()
            .skip_while(|l| !l.contains("error vs truth"))
            .skip(1)
            .take(4)
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(table(&sa), table(&sb));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn meaningless_replays_exit_non_zero() {
    let d = dir("meaningless");
    let (log, lines) = simulated(&d);
    let h = &lines[0];
    let out = d.join("e.csv");
    let write = |name: &str, f: &dyn Fn(usize, Vec<String>) -> Vec<String>| {
        let p = d.join(name);
        let mut s = format!("{h}\n");
        for (k, l) in lines[1..].iter().enumerate() {
            s.push_str(&f(k, l.split(',').map(String::from).collect()).join(","));
            s.push('\n');
        }
        std::fs::write(&p, s).unwrap();
        p
    };
    let equal_t = write("equal_t.csv", &|_, mut f| {
        f[0] = "5".into();
        f
    });
    fails_with(&replay(&equal_t, &out, &[]), "same time");
    let negative_t = write("neg_t.csv", &|k, mut f| {
        f[0] = format!("{}", -1.0 + k as f64 * 0.01);
        f
    });
    fails_with(&replay(&negative_t, &out, &[]), "negative");
    let ax = col(h, "ax");
    let huge = write("huge.csv", &|_, mut f| {
        f[ax] = "1e30".into();
        f
    });
    fails_with(&replay(&huge, &out, &[]), "accepted 0 of");
    let va = col(h, "airspeed");
    let no_air = write("no_air.csv", &|_, mut f| {
        f[va] = String::new();
        f
    });
    fails_with(&replay(&no_air, &out, &["--model", "ekf2"]), "needs airspeed");
    fails_with(&replay(&log, &out, &["--from", "1e6"]), "no samples to compare");
    let o = run(&[
        "report".as_ref(),
        log.as_os_str(),
        "--from".as_ref(),
        "1e6".as_ref(),
        "--no-figures".as_ref(),
        "--out".as_ref(),
        d.join("rep").as_os_str(),
    ]);
    fails_with(&o, "no samples to compare");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn nan_truth_cells_are_skipped_and_counted() {
    let d = dir("nan_truth");
    let (_, lines) = simulated(&d);
    let roll = col(&lines[0], "true_roll");
    let mut s = format!("{}\n", lines[0]);
    for (k, l) in lines[1..].iter().enumerate() {
        let mut f: Vec<&str> = l.split(',').collect();
        if k == 1500 {
            f[roll] = "NaN";
        }
        s.push_str(&f.join(","));
        s.push('\n');
    }
    let p = d.join("nan.csv");
    std::fs::write(&p, s).unwrap();
    let o = replay(&p, &d.join("e.csv"), &[]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("(1 rows with a non-finite truth/ref cell skipped)"), "{out}");
    let roll_line = out.lines().find(|l| l.trim_start().starts_with("roll")).unwrap();
    assert!(!roll_line.contains("NaN"), "{roll_line}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn telemetry_qemu_refuses_firmware_for_another_board() {
    let d = dir("elf");
    // A 32-bit ARM ELF linked at the F405's flash (0x0800_0000): one PT_LOAD.
    let mut e = vec![0u8; 52 + 32];
    e[..4].copy_from_slice(b"\x7fELF");
    e[4] = 1; // 32-bit
    e[5] = 1; // little-endian
    e[18..20].copy_from_slice(&40u16.to_le_bytes()); // EM_ARM
    e[28..32].copy_from_slice(&52u32.to_le_bytes()); // e_phoff
    e[42..44].copy_from_slice(&32u16.to_le_bytes()); // e_phentsize
    e[44..46].copy_from_slice(&1u16.to_le_bytes()); // e_phnum
    e[52..56].copy_from_slice(&1u32.to_le_bytes()); // PT_LOAD
    e[64..68].copy_from_slice(&0x0800_0000u32.to_le_bytes()); // p_paddr
    e[72..76].copy_from_slice(&0x1000u32.to_le_bytes()); // p_memsz
    let f405 = d.join("f405.elf");
    std::fs::write(&f405, &e).unwrap();
    let o = run(&["telemetry".as_ref(), "--qemu".as_ref(), f405.as_os_str()]);
    fails_with(&o, "not the QEMU board's firmware");
    assert!(String::from_utf8_lossy(&o.stderr).contains("0x08000000"));
    let text = d.join("notes.txt");
    std::fs::write(&text, "hello").unwrap();
    fails_with(&run(&["telemetry".as_ref(), "--qemu".as_ref(), text.as_os_str()]), "not an ELF");
    std::fs::remove_dir_all(&d).ok();
}
