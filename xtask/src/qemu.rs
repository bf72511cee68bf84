//! QEMU invocation for the mps2-an386 firmware and ELF size accounting.
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::{Command, Stdio};

/// Base QEMU arguments: AN386 (Cortex-M4F), semihosting on (defmt log + exit code).
pub fn base_args(elf: &Path) -> Vec<String> {
    ["-cpu", "cortex-m4", "-machine", "mps2-an386", "-display", "none", "-monitor", "none"]
        .iter()
        .map(|s| s.to_string())
        .chain([
            "-semihosting-config".into(),
            "enable=on,target=native".into(),
            "-kernel".into(),
            elf.display().to_string(),
        ])
        .collect()
}

/// Boots the firmware with no sensor input (it idles waiting for HIL records) for a
/// few seconds and prints its defmt log through `defmt-print` when installed.
pub fn run_alone(elf: &Path) -> Result<()> {
    let mut q = Command::new("qemu-system-arm");
    q.args(base_args(elf)).args(["-serial", "null", "-serial", "null", "-serial", "null"]);
    q.stdout(Stdio::piped());
    let mut child =
        q.spawn().context("starting qemu-system-arm (apt-get install qemu-system-arm)")?;
    let out = child.stdout.take().expect("piped");
    let decoder = Command::new("defmt-print").args(["-e"]).arg(elf).stdin(out).spawn();
    std::thread::sleep(std::time::Duration::from_secs(3));
    let _ = child.kill();
    let _ = child.wait();
    match decoder {
        Ok(mut d) => {
            let _ = d.wait();
        }
        Err(_) => {
            eprintln!("(install `defmt-print` to decode the defmt log: cargo install defmt-print)")
        }
    }
    Ok(())
}

/// Flash and static RAM of a firmware ELF, bytes.
pub struct Sizes {
    /// Vector table + code + read-only data + initialised-data image.
    pub flash: u64,
    /// .data + .bss (+ .uninit): static RAM, excluding the stack.
    pub ram: u64,
}

/// Reads section sizes from the ELF (allocated sections only).
pub fn sizes(elf: &Path) -> Result<Sizes> {
    use object::{Object, ObjectSection};
    let data = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let file = object::File::parse(&*data).context("parsing the firmware ELF")?;
    let (mut flash, mut ram) = (0, 0);
    for s in file.sections() {
        let name = s.name().unwrap_or("");
        match name {
            ".vector_table" | ".text" | ".rodata" => flash += s.size(),
            ".data" => {
                flash += s.size();
                ram += s.size();
            }
            ".bss" | ".uninit" => ram += s.size(),
            _ => {}
        }
    }
    if flash == 0 {
        bail!("no .text in {}", elf.display());
    }
    Ok(Sizes { flash, ram })
}
