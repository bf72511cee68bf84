//! Property test of the flight-log reader (`csv::parse_log`) and the replay behind it:
//! random headers and rows — numbers, empty cells, NaN/inf, huge values, garbage, wrong
//! cell counts, times out of order — must give a log or an error naming where, never a
//! panic; every log that reads replays without a panic. Seeded (reproducible).
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sim_harness::csv::parse_log;

const COLS: [&str; 22] = [
    "t",
    "gx",
    "gy",
    "gz",
    "ax",
    "ay",
    "az",
    "gps_t",
    "vn",
    "ve",
    "vd",
    "airspeed",
    "true_roll",
    "true_pitch",
    "true_yaw",
    "true_bp",
    "true_bq",
    "true_br",
    "ref_roll",
    "ref_pitch",
    "ref_yaw",
    "gps_sacc",
];

fn cell(rng: &mut ChaCha8Rng, t: f64) -> String {
    match rng.gen_range(0..20) {
        0 => String::new(),
        1 => "NaN".into(),
        2 => "inf".into(),
        3 => "-1e308".into(),
        4 => "x".into(),
        5 => "1e999".into(),
        6 => format!("{t}"),
        7 => "\"3\"".into(),
        _ => format!("{}", rng.gen_range(-20.0..20.0)),
    }
}

#[test]
fn random_csv_never_panics_and_errors_say_where() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let (mut ok, mut err) = (0, 0);
    for case in 0..3000 {
        // Required columns present in most cases; optional ones 85 % each.
        let all_required = rng.gen_bool(0.9);
        let mut cols: Vec<&str> = COLS
            .iter()
            .enumerate()
            .filter(|&(i, _)| (i < 7 && all_required) || rng.gen_bool(0.85))
            .map(|(_, c)| *c)
            .collect();
        if rng.gen_bool(0.1) {
            cols.push("extra");
        }
        if rng.gen_bool(0.05) {
            let j = rng.gen_range(0..cols.len().max(1));
            cols.swap(0, j);
        }
        let mut s = cols.join(",");
        s.push('\n');
        let rows = rng.gen_range(0..60);
        // Hostility: the chance that any one cell is replaced by a random (often bad) one.
        let p_bad = [0.0, 0.0, 0.01, 0.3][rng.gen_range(0..4)];
        let mut last_t = 0.0;
        for k in 0..rows {
            let t = k as f64 * 0.01 + if rng.gen_bool(0.01) { -1.0 } else { 0.0 };
            // Per row, each optional group filled or empty as a whole.
            let fill: Vec<bool> = (0..5).map(|_| rng.gen_bool(0.5)).collect();
            let group = |c: &str| match c {
                "gps_t" | "vn" | "ve" | "vd" | "gps_sacc" => Some(0),
                "airspeed" => Some(1),
                c if c.starts_with("true_b") => Some(3),
                c if c.starts_with("true_") => Some(2),
                c if c.starts_with("ref_") => Some(4),
                _ => None,
            };
            let n = if rng.gen_bool(0.02) { rng.gen_range(0..cols.len() + 3) } else { cols.len() };
            let cells: Vec<String> = (0..n)
                .map(|i| {
                    if rng.gen_bool(p_bad) {
                        return cell(&mut rng, t);
                    }
                    match cols.get(i).copied() {
                        Some("t") => format!("{t}"),
                        Some("gps_t") if fill[0] => {
                            format!("{}", if rng.gen_bool(0.3) { last_t } else { t })
                        }
                        Some("gps_sacc") if fill[0] => format!("{}", rng.gen_range(0.0..2.0)),
                        Some(c) => match group(c) {
                            Some(g) if !fill[g] => String::new(),
                            _ => format!("{}", rng.gen_range(-5.0..5.0)),
                        },
                        None => "1".into(),
                    }
                })
                .collect();
            last_t = t;
            s.push_str(&cells.join(","));
            s.push(if rng.gen_bool(0.1) { '\r' } else { ' ' });
            s.push('\n');
        }
        let res = std::panic::catch_unwind(|| parse_log(s.as_bytes(), "fuzz.csv"));
        let res = res.unwrap_or_else(|_| panic!("case {case}: reader panicked on:\n{s}"));
        match res {
            Ok(log) => {
                ok += 1;
                let r = std::panic::catch_unwind(|| {
                    sim_harness::estimate::replay_estimates(&log, wing_ahrs::Config::default())
                });
                assert!(r.is_ok(), "case {case}: replay panicked on:\n{s}");
            }
            Err(e) => {
                err += 1;
                let m = format!("{e:#}");
                assert!(m.starts_with("fuzz.csv"), "case {case}: error without the file name: {m}");
                assert!(
                    m.contains("line")
                        || m.contains("header")
                        || m.contains("no data rows")
                        || m.contains("same time"),
                    "case {case}: error does not say where: {m}"
                );
            }
        }
    }
    println!("3000 random logs: {ok} read and replayed, {err} rejected with a located error");
    assert!(ok > 100 && err > 100, "both outcomes exercised: {ok} ok, {err} errors");
}
