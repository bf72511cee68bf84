//! Replays one scenario's log through the default filter many times (for `valgrind --tool=callgrind` or
//! `perf`: per-function instruction counts of the host step). Not a benchmark: see
//! `benches/cost.rs` and `sim-harness compare` for timed figures.
//!
//! `cargo run --release -p sim-harness --example cost_profile -- [scenario] [passes] [estimator]`
//! (estimator: a substring of a `compare` table name, default `wing-ahrs`, the first row: the default filter).

fn main() {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "flight2".into());
    let passes: usize = args.next().and_then(|p| p.parse().ok()).unwrap_or(5);
    let which = args.next().unwrap_or_else(|| "wing-ahrs".into());
    // Exit 3: the log is not here (no JSBSim output, no shared data); 2: a bad argument.
    let log = match sim_harness::compare::scenario_log(&name, 1) {
        Ok(Some((log, _))) => log,
        Ok(None) => {
            eprintln!("`{name}` is not available here");
            std::process::exit(3);
        }
        Err(e) => {
            eprintln!("`{name}`: {e:#}");
            std::process::exit(if e.to_string().contains("not a scenario") { 2 } else { 3 });
        }
    };
    let dt = sim_harness::compare::nominal_dt(&log);
    let Some(k) =
        sim_harness::peers::all(dt).iter().position(|e| e.name().contains(which.as_str()))
    else {
        eprintln!("no estimator named like `{which}`");
        std::process::exit(2);
    };
    let mut sum = 0.0;
    for _ in 0..passes {
        let mut w = sim_harness::peers::all(dt).swap_remove(k);
        for row in &log.rows {
            w.step(std::hint::black_box(row));
        }
        sum += w.attitude()[0];
    }
    println!("{which}: {} rows × {passes} passes, final roll sum {sum:.6}", log.rows.len());
}
