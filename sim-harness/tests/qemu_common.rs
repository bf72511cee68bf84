//! Shared setup for the QEMU tests: find qemu-system-arm and the firmware ELF, or
//! say clearly why the test is skipped. Build the firmware first: `cargo xtask build-fw`.
#![allow(dead_code)]

use std::path::PathBuf;

/// The firmware ELF, or None (with a printed reason) when QEMU or the build is missing.
pub fn setup(test: &str) -> Option<PathBuf> {
    if !sim_harness::hil::qemu::available() {
        eprintln!("SKIP {test}: qemu-system-arm not installed (apt-get install qemu-system-arm)");
        return None;
    }
    let fw = std::env::var_os("WING_AHRS_FW").map(PathBuf::from).unwrap_or_else(sim_harness::hil::cli::default_firmware);
    if !fw.exists() {
        eprintln!("SKIP {test}: firmware not built at {} (run `cargo xtask build-fw`)", fw.display());
        return None;
    }
    Some(fw)
}
