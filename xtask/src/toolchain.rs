//! Chooses and, when missing, installs a Cortex-M4F (`thumbv7em-none-eabihf`)
//! toolchain — so nobody has to do it by hand:
//!
//! 1. rustup's prebuilt target, if installed or installable (`rustup target add`);
//! 2. otherwise Debian's `rustc-web` + `rust-web-src` + `lld-22`, built with
//!    `RUSTC=/usr/bin/rustc RUSTC_BOOTSTRAP=1 -Zbuild-std=core` (its own std sources).
//!
//! `WING_AHRS_TOOLCHAIN=rustup|debian` forces a choice.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The Cortex-M4F target triple.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// Which toolchain builds for the target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// rustup's `rust-std` for the target.
    Rustup,
    /// Debian's rustc-web with `-Zbuild-std=core`.
    Debian,
}

/// A ready cross toolchain.
#[derive(Debug, Clone)]
pub struct Cross {
    pub kind: Kind,
    root: PathBuf,
}

const DEBIAN_RUSTC: &str = "/usr/bin/rustc";
const DEBIAN_CLIPPY: &str = "/usr/bin/cargo-clippy";
const DEBIAN_PACKAGES: &[&str] =
    &["rustc-web", "rust-web-src", "rust-web-llvm", "lld-22", "rust-web-clippy"];

impl Cross {
    /// Finds a working toolchain, installing one if needed.
    pub fn ensure(root: &Path) -> Result<Cross> {
        let forced = std::env::var("WING_AHRS_TOOLCHAIN").ok();
        let kind = match forced.as_deref() {
            Some("rustup") => {
                ensure_rustup_target()?;
                Kind::Rustup
            }
            Some("debian") => {
                ensure_debian()?;
                Kind::Debian
            }
            Some(other) => bail!("WING_AHRS_TOOLCHAIN={other}: expected `rustup` or `debian`"),
            None => {
                if ensure_rustup_target().is_ok() {
                    Kind::Rustup
                } else {
                    eprintln!("xtask: rustup cannot provide {TARGET}; falling back to Debian's rustc-web with -Zbuild-std=core");
                    ensure_debian()?;
                    Kind::Debian
                }
            }
        };
        Ok(Cross { kind, root: root.to_path_buf() })
    }

    /// A `cargo` command prepared for the target: `cargo <sub> --target … [-Zbuild-std=core]`,
    /// with the Debian toolchain's environment and its own target dir (so the two
    /// compilers never invalidate each other's artifacts).
    pub fn cargo(&self, sub: &str) -> Command {
        self.cargo_std(sub, "core")
    }

    /// [`Self::cargo`] for a program that also needs `std_crates` (e.g. `core,alloc`) built
    /// from source under the Debian toolchain (rustup's target ships them prebuilt).
    pub fn cargo_std(&self, sub: &str, std_crates: &str) -> Command {
        let mut c = Command::new(cargo_bin());
        c.current_dir(&self.root).arg(sub).args(["--target", TARGET]);
        if self.kind == Kind::Debian {
            c.env("RUSTC", DEBIAN_RUSTC)
                .env("RUSTC_BOOTSTRAP", "1")
                .arg(format!("-Zbuild-std={std_crates}"))
                .arg("-Zbuild-std-features=compiler-builtins-mem");
            c.env("CARGO_TARGET_DIR", self.target_dir());
        }
        c
    }

    /// `cargo clippy --target …` for the target. Debian's toolchain has its own clippy (its
    /// driver must match its rustc), run through its `cargo-clippy` with this cargo.
    pub fn clippy(&self) -> Command {
        if self.kind == Kind::Rustup {
            return self.cargo("clippy");
        }
        let mut c = Command::new(DEBIAN_CLIPPY);
        c.current_dir(&self.root).arg("clippy").args(["--target", TARGET]);
        c.env("CARGO", cargo_bin())
            .env("RUSTC", DEBIAN_RUSTC)
            .env("RUSTC_BOOTSTRAP", "1")
            .args(["-Zbuild-std=core", "-Zbuild-std-features=compiler-builtins-mem"])
            .env("CARGO_TARGET_DIR", self.target_dir());
        c
    }

    /// Where artifacts for the target land (`…/thumbv7em-none-eabihf/<profile>/`).
    pub fn target_dir(&self) -> PathBuf {
        let base = std::env::var_os("CARGO_TARGET_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| self.root.join("target"));
        match self.kind {
            Kind::Rustup => base,
            Kind::Debian => base.join("debian-rustc"),
        }
    }

    /// The path of a built binary for the target.
    pub fn artifact(&self, profile: &str, name: &str) -> PathBuf {
        self.target_dir().join(TARGET).join(profile).join(name)
    }
}

/// The cargo that runs xtask (so rustup proxies and versions match).
pub fn cargo_bin() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

fn rustup_has_target() -> bool {
    Command::new("rustup")
        .args(["target", "list", "--installed"])
        .output()
        .map(|o| {
            o.status.success()
                && String::from_utf8_lossy(&o.stdout).lines().any(|l| l.trim() == TARGET)
        })
        .unwrap_or(false)
}

fn ensure_rustup_target() -> Result<()> {
    if rustup_has_target() {
        return Ok(());
    }
    eprintln!("xtask: rustup target add {TARGET}");
    let mut child = Command::new("rustup")
        .args(["target", "add", TARGET])
        .stdout(Stdio::inherit())
        .stderr(Stdio::inherit())
        .spawn()
        .context("rustup is not available")?;
    let start = Instant::now();
    loop {
        if let Some(st) = child.try_wait()? {
            if st.success() && rustup_has_target() {
                return Ok(());
            }
            bail!("rustup target add {TARGET} failed");
        }
        if start.elapsed() > Duration::from_secs(240) {
            let _ = child.kill();
            bail!("rustup target add {TARGET} timed out");
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

fn debian_ready() -> bool {
    Path::new(DEBIAN_RUSTC).exists()
        && Path::new(DEBIAN_CLIPPY).exists()
        && Path::new("/usr/lib/rustlib/src/rust/library/core").exists()
        && (Path::new("/usr/bin/ld.lld-22").exists()
            || Path::new("/usr/lib/llvm-22/bin/ld.lld").exists())
}

fn ensure_debian() -> Result<()> {
    if debian_ready() {
        return Ok(());
    }
    apt_install(DEBIAN_PACKAGES)?;
    if !debian_ready() {
        bail!("Debian toolchain installed but rustc or its library sources were not found at the expected paths");
    }
    Ok(())
}

/// Installs Debian packages (the machines run as root); runs `apt-get update` once per process.
pub fn apt_install(pkgs: &[&str]) -> Result<()> {
    static UPDATED: std::sync::Once = std::sync::Once::new();
    let sudo = if is_root() { None } else { Some("sudo") };
    let run = |args: &[&str]| -> Result<()> {
        let mut c = match sudo {
            Some(s) => {
                let mut c = Command::new(s);
                c.arg("apt-get");
                c
            }
            None => Command::new("apt-get"),
        };
        c.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        let st = c.status().context("apt-get is not available")?;
        if !st.success() {
            bail!("apt-get {} failed", args.join(" "));
        }
        Ok(())
    };
    let mut res = Ok(());
    UPDATED.call_once(|| res = run(&["update", "-qq"]));
    res?;
    let mut args = vec!["install", "-y", "-qq", "--no-install-recommends"];
    args.extend_from_slice(pkgs);
    eprintln!("xtask: apt-get install {}", pkgs.join(" "));
    run(&args)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

/// Whether `cmd` is on the PATH.
pub fn have(cmd: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {cmd} >/dev/null 2>&1")])
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// Installs the Debian packages `pkgs` unless `present()` already says they are there.
pub fn ensure_apt(what: &str, present: impl Fn() -> bool, pkgs: &[&str]) -> Result<()> {
    if present() {
        return Ok(());
    }
    eprintln!("xtask: {what} missing");
    apt_install(pkgs)?;
    if !present() {
        bail!("{what}: installed {} but it is still not found", pkgs.join(" "));
    }
    Ok(())
}

/// libclang (for bindgen) and a host C++ compiler: the `ekf2` peer of `sim-harness compare`
/// builds PX4's EKF2 C++ from source.
pub fn ensure_host_cxx() -> Result<()> {
    let libclang = || {
        std::fs::read_dir("/usr/lib").into_iter().flatten().flatten().any(|d| {
            let n = d.file_name();
            let n = n.to_string_lossy();
            n.starts_with("llvm-") && d.path().join("lib/libclang.so").exists()
        }) || Path::new("/usr/lib/x86_64-linux-gnu/libclang.so").exists()
    };
    ensure_apt("libclang (bindgen, for the ekf2 peer)", libclang, &["libclang-dev"])?;
    ensure_apt("a C++ compiler (for the ekf2 peer)", || have("c++") || have("g++"), &["g++"])
}

/// Debian's bare-metal ARM C++ compiler (`arm-none-eabi-g++`) with newlib's C headers and
/// its libstdc++ headers: `cargo xtask bench-peers` cross-compiles PX4's EKF2 C++ (the `ekf2`
/// crate's build script: cc with `arm-none-eabi-g++`, bindgen for the target), plus libclang.
/// Headers only: no C or C++ library is linked, so neither newlib's multilib libraries
/// (`libnewlib-arm-none-eabi`) nor libstdc++'s (`libstdc++-arm-none-eabi-newlib`, 1.5 GB
/// installed) are installed — about 50 MB to download instead of 410 MB.
pub fn ensure_arm_cxx() -> Result<()> {
    ensure_host_cxx()?;
    let present = || {
        have("arm-none-eabi-g++")
            && Path::new("/usr/lib/arm-none-eabi/include/newlib.h").exists()
            && std::fs::read_dir("/usr/include/newlib/c++")
                .map(|mut d| d.next().is_some())
                .unwrap_or(false)
    };
    ensure_apt(
        "the arm-none-eabi C++ compiler and headers (for the ekf2 M4F bench)",
        present,
        &["gcc-arm-none-eabi", "libnewlib-dev", "libstdc++-arm-none-eabi-dev"],
    )
}

/// Installs `qemu-system-arm` (Debian) if missing.
pub fn ensure_qemu() -> Result<()> {
    if !have("qemu-system-arm") {
        apt_install(&["qemu-system-arm"])?;
    }
    Ok(())
}

/// Installs a Python package from PyPI if `import module` fails.
pub fn ensure_python_module(module: &str, package: &str) -> Result<()> {
    let importable = |m: &str| {
        Command::new("python3")
            .args(["-c", &format!("import {m}")])
            .status()
            .map(|s| s.success())
            .unwrap_or(false)
    };
    if importable(module) {
        return Ok(());
    }
    eprintln!("xtask: pip install {package}");
    let st = Command::new("python3")
        .args(["-m", "pip", "install", "-q", package])
        .status()
        .context("python3/pip is not available")?;
    if !st.success() || !importable(module) {
        bail!("could not install the Python package {package}");
    }
    Ok(())
}
