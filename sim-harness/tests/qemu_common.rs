//! Shared setup for the QEMU tests: find qemu-system-arm and the firmware ELF, or
//! say clearly why the test is skipped. Build the firmware first: `cargo xtask build-fw`.
#![allow(dead_code)]

use std::path::PathBuf;

/// The firmware ELF, or None (with a printed reason) when QEMU or the build is missing.
/// Under `cargo xtask test` (which sets `WING_AHRS_REQUIRE_QEMU=1` after installing
/// QEMU and building the firmware) a missing piece is a failure, not a skip.
pub fn setup(test: &str) -> Option<PathBuf> {
    let required = std::env::var_os("WING_AHRS_REQUIRE_QEMU").is_some();
    let skip = |why: String| {
        assert!(!required, "{test}: {why}");
        eprintln!("SKIP {test}: {why}");
    };
    if !sim_harness::hil::qemu::available() {
        skip("qemu-system-arm not installed (apt-get install qemu-system-arm)".into());
        return None;
    }
    let fw = std::env::var_os("WING_AHRS_FW")
        .map(PathBuf::from)
        .unwrap_or_else(sim_harness::hil::cli::default_firmware);
    if !fw.exists() {
        skip(format!("firmware not built at {} (run `cargo xtask build-fw`)", fw.display()));
        return None;
    }
    Some(fw)
}
