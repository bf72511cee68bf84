//! Boots the firmware in `qemu-system-arm -machine mps2-an386` with its three HIL
//! UARTs on local TCP sockets (the harness listens; QEMU connects).

use anyhow::{bail, Context, Result};
use std::io::Read;
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running QEMU with the sensor, GPS and telemetry links connected.
pub struct Qemu {
    /// The QEMU process.
    pub child: Child,
    /// UART0: sensor records (host → firmware).
    pub sensor: TcpStream,
    /// UART1: GPS bytes (host → firmware).
    pub gps: TcpStream,
    /// UART2: MAVLink telemetry (firmware → host).
    pub telemetry: Box<dyn Read + Send>,
    _fifo_dir: Option<PathBuf>,
    /// Semihosting output (defmt frames), collected in the background.
    pub defmt: std::thread::JoinHandle<Vec<u8>>,
}

/// Whether `qemu-system-arm` can be run.
pub fn available() -> bool {
    Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn accept(l: &TcpListener, what: &str, deadline: Instant, child: &mut Child) -> Result<TcpStream> {
    l.set_nonblocking(true)?;
    loop {
        match l.accept() {
            Ok((s, _)) => {
                s.set_nonblocking(false)?;
                s.set_nodelay(true)?;
                return Ok(s);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if let Some(st) = child.try_wait()? {
                    bail!("qemu-system-arm exited ({st}) before connecting its {what} UART");
                }
                if Instant::now() > deadline {
                    bail!("qemu-system-arm did not connect its {what} UART within 20 s");
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            Err(e) => return Err(e.into()),
        }
    }
}

/// Starts QEMU on `elf`. `icount`: deterministic instruction counting
/// (`-icount shift=0,sleep=off`: 1 instruction = 1 ns of virtual time).
/// `telemetry_fifo`: telemetry through a Unix socket (≈ 200 KiB of kernel buffer,
/// not auto-tuned) instead of TCP, whose multi-megabyte buffers hide back-pressure.
pub fn start(elf: &Path, icount: bool, telemetry_fifo: bool) -> Result<Qemu> {
    if !elf.exists() {
        bail!("firmware ELF {} not found (build it: cargo xtask build-fw)", elf.display());
    }
    check_qemu_elf(elf)?;
    let listeners: Vec<TcpListener> =
        (0..3).map(|_| TcpListener::bind("127.0.0.1:0")).collect::<std::io::Result<_>>()?;
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args([
        "-cpu",
        "cortex-m4",
        "-machine",
        "mps2-an386",
        "-display",
        "none",
        "-monitor",
        "none",
    ]);
    cmd.args(["-semihosting-config", "enable=on,target=native"]);
    if icount {
        cmd.args(["-icount", "shift=0,sleep=off"]);
    }
    let mut fifo_dir = None;
    let mut unix = None;
    for (i, l) in listeners.iter().enumerate() {
        if i == 2 && telemetry_fifo {
            let dir = std::env::temp_dir().join(format!(
                "wing-ahrs-hil-{}-{}",
                std::process::id(),
                l.local_addr()?.port()
            ));
            std::fs::create_dir_all(&dir)?;
            let path = dir.join("tlm.sock");
            let _ = std::fs::remove_file(&path);
            unix = Some(
                std::os::unix::net::UnixListener::bind(&path)
                    .context("binding the telemetry Unix socket")?,
            );
            cmd.arg("-chardev").arg(format!("socket,id=u{i},path={}", path.display()));
            fifo_dir = Some(dir);
        } else {
            let port = l.local_addr()?.port();
            cmd.arg("-chardev").arg(format!("socket,id=u{i},host=127.0.0.1,port={port}"));
        }
        cmd.arg("-serial").arg(format!("chardev:u{i}"));
    }
    cmd.arg("-kernel").arg(elf);
    cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::inherit());
    let mut child = cmd
        .spawn()
        .context("starting qemu-system-arm (install it: apt-get install qemu-system-arm)")?;
    let deadline = Instant::now() + Duration::from_secs(20);
    let sensor = accept(&listeners[0], "sensor", deadline, &mut child)?;
    let gps = accept(&listeners[1], "GPS", deadline, &mut child)?;
    let telemetry: Box<dyn Read + Send> = match &unix {
        Some(u) => Box::new(u.accept().context("accepting the telemetry Unix socket")?.0),
        None => Box::new(accept(&listeners[2], "telemetry", deadline, &mut child)?),
    };
    let mut out = child.stdout.take().expect("piped stdout");
    let defmt = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out.read_to_end(&mut v);
        v
    });
    Ok(Qemu { child, sensor, gps, telemetry, _fifo_dir: fifo_dir, defmt })
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        if let Some(d) = &self._fifo_dir {
            let _ = std::fs::remove_dir_all(d);
        }
    }
}

/// The QEMU board's firmware: a 32-bit little-endian ARM ELF whose vector table (the lowest
/// loaded address) lies in the mps2-an386 code RAM at 0x0 (the F405 build's is at flash
/// 0x0800_0000). Hand-read header fields: three of them do not justify an ELF crate.
pub fn check_qemu_elf(elf: &Path) -> Result<()> {
    let b = std::fs::read(elf).with_context(|| format!("cannot read {}", elf.display()))?;
    let not = |why: &str| {
        anyhow::anyhow!(
            "{} is not the QEMU board's firmware ({why}); build it with `cargo xtask build-fw`",
            elf.display()
        )
    };
    if b.len() < 52 || &b[..4] != b"\x7fELF" {
        return Err(not("not an ELF file"));
    }
    if b[4] != 1 || b[5] != 1 {
        return Err(not("not a 32-bit little-endian ELF"));
    }
    let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]);
    let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    if u16_at(18) != 40 {
        return Err(not("not an ARM executable"));
    }
    let (phoff, phentsize, phnum) = (u32_at(28) as usize, u16_at(42) as usize, u16_at(44) as usize);
    let lowest = (0..phnum)
        .filter_map(|i| {
            let o = phoff.checked_add(i.checked_mul(phentsize)?)?;
            (o + 32 <= b.len() && u32_at(o) == 1 && u32_at(o + 20) > 0).then(|| u32_at(o + 12))
        })
        .min()
        .ok_or_else(|| not("no loadable segment"))?;
    if lowest >= 0x0040_0000 {
        return Err(not(&format!(
            "its code is linked at {lowest:#010x}, the mps2-an386 boots from 0x00000000"
        )));
    }
    Ok(())
}
