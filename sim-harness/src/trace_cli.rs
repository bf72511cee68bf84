//! The command line the trace examples share (`examples/nees_trace.rs`,
//! `examples/oc_trace.rs`): `LOG [EVERY_S]`.

use crate::log::FlightLog;

/// The command line of a trace example, `NAME LOG [EVERY_S]`: the log, which must carry
/// truth, and the seconds between printed lines (default 2). Exits with a message, never a
/// backtrace: 2 for bad arguments, 1 for a log that cannot be read or has no truth.
pub fn args(name: &str) -> (FlightLog, f64) {
    let mut a = std::env::args().skip(1);
    let (Some(path), every) = (a.next(), a.next()) else {
        eprintln!("usage: {name} LOG [EVERY_S]");
        std::process::exit(2);
    };
    let every: f64 = match every.map(|s| s.parse()) {
        None => 2.0,
        Some(Ok(v)) if v > 0.0 => v,
        _ => {
            eprintln!("EVERY_S must be a positive number of seconds");
            std::process::exit(2);
        }
    };
    match crate::csv::read_log(std::path::Path::new(&path)) {
        Ok(l) if l.rows.iter().any(|r| r.truth.is_some()) => (l, every),
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
