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

/// `report` on a log with neither truth nor `ref_*` still plots what the filter did (it used
/// to write "0 figures"): the attitude figure of the log exists and the count says so.
#[test]
fn report_plots_a_log_without_truth() {
    let rows = (0..1000)
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
                ..Default::default()
            }
        })
        .collect();
    let dir = std::env::temp_dir().join(format!("harness_fig_notruth_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("notruth.csv");
    sim_harness::csv::write_log_file(&log, &FlightLog { rows }).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sim-harness"))
        .arg("report")
        .arg(&log)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(!stdout.contains(" 0 figures"), "{stdout}");
    let attitude: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("notruth_") && n.ends_with("_attitude.png"))
        .collect();
    assert!(!attitude.is_empty(), "no attitude figure in {}", out.display());
    let _ = std::fs::remove_dir_all(&dir);
}
