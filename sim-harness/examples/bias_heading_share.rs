//! The accelerometer bias' heading effect against the consider terms that stand for it
//! (`sim_harness::bias_share`): per 5 s from 20 s, the RMS effect, the term's σ and the
//! ratio of their squares (1: as large as the effect; below 1: conservative), then the
//! same over the banked (> 15°) and the level samples.
//! `cargo run --release -p sim-harness --example bias_heading_share -- [SCENARIO] [SEEDS] [SIGMA_B]`
//! (default `coordinated_turn 40 0.1`; the scenario's sensors otherwise).
use sim_harness::bias_share::{self, FROM_S};

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("coordinated_turn", |s| s.as_str());
    let parsed = (
        args.get(1).map_or(Ok(40), |s| s.parse::<u64>()),
        args.get(2).map_or(Ok(0.1), |s| s.parse::<f64>()),
    );
    let (Ok(seeds @ 1..), Ok(sigma_b)) = parsed else {
        eprintln!("usage: bias_heading_share [SCENARIO] [SEEDS ≥ 1] [SIGMA_B m/s²]");
        std::process::exit(2)
    };
    if !(sigma_b > 0.0 && sigma_b <= 2.0) {
        eprintln!("SIGMA_B must be in (0, 2] m/s², got {sigma_b}");
        std::process::exit(2)
    }
    let share = match bias_share::measure(name, seeds, sigma_b) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{name}: {e:#}");
            std::process::exit(1)
        }
    };
    println!("{name}, {seeds} seeds, σ_b {sigma_b} m/s²: the bias' heading effect against its consider σ");
    println!("{:>6} {:>12} {:>12} {:>8}", "t [s]", "effect [°]", "term σ [°]", "ratio");
    for (k, s) in share.per_second.iter().enumerate().filter(|(k, s)| k % 5 == 0 && s.n > 0) {
        let (e, v) = s.rms();
        println!(
            "{:6.0} {:12.3} {:12.3} {:8.2}",
            FROM_S + k as f64,
            e.to_degrees(),
            v.to_degrees(),
            s.ratio()
        );
    }
    for (s, kind) in [(share.banked, "banked beyond 15°"), (share.level, "within 15° of level")] {
        let (e, v) = s.rms();
        println!(
            "{kind}: effect {:.3}° RMS, term σ {:.3}° RMS, ratio {:.2} ({} samples)",
            e.to_degrees(),
            v.to_degrees(),
            s.ratio(),
            s.n
        );
    }
}
