//! Figures render headless (no system fonts): PNG and SVG files with text, from a
//! hand-made log with truth replayed through the core.
use sim_harness::estimate::replay_estimates;
use sim_harness::figures::standard_set;
use sim_harness::log::{FlightLog, GpsSample, LogRow};
use wing_ahrs::Config;

#[test]
fn standard_set_writes_png_and_svg_with_text() {
    // Level, still, 20 s at 100 Hz with a stationary-ish GPS at 10 Hz moving north at 15 m/s.
    let rows = (0..2000)
        .map(|k| {
            let t = k as f64 * 0.01;
            LogRow {
                t,
                gyro: [0.0; 3],
                accel: [0.0, 0.0, -9.80665],
                gps: (k % 10 == 0).then_some(GpsSample {
                    t,
                    vel: [15.0, 0.0, 0.0],
                    speed_acc: None,
                    lla: None,
                }),
                truth: Some([0.0; 3]),
                truth_bias: Some([0.0; 3]),
                ..Default::default()
            }
        })
        .collect();
    let log = FlightLog { rows };
    let (est, _) = replay_estimates(&log, Config::euler());
    let dir = std::env::temp_dir().join(format!("harness_fig_{}", std::process::id()));
    let pngs = standard_set(&dir, "level", "hand-made level flight", &log, &est).unwrap();
    assert_eq!(pngs.len(), 4);
    for p in &pngs {
        let bytes = std::fs::read(p).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", p.display());
        let svg = std::fs::read_to_string(p.with_extension("svg")).unwrap();
        assert!(
            svg.contains("<text") && svg.contains("t [s]"),
            "SVG without axis text: {}",
            p.display()
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
