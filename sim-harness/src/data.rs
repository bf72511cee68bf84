//! Where the shared third-party data lives: `$WING_AHRS_DATA`, else
//! `<workspace root>/../shared/data`. Never copied into the repository.

use std::path::PathBuf;

/// The data directory, if it exists.
pub fn data_dir() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("WING_AHRS_DATA") {
        let p = PathBuf::from(p);
        return p.is_dir().then_some(p);
    }
    // sim-harness/ → workspace root → ../shared/data
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let p = root.join("..").join("shared").join("data");
    p.is_dir().then_some(p)
}

/// A real-flight log by file name (e.g. `px4_2014_flight_a.csv`), if present.
pub fn real_log(name: &str) -> Option<PathBuf> {
    let p = data_dir()?.join("real").join(name);
    p.is_file().then_some(p)
}

/// The two real PX4 flights shipped in shared/data.
pub const REAL_FLIGHTS: [&str; 2] = ["px4_2014_flight_a.csv", "px4_2014_flight_b.csv"];

/// Set (to anything) by `cargo xtask test`: a test that would skip for want of the shared
/// data or a tool that reads it (python3, pyubx2) fails instead.
pub const REQUIRE_ENV: &str = "WING_AHRS_REQUIRE_DATA";

/// Whether `python3` is here and can import `module` (the cross-check tools: pymavlink,
/// jsbsim, …).
pub fn python_has(module: &str) -> bool {
    std::process::Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// For tests: reports that `test` skips because `why`, or panics with that reason when
/// [`REQUIRE_ENV`] is set.
pub fn skip(test: &str, why: &str) {
    assert!(std::env::var_os(REQUIRE_ENV).is_none(), "{test}: {why} ({REQUIRE_ENV} is set)");
    eprintln!("SKIP {test}: {why}");
}

/// A file under the data directory (e.g. `real/raw/sample_log_small.ulg`), if present.
pub fn data_file(rel: &str) -> Option<PathBuf> {
    let p = data_dir()?.join(rel);
    p.is_file().then_some(p)
}
