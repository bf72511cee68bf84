//! Linker inputs for the firmware binary (bare-metal target only; a no-op on the host).
//! The board's `memory.x` and the interrupt-handler `device.x` are copied to OUT_DIR,
//! which is put on the linker search path for cortex-m-rt's `link.x`.
use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let target_os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target_os != "none" {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let board_dir = PathBuf::from("src/bin/wing-ahrs-fw/board");
    // Per-board linker fragments: QEMU mps2-an386 is the default board. No memory.x
    // may sit in the package root: the linker looks in its working directory first,
    // so one there would shadow the board's.
    let (memory, device) = if env::var_os("CARGO_FEATURE_BOARD_F405").is_some() {
        (board_dir.join("f405/memory.x"), None)
    } else {
        (board_dir.join("qemu_memory.x"), Some(board_dir.join("qemu_device.x")))
    };
    for (src, name) in [(Some(memory), "memory.x"), (device, "device.x")] {
        // A fragment left from a previous board build would shadow the PAC's own
        // device.x (F405: stm32f4 `rt`), so remove what this board does not supply.
        if src.is_none() {
            let _ = fs::remove_file(out.join(name));
        }
        if let Some(src) = src {
            if src.exists() {
                fs::copy(&src, out.join(name)).expect("copy linker fragment");
                println!("cargo:rerun-if-changed={}", src.display());
            }
        }
    }
    println!("cargo:rustc-link-search={}", out.display());
}
