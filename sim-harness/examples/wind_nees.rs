//! How honest the wind's reported σ is over a robustness-suite draw: for each world without
//! turbulence (where the truth column is the mean wind the filter estimates) and each of the
//! honest and 0.3× receiver reports, the mean of `|e_w|²/(σ_N² + σ_E²)` over the epochs from
//! 20 s after the switch-on (1 for a consistent 2-D estimate), the share of epochs beyond
//! `4.5` (χ²₂ > 9: 1.1 % if consistent) and the largest wind error.
//! `cargo run --release -p sim-harness --example wind_nees -- SEED [WORLDS]` (96 worlds by
//! default, as docs/harness.md's table).
use sim_harness::montecarlo::{record_run, EPOCH_COLUMNS};
use sim_harness::robust;

fn column(name: &str) -> usize {
    EPOCH_COLUMNS.iter().position(|c| *c == name).expect("an epoch column")
}

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let mut a = std::env::args().skip(1);
    let parse = |s: Option<String>, default: Option<u64>| match s.map(|s| s.parse::<u64>()) {
        Some(Ok(v)) => Some(v),
        None => default,
        Some(Err(_)) => None,
    };
    let (Some(seed), Some(n)) = (parse(a.next(), None), parse(a.next(), Some(96))) else {
        eprintln!("usage: wind_nees SEED [WORLDS]  (whole numbers)");
        std::process::exit(2);
    };
    let (err_col, sd_col) = (column("wind_err"), column("wind_sd"));
    let mut runs = Vec::new();
    for (k, w) in robust::worlds(n as usize, seed).iter().enumerate() {
        if w.label().contains("turb") {
            continue;
        }
        for sacc in ["honest", "x0.3"] {
            let log = match robust::flight(w, sacc.parse().expect("a receiver report")) {
                Ok(l) => l,
                Err(e) => {
                    eprintln!("world {k} ({}): {e:#}", w.label());
                    std::process::exit(1);
                }
            };
            let t_from = log.rows.first().map_or(0.0, |r| r.t) + 20.0;
            let cfg = robust::told(wing_ahrs::Config::default(), w);
            let rec = record_run(w.seed, &log, cfg, t_from);
            let z: Vec<f64> = rec
                .epochs
                .iter()
                .filter(|e| e[err_col].is_finite() && e[sd_col] > 0.0)
                .map(|e| (e[err_col] / e[sd_col]).powi(2))
                .collect();
            if z.is_empty() {
                continue;
            }
            let mean = z.iter().sum::<f64>() / z.len() as f64;
            let beyond = z.iter().filter(|&&v| v > 4.5).count() as f64 / z.len() as f64;
            let worst =
                rec.epochs.iter().map(|e| e[err_col]).filter(|v| v.is_finite()).fold(0.0, f64::max);
            println!(
                "{k:3} {:58} {sacc:7} mean {mean:7.2}  beyond {:5.1} %  largest error {worst:5.1} m/s",
                w.label(),
                100.0 * beyond
            );
            runs.push((mean, beyond));
        }
    }
    if runs.is_empty() {
        eprintln!("no run without turbulence in this draw");
        std::process::exit(1);
    }
    let mut means: Vec<f64> = runs.iter().map(|r| r.0).collect();
    means.sort_by(f64::total_cmp);
    println!(
        "{} runs: median of the runs' means {:.2}; mean share beyond {:.1} %; runs more than 10 % beyond: {}",
        runs.len(),
        means[means.len() / 2],
        100.0 * runs.iter().map(|r| r.1).sum::<f64>() / runs.len() as f64,
        runs.iter().filter(|r| r.1 > 0.1).count()
    );
}
