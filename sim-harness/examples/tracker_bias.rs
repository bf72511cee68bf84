//! Where the online latency tracker settles on `aerobatics_realistic` (5 Hz receiver, 60 ms
//! delivery, 0.1 s velocity filter), seed by seed, against the offline estimate
//! (`latency::estimate`, from the truth attitude), and what it costs: the tilt RMS from 60 s
//! with the tracker, and with the latency fixed at the offline estimate. Then the same with
//! the receiver's delay or its velocity filter removed, to see which of them the tracker
//! overshoots (docs/open-problems.md, "The latency tracker helps some flights and breaks
//! others").
//! `cargo run --release -p sim-harness --example tracker_bias -- [SEEDS, e.g. 1-6]`
use sim_harness::latency::estimate;
use sim_harness::log::FlightLog;
use sim_harness::{estimate::replay_estimates, metrics, sim};

/// Tilt RMS (deg) from 60 s and the latency the filter ends with (s).
fn tilt_and_latency(log: &FlightLog, cfg: wing_ahrs::Config) -> Option<(f64, f64)> {
    let (est, ahrs) = replay_estimates(log, cfg);
    let cmp = metrics::compare(log, &est, 60.0)?;
    Some((cmp.tilt.rms.to_degrees(), ahrs.gps_latency() as f64))
}

fn main() {
    sim_harness::quiet_on_closed_pipe();
    let seeds = std::env::args().nth(1).unwrap_or_else(|| "1-6".into());
    let Some((a, b)) = seeds
        .split_once('-')
        .and_then(|(a, b)| Some((a.parse::<u64>().ok()?, b.parse::<u64>().ok()?)))
    else {
        eprintln!("seeds: FIRST-LAST, e.g. 1-6 (got {seeds})");
        std::process::exit(2)
    };
    let base = match sim::load_scenario("aerobatics_realistic") {
        Ok(s) => s,
        Err(e) => {
            eprintln!("aerobatics_realistic: {e:#}");
            std::process::exit(1)
        }
    };
    let mut delay_only = base.clone();
    delay_only.sensors.gps.smoothing_tau_s = 0.0;
    let mut filter_only = base.clone();
    filter_only.sensors.gps.latency_s = 0.0;
    println!(
        "| receiver | seed | offline s | tracked s | tilt tracked ° | tilt at offline latency ° |"
    );
    println!("|---|---|---|---|---|---|");
    for (name, sc) in [
        ("60 ms + 0.1 s filter", &base),
        ("60 ms only", &delay_only),
        ("0.1 s filter only", &filter_only),
    ] {
        for seed in a..=b {
            let log = match sim::run(sc, seed) {
                Ok(r) => r.log,
                Err(e) => {
                    eprintln!("{name} seed {seed}: {e:#}");
                    std::process::exit(1)
                }
            };
            let Some(offline) = estimate(&log, 0.5).map(|e| e.latency_s) else {
                println!("| {name} | {seed} | not measurable | | | |");
                continue;
            };
            let mut fixed = wing_ahrs::Config::default();
            fixed.quat_mut().expect("the default is the quaternion filter").latency_gain = 0.0;
            fixed.gps_latency = offline as f32;
            let (Some((tilt, found)), Some((tilt_fixed, _))) = (
                tilt_and_latency(&log, wing_ahrs::Config::default()),
                tilt_and_latency(&log, fixed),
            ) else {
                eprintln!("{name} seed {seed}: no truth to compare with");
                std::process::exit(1)
            };
            println!(
                "| {name} | {seed} | {offline:.3} | {found:.3} | {tilt:.3} | {tilt_fixed:.3} |"
            );
        }
    }
}
