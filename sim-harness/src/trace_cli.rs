//! The command line the trace examples share (`examples/nees_trace.rs`,
//! `examples/oc_trace.rs`): `LOG [EVERY_S] [--told thesis|realistic]`.

use crate::log::FlightLog;
use crate::peers::setup::SensorFigures;
use wing_ahrs::Config;

/// What a trace example replays: the log, which must carry truth, the seconds between
/// printed lines (default 2), and the configuration: `Config::default()`, or with
/// `--told GRADE` the one `sim-harness robust` flies a world of that sensor grade with
/// (the IMU's accelerometer bias and misalignment told, `robust::told`), so that the σ
/// printed is the σ the suite scores.
pub struct TraceArgs {
    pub log: FlightLog,
    pub every: f64,
    pub config: Config,
}

const USAGE: &str = "LOG [EVERY_S] [--told thesis|realistic]";

/// Parses the command line of trace example `name`. Exits with a message, never a
/// backtrace: 2 for bad arguments, 1 for a log that cannot be read or has no truth.
pub fn args(name: &str) -> TraceArgs {
    let bad = |why: &str| -> ! {
        eprintln!("{name}: {why}\nusage: {name} {USAGE}");
        std::process::exit(2);
    };
    let mut positional = Vec::new();
    let mut config = Config::default();
    let mut a = std::env::args().skip(1);
    while let Some(s) = a.next() {
        if s != "--told" {
            positional.push(s);
            continue;
        }
        let figures = match a.next().as_deref() {
            Some("thesis") => SensorFigures::thesis(),
            Some("realistic") => SensorFigures::realistic(),
            _ => bad("--told takes thesis or realistic"),
        };
        config = crate::peers::wing::unobservable(config, &figures);
    }
    let (path, every) = match positional.as_slice() {
        [p] => (p.clone(), 2.0),
        [p, e] => match e.parse::<f64>() {
            Ok(v) if v > 0.0 => (p.clone(), v),
            _ => bad("EVERY_S must be a positive number of seconds"),
        },
        _ => bad("one log, then at most one EVERY_S"),
    };
    match crate::csv::read_log(std::path::Path::new(&path)) {
        Ok(log) if log.rows.iter().any(|r| r.truth.is_some()) => TraceArgs { log, every, config },
        Ok(_) => {
            eprintln!("{path}: no truth columns");
            std::process::exit(1);
        }
        Err(e) => {
            eprintln!("{path}: {e:#}");
            std::process::exit(1);
        }
    }
}
