//! The headline table of `sim-harness compare --headline FILE`: ours against the two peers
//! a fixed-wing user would pick (fusion-nav, PX4 EKF2), accuracy per flight class and cost.
//!
//! Accuracy: roll / pitch RMS pooled over every sample of every scenario of the class
//! (degrees; real logs: agreement with the autopilot). Host cost: ns per IMU sample over
//! all scenarios of the run. M4F: read from `target/bench-peers.txt` (written by
//! `cargo xtask bench-peers`) when it exists.

use crate::compare::{command_line, find, CompareArgs, FlightClass, ScenarioResult};
use crate::peers;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// A flight on which an estimator's tilt RMS exceeds this, rad (5°), is a divergence: it is
/// listed in the estimator's own column, not pooled as its accuracy (docs/peers.md says why).
pub const DIVERGED_TILT: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Whether `r` diverged on its flight (simulated flights only: a real log's reference is
/// itself off by degrees).
fn diverged(sc: &ScenarioResult, r: &crate::compare::Row) -> bool {
    sc.against == crate::compare::Against::Truth && r.stats.tilt_total()[0].rms > DIVERGED_TILT
}

/// Where `cargo xtask bench-peers` leaves its `key: value` figures.
pub const BENCH_FILE: &str = "target/bench-peers.txt";

/// The three estimators of the headline, by table name, with their bench-file prefix.
fn estimators(results: &[ScenarioResult]) -> Vec<(String, &'static str)> {
    let ours =
        results.first().and_then(|s| s.rows.first()).map_or("ours".into(), |r| r.name.clone());
    vec![
        (ours, "ours"),
        (peers::fusion_nav::NAME.to_string(), "fusion-nav"),
        (peers::px4_ekf2::NAME.to_string(), "ekf2"),
    ]
}

/// `key: value` lines of a bench file (missing file: empty).
pub fn bench_figures(path: &Path) -> BTreeMap<String, String> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| {
            l.split_once(':').map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        })
        .collect()
}

/// The headline markdown table.
pub fn markdown(results: &[ScenarioResult], args: &CompareArgs) -> String {
    let bench = bench_figures(Path::new(BENCH_FILE));
    let mut s = String::new();
    let _ = writeln!(s, "| estimator | {} | diverged (tilt RMS > 5°, not pooled) | host ns/sample | × fusion-nav | M4F instructions/sample: mean / GPS sample / max | flash | static RAM | stack |", FlightClass::ALL.map(|c| c.label()).join(" | "));
    let _ =
        writeln!(s, "|---|{}---|---|---|---|---|---|---|", "---|".repeat(FlightClass::ALL.len()));
    // Mean over scenarios of the per-sample cost measured on each.
    let cost = |name: &str| {
        let v: Vec<f64> =
            results.iter().filter_map(|sc| find(sc, name)).map(|r| r.stats.ns_per_step()).collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    let fnav_cost = cost(peers::fusion_nav::NAME);
    for (name, key) in estimators(results) {
        let mut cells = Vec::new();
        let mut apart = Vec::new();
        for class in FlightClass::ALL {
            let (mut ss, mut n, mut synth) = ([0.0; 2], 0usize, false);
            for sc in results.iter().filter(|sc| sc.class == class) {
                if let Some(r) = find(sc, &name) {
                    if diverged(sc, r) {
                        let tilt = r.stats.tilt_total()[0].rms.to_degrees();
                        apart.push(format!("{} ({tilt:.0}°)", sc.name));
                        continue;
                    }
                    let (q, k) = r.stats.rp_sums();
                    ss[0] += q[0];
                    ss[1] += q[1];
                    n += k;
                    synth |= r.synthetic_position;
                }
            }
            cells.push(if n == 0 {
                "—".to_string()
            } else {
                let rms = ss.map(|q| (q / n as f64).sqrt().to_degrees());
                format!("{:.2}° / {:.2}°{}", rms[0], rms[1], if synth { " †" } else { "" })
            });
        }
        let b = |k: &str| bench.get(&format!("{key}.{k}")).cloned().unwrap_or_else(|| "—".into());
        // EKF2 allocates its state: its heap's peak joins the static RAM.
        let ram = match bench.get(&format!("{key}.heap_peak_bytes")) {
            Some(h) => format!("{} + {h} heap", b("static_ram_bytes")),
            None => b("static_ram_bytes"),
        };
        let c = cost(&name);
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {c:.0} | {:.3} | {} / {} / {} | {} | {} | {} |",
            cells.join(" | "),
            if apart.is_empty() { "none".to_string() } else { apart.join(", ") },
            c / fnav_cost,
            b("mean_instr"),
            b("gps_instr"),
            b("max_instr"),
            b("flash_bytes"),
            ram,
            b("stack_bytes"),
        );
    }
    let _ = writeln!(s, "\nRoll / pitch RMS from the common settled time, pooled over the class's flights (a flight where the estimator diverged is left out of its pool and named in its own column, tilt RMS in brackets); real logs: agreement with the autopilot's attitude. Generated by `{}`. M4F: instructions, not cycles (QEMU `-icount`), from `cargo xtask bench-peers`{}. `†` the peers were fed a GNSS position integrated from the fixes' velocities.", command_line(args), if bench.is_empty() { " (not run: no target/bench-peers.txt)" } else { "" });
    let _ = writeln!(s, "\n{}", ahead_line(results));
    let _ = writeln!(s, "\nFlights per class:");
    for class in FlightClass::ALL {
        let names: Vec<&str> =
            results.iter().filter(|sc| sc.class == class).map(|sc| sc.name.as_str()).collect();
        if !names.is_empty() {
            let _ = writeln!(s, "- {}: {}", class.label(), names.join(", "));
        }
    }
    s
}

/// "Ahead on N of M flights": the flights where ours has the lowest roll/pitch RMS of the
/// three, and the ones each peer has it, by name.
pub fn ahead_line(results: &[ScenarioResult]) -> String {
    let names = estimators(results);
    let mut best: Vec<Vec<&str>> = vec![Vec::new(); names.len()];
    let mut m = 0;
    for sc in results {
        let rms: Option<Vec<f64>> =
            names.iter().map(|(n, _)| find(sc, n).map(|r| r.stats.rp_rms())).collect();
        let Some(rms) = rms else { continue };
        m += 1;
        let k = (0..rms.len()).min_by(|&a, &b| rms[a].total_cmp(&rms[b])).unwrap_or(0);
        best[k].push(sc.name.as_str());
    }
    let mut s = format!(
        "Ours ({}) is ahead (lowest roll/pitch RMS of the three) on {} of {m} flights",
        names[0].0,
        best[0].len()
    );
    for (k, (name, _)) in names.iter().enumerate().skip(1) {
        if !best[k].is_empty() {
            s += &format!("; {name} on {} ({})", best[k].len(), best[k].join(", "));
        }
    }
    s + "."
}

/// A peer whose tilt RMS on a flight is over this many times ours needs a reason in
/// docs/peers.md's reasons table (issue 33's 2× rule).
pub const RATIO_LIMIT: f64 = 2.0;

/// The two peers of the 2× rule, by table name and the short name the tables use.
pub const RULE_PEERS: [(&str, &str); 2] =
    [(peers::fusion_nav::NAME, "fusion-nav"), (peers::px4_ekf2::NAME, "EKF2")];

/// The per-flight table of the 2× rule: for each flight, ours and each peer's tilt RMS
/// (roll / pitch RMS beside it), the peer's tilt RMS over ours, and the peers that are over
/// [`RATIO_LIMIT`]. Only a peer worse than ours counts. Tilt, not roll and pitch, is the
/// ratio's measure: it stays defined through the vertical figures of aerobatic flights,
/// where Euler roll does not.
pub fn ratio_table(results: &[ScenarioResult], args: &CompareArgs) -> String {
    let mut s = String::new();
    let ours =
        results.first().and_then(|s| s.rows.first()).map_or("ours".into(), |r| r.name.clone());
    let cell = |r: &crate::compare::Row| {
        let rms = r.stats.rms().map(f64::to_degrees);
        format!(
            "{:.2}° ({:.2}° / {:.2}°){}",
            r.stats.tilt_total()[0].rms.to_degrees(),
            rms[0],
            rms[1],
            if r.synthetic_position { " †" } else { "" }
        )
    };
    let _ = writeln!(
        s,
        "| flight | {ours} | {} | × ours | {} | × ours | over {RATIO_LIMIT}× |",
        RULE_PEERS[0].1, RULE_PEERS[1].1
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    for sc in results {
        let Some(o) = sc.rows.first() else { continue };
        let o_tilt = o.stats.tilt_total()[0].rms;
        let mut cells = vec![cell(o)];
        let mut over = Vec::new();
        for (name, short) in RULE_PEERS {
            let Some(r) = find(sc, name) else {
                cells.extend(["—".to_string(), "—".to_string()]);
                continue;
            };
            let ratio = r.stats.tilt_total()[0].rms / o_tilt;
            cells.push(cell(r));
            cells.push(format!("{ratio:.2}"));
            if ratio > RATIO_LIMIT {
                over.push(short);
            }
        }
        let _ = writeln!(
            s,
            "| {} | {} | {} |",
            sc.name,
            cells.join(" | "),
            if over.is_empty() { "—".to_string() } else { over.join(", ") }
        );
    }
    let _ = writeln!(s, "\nTilt RMS (roll / pitch RMS) from the common settled time, degrees; real logs: agreement with the autopilot's attitude. × ours: the peer's tilt RMS over ours; a peer over {RATIO_LIMIT}× is named in the last column and has its reason, keyed by (flight, peer), in docs/peers.md. Generated by `{}`. `†` fed a GNSS position integrated from the fixes' velocities.", command_line(args));
    s
}

/// The (flight, peer) pairs a generated [`ratio_table`] names as over the limit.
pub fn over_limit_pairs(table: &str) -> Vec<(String, String)> {
    let mut v = Vec::new();
    for line in table.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| flight")) {
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        let (Some(flight), Some(over)) = (cells.first(), cells.last()) else { continue };
        if *over == "—" || over.starts_with("---") {
            continue;
        }
        for peer in over.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            v.push((flight.to_string(), peer.to_string()));
        }
    }
    v
}

/// The text between `<!-- {name}:begin -->` and `<!-- {name}:end -->` in `text`.
pub fn block<'a>(text: &'a str, name: &str) -> Option<&'a str> {
    let (b, e) = (format!("<!-- {name}:begin -->"), format!("<!-- {name}:end -->"));
    let a = text.find(&b)? + b.len();
    let z = a + text[a..].find(&e)?;
    Some(&text[a..z])
}

/// Replaces each named block of `text` that is present (see [`block`]) with its body;
/// returns the new text and how many blocks were replaced.
pub fn replace_blocks(text: &str, blocks: &[(String, String)]) -> (String, usize) {
    let mut out = text.to_string();
    let mut n = 0;
    for (name, body) in blocks {
        let (b, e) = (format!("<!-- {name}:begin -->"), format!("<!-- {name}:end -->"));
        let Some(a) = out.find(&b).map(|a| a + b.len()) else { continue };
        let Some(z) = out[a..].find(&e).map(|z| a + z) else { continue };
        out = format!("{}\n{}{}", &out[..a], body, &out[z..]);
        n += 1;
    }
    (out, n)
}
