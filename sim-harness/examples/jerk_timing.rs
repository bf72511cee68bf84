//! Where the online latency tracker settles on a receiver that smooths its velocity: the
//! filter's own `LatencyTracker` driven by a forward model (docs/open-problems.md, "The
//! latency tracker helps some flights and breaks others").
//!
//! The tracker correlates the GPS-acceleration residual with the jerk between two
//! consecutive IMU windows. That jerk stands at the windows' common edge, half an interval
//! before the newer window's centre, where the residual stands. For a pure delay the timing
//! does not matter (the residual vanishes at the right delay); for a receiver with a
//! first-order velocity filter it does. On an exact manoeuvre (four sines north, no noise,
//! no attitude error) this prints where the tracker settles with the residual as shipped,
//! and fed the mean of the two windows' residuals (the residual moved to the jerk's edge:
//! with no window noise that is the whole of the moved form), beside the least-squares pure
//! delay over the same flight.
//! `cargo run --release -p sim-harness --example jerk_timing`
use wing_ahrs::config::{QuatConfig, GRAVITY};
use wing_ahrs::mekf::{latency::LatencyTracker, MAX_LATENCY};

/// The manoeuvre: north acceleration `a·sin(w·t + p)` per sine (rad/s, m/s², rad).
const SINES: [(f64, f64, f64); 4] =
    [(0.7, 5.0, 0.3), (1.9, 4.0, 1.1), (3.7, 3.0, 2.0), (5.3, 2.0, 0.5)];
/// Intervals flown; the settled value is the mean over the last `SETTLED`.
const INTERVALS: usize = 3000;
const SETTLED: usize = 1000;

/// North velocity at `t` s as a receiver with a `tau`-s first-order filter reports it, m/s.
fn velocity(t: f64, tau: f64) -> f64 {
    SINES
        .iter()
        .map(|&(w, a, p)| {
            let gain = 1.0 / (1.0 + (w * tau).powi(2)).sqrt();
            -a / w * gain * (w * t + p - (w * tau).atan()).cos()
        })
        .sum()
}

/// The GPS-acceleration residual over the interval ending at `t` (fixes `delay` s late
/// through a `tau`-s filter, IMU window held back `d` s) and the IMU window's mean, m/s².
fn residual(t: f64, dt: f64, delay: f64, tau: f64, d: f64) -> (f64, f64) {
    let gps = (velocity(t - delay, tau) - velocity(t - dt - delay, tau)) / dt;
    let imu = (velocity(t - d, 0.0) - velocity(t - dt - d, 0.0)) / dt;
    (gps - imu, imu)
}

/// Where the tracker settles, s: fed each interval's residual, or (`centred`) the mean of
/// this and the previous interval's.
fn track(delay: f64, tau: f64, dt: f64, centred: bool) -> f64 {
    let gain = QuatConfig::default().latency_gain;
    let mut tracker = LatencyTracker::new(0.0, gain, MAX_LATENCY);
    let mut prev_y = None;
    let mut sum = 0.0;
    for k in 1..INTERVALS {
        let d = f64::from(tracker.value());
        let (y, f) = residual(k as f64 * dt, dt, delay, tau, d);
        let fed = match (centred, prev_y) {
            (true, Some(y0)) => 0.5 * (y + y0),
            _ => y,
        };
        let f = [f as f32, 0.0, -GRAVITY];
        let jerk = tracker.jerk(f, dt as f32);
        tracker.observe([fed as f32, 0.0, 0.0], f, 0.0, dt as f32, true, jerk);
        prev_y = Some(y);
        if k >= INTERVALS - SETTLED {
            sum += f64::from(tracker.value());
        }
    }
    sum / SETTLED as f64
}

/// The pure delay that best fits the settled part of the flight (least squares on a 1 ms
/// grid up to the tracker's span), s.
fn best_fit(delay: f64, tau: f64, dt: f64) -> f64 {
    let sse = |d: f64| -> f64 {
        (INTERVALS - SETTLED..INTERVALS)
            .step_by(2)
            .map(|k| residual(k as f64 * dt, dt, delay, tau, d).0.powi(2))
            .sum()
    };
    (0..=300)
        .map(|i| (i as f64 / 1000.0, sse(i as f64 / 1000.0)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0.0, |(d, _)| d)
}

fn main() {
    sim_harness::quiet_on_closed_pipe();
    if let Some(arg) = std::env::args().nth(1) {
        eprintln!("jerk_timing takes no arguments (got {arg})");
        std::process::exit(2)
    }
    println!(
        "| receiver | fixes | best pure delay s | tracked, residual at its window s \
         | tracked, residual at the jerk's edge s |"
    );
    println!("|---|---|---|---|---|");
    for (delay, tau) in [(0.16, 0.0), (0.06, 0.1), (0.0, 0.1)] {
        for dt in [1.0, 0.5, 0.2, 0.1, 0.05] {
            let filter = if tau > 0.0 { format!(" + {tau} s filter") } else { String::new() };
            println!(
                "| {:.0} ms{filter} | {} Hz | {:.3} | {:.3} | {:.3} |",
                delay * 1000.0,
                1.0 / dt,
                best_fit(delay, tau, dt),
                track(delay, tau, dt, false),
                track(delay, tau, dt, true),
            );
        }
    }
}
