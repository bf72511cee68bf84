//! Static worst-case stack of the firmware's interrupt nest, from the ELF's code.
//!
//! Each function's frame is read from its prologue (`push`/`vpush` register lists
//! and `sub sp, #n`, summed over the whole function — conservative where a path
//! allocates conditionally); direct calls (`bl`, tail `b`/`b.w` to another symbol)
//! form the call graph; a handler's depth is its deepest call chain. Panic paths
//! end in the fail-safe (no return) and are left out. The firmware has no
//! recursion and no function-pointer calls on its handler paths; either is reported
//! if seen. Disassembly by `llvm-objdump` (skipped with a note when not installed).
use anyhow::{bail, Context, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

/// Handlers from the lowest priority to the highest (QEMU board, `board/qemu.rs`
/// `prio`): each may be preempted by every later one, so the worst case is all
/// of them nested. `UART_OVF` shares the sensor-RX priority and cannot nest with it.
pub const NEST: &[&str] = &["TELEMETRY_TASK", "TELEMETRY_TX", "IMU_TASK", "SENSOR_DATA", "GPS_RX"];
/// Exception entry with the FPU context active: 26 words + 1 alignment word.
pub const EXCEPTION_FRAME: u64 = 108;
/// Callees that only lead to the panic handler (which does not return).
const PANIC_PATHS: &[&str] = &[
    "panicking",
    "panic_fmt",
    "rust_begin_unwind",
    "slice_index_fail",
    "unwrap_failed",
    "expect_failed",
];

struct Func {
    frame: u64,
    calls: BTreeSet<String>,
    indirect: bool,
}

/// A handler's worst call chain.
pub struct Chain {
    /// Bytes, including the handler's own frame.
    pub bytes: u64,
    /// Function names (frame bytes) from the handler down.
    pub path: Vec<(String, u64)>,
    /// An indirect call (`blx rN`) was seen on the chain.
    pub indirect: bool,
}

fn reg_bytes(list: &str) -> u64 {
    list.split(',')
        .map(|r| {
            let r = r.trim();
            let w = if r.starts_with('d') { 8 } else { 4 };
            match r.split_once('-') {
                Some((a, b)) => {
                    let n = |s: &str| s[1..].parse::<u64>().unwrap_or(0);
                    (n(b) - n(a) + 1) * w
                }
                None => w,
            }
        })
        .sum()
}

fn parse(dis: &str) -> BTreeMap<String, Func> {
    let mut funcs: BTreeMap<String, Func> = BTreeMap::new();
    let mut cur: Option<String> = None;
    for line in dis.lines() {
        // `00000130 <IMU_TASK>:` starts a symbol; `$t`/`$d` mapping symbols do not.
        if let Some(name) = line.strip_suffix(">:").and_then(|l| l.split_once(" <")).map(|(_, n)| n)
        {
            if !name.starts_with('$') {
                cur = Some(name.to_string());
                funcs.entry(name.to_string()).or_insert(Func {
                    frame: 0,
                    calls: BTreeSet::new(),
                    indirect: false,
                });
            }
            continue;
        }
        let Some(f) = cur.as_ref().and_then(|c| funcs.get_mut(c)) else { continue };
        let mut parts = line.split('\t').skip(1);
        let (Some(op), args) = (parts.next().map(str::trim), parts.next().unwrap_or("")) else {
            continue;
        };
        match op {
            "push" | "push.w" | "vpush" => {
                if let Some(l) =
                    args.split_once('{').and_then(|(_, r)| r.split_once('}')).map(|(l, _)| l)
                {
                    f.frame += reg_bytes(l);
                }
            }
            "sub" | "sub.w" | "subw" if args.starts_with("sp, ") => {
                if let Some(n) = args
                    .rsplit_once('#')
                    .and_then(|(_, n)| n.split_whitespace().next())
                    .and_then(|n| n.parse::<u64>().ok())
                {
                    f.frame += n;
                }
            }
            "bl" | "b" | "b.w" => {
                // `bl 0x5cfa <name+0x10>`: a call/tail call when it leaves the function.
                if let Some(t) =
                    args.split_once('<').and_then(|(_, r)| r.split_once('>')).map(|(t, _)| t)
                {
                    let name = t.split('+').next().unwrap_or(t);
                    if !name.starts_with('$') && Some(name) != cur.as_deref() {
                        f.calls.insert(name.to_string());
                    }
                }
            }
            "blx" if args.trim_start().starts_with('r') => f.indirect = true,
            _ => {}
        }
    }
    funcs
}

/// The deepest call chain below a function: stack bytes, the chain (function, frame bytes),
/// and whether any function on it calls through a pointer.
type Deepest = (u64, Vec<(String, u64)>, bool);

fn deepest(
    funcs: &BTreeMap<String, Func>,
    name: &str,
    on_path: &mut Vec<String>,
    memo: &mut BTreeMap<String, Deepest>,
) -> Result<Deepest> {
    if let Some(m) = memo.get(name) {
        return Ok(m.clone());
    }
    if on_path.iter().any(|p| p == name) {
        bail!("recursion through {name}: no static bound");
    }
    let f = funcs.get(name).with_context(|| format!("no symbol {name} in the firmware"))?;
    on_path.push(name.to_string());
    let mut best = (0, Vec::new(), false);
    for c in &f.calls {
        if PANIC_PATHS.iter().any(|p| c.contains(p)) || !funcs.contains_key(c) {
            continue;
        }
        let d = deepest(funcs, c, on_path, memo)?;
        if d.0 > best.0 {
            best = d;
        }
    }
    on_path.pop();
    let mut path = vec![(name.to_string(), f.frame)];
    path.extend(best.1);
    let r = (f.frame + best.0, path, f.indirect || best.2);
    memo.insert(name.to_string(), r.clone());
    Ok(r)
}

/// Deepest chain of each handler in `NEST`; `None` when `llvm-objdump` is missing.
pub fn chains(elf: &Path) -> Result<Option<Vec<Chain>>> {
    let out = match Command::new("llvm-objdump")
        .args(["-d", "--no-show-raw-insn", "-C"])
        .arg(elf)
        .output()
    {
        Ok(o) if o.status.success() => o.stdout,
        Ok(o) => bail!("llvm-objdump failed: {}", String::from_utf8_lossy(&o.stderr)),
        Err(_) => return Ok(None),
    };
    let funcs = parse(&String::from_utf8_lossy(&out));
    let mut memo = BTreeMap::new();
    NEST.iter()
        .map(|h| {
            let (bytes, path, indirect) = deepest(&funcs, h, &mut Vec::new(), &mut memo)?;
            Ok(Chain { bytes, path, indirect })
        })
        .collect::<Result<Vec<_>>>()
        .map(Some)
}

/// Prints the per-handler chains and the nested bound as `key: value` lines.
/// Prints the static stack figures as `key: value` lines and returns them.
pub fn report(elf: &Path) -> Result<Vec<String>> {
    let Some(chains) = chains(elf)? else {
        println!("note: llvm-objdump not found: no static stack bound (apt-get install llvm)");
        return Ok(Vec::new());
    };
    let mut lines = Vec::new();
    let mut total = 0;
    for (h, c) in NEST.iter().zip(&chains) {
        let path: Vec<String> = c.path.iter().map(|(n, b)| format!("{} {b}", short(n))).collect();
        lines.push(format!(
            "fw_stack_chain_{}_bytes: {} ({}{})",
            h.to_lowercase(),
            c.bytes,
            path.join(" > "),
            if c.indirect { "; has indirect calls" } else { "" }
        ));
        total += c.bytes + EXCEPTION_FRAME;
    }
    lines.push(format!("fw_stack_isr_bound_bytes: {total} (all {} handlers nested, {EXCEPTION_FRAME} B exception frame each, panic paths excluded)", NEST.len()));
    for l in &lines {
        println!("{l}");
    }
    Ok(lines)
}

/// `wing_ahrs::ekf::Ekf::predict::h0123…` → `Ekf::predict`.
fn short(name: &str) -> String {
    let parts: Vec<&str> =
        name.split("::").filter(|p| !(p.starts_with('h') && p.len() == 17)).collect();
    parts[parts.len().saturating_sub(2)..].join("::")
}

#[cfg(test)]
mod tests {
    use super::*;

    // Hand-written llvm-objdump output: frames known by construction.
    const DIS: &str = "\
00000130 <IMU_TASK>:
     130:      \tpush\t{r4, r5, r6, r7, lr}
     132:      \tpush.w\t{r8, r9, r10, r11}
     13a:      \tvpush\t{d8, d9, d10, d11, d12, d13, d14, d15}
     13e:      \tsub.w\tsp, sp, #616
     142:      \tbl\t0x200 <leaf::h0123456789abcdef>
     146:      \tbl\t0x300 <core::panicking::panic::h0123456789abcdef>
     14a:      \tb\t0x160 <$t>

00000160 <$t>:
     160:      \tbl\t0x400 <mid>
     164:      \tbx\tlr

00000200 <leaf::h0123456789abcdef>:
     200:      \tpush\t{r7, lr}
     202:      \tsub\tsp, #8
     204:      \tpop\t{r7, pc}

00000300 <core::panicking::panic::h0123456789abcdef>:
     300:      \tsubw\tsp, sp, #2000

00000400 <mid>:
     400:      \tpush\t{r4, lr}
     402:      \tbl\t0x200 <leaf::h0123456789abcdef>
";

    #[test]
    fn frames_and_deepest_chain_from_prologues() {
        let funcs = parse(DIS);
        // 9 + 8 core registers (36 B) + d8–d15 (64 B) + 616.
        assert_eq!(funcs["IMU_TASK"].frame, 36 + 64 + 616);
        assert_eq!(funcs["leaf::h0123456789abcdef"].frame, 16);
        // The `$t` mapping symbol continues IMU_TASK: its call to `mid` belongs to it.
        assert!(funcs["IMU_TASK"].calls.contains("mid"));
        let (bytes, path, indirect) =
            deepest(&funcs, "IMU_TASK", &mut Vec::new(), &mut BTreeMap::new()).unwrap();
        // IMU_TASK > mid (8) > leaf (16); the 2,000-byte panic path is left out.
        assert_eq!(bytes, 716 + 8 + 16);
        assert_eq!(
            path.iter().map(|(n, _)| short(n)).collect::<Vec<_>>(),
            ["IMU_TASK", "mid", "leaf"]
        );
        assert!(!indirect);
    }

    #[test]
    fn recursion_has_no_bound() {
        let funcs = parse("00000100 <a>:\n 100: \tpush\t{r7, lr}\n 102: \tbl\t0x200 <b>\n\n00000200 <b>:\n 200: \tbl\t0x100 <a>\n");
        assert!(deepest(&funcs, "a", &mut Vec::new(), &mut BTreeMap::new()).is_err());
    }
}
