//! Flight-log and estimate CSV: round trip, the docs/formats.md rules (empty cell = none,
//! extra columns ignored, fixed names) and errors with line and column on bad files.
use sim_harness::csv::{parse_log, write_log};
use sim_harness::estimate::{read_estimates, EstimateRow, EstimateWriter, COLUMNS};
use sim_harness::log::{FlightLog, GpsSample, LogRow};

fn err_of(text: &str) -> String {
    format!("{:#}", parse_log(text.as_bytes(), "test.csv").unwrap_err())
}

#[test]
fn round_trip_is_lossless() {
    let mut rows = Vec::new();
    for k in 0..50 {
        let t = k as f64 * 0.01 + 1e-9 * k as f64;
        rows.push(LogRow {
            t,
            gyro: [0.1 * t, -0.2, 1.0 / 3.0],
            accel: [0.3, -9.80665, std::f64::consts::PI],
            gps: (k % 10 == 0).then_some(GpsSample {
                t: t - 0.05,
                vel: [20.0, -1.0 / 7.0, 0.5],
                speed_acc: (k % 20 == 0).then_some(0.125),
                lla: (k % 20 == 0).then_some([47.397_742_1 + 1e-9 * k as f64, -8.5, 488.25]),
            }),
            airspeed: (k % 2 == 0).then_some(21.123456789),
            baro_alt: (k % 3 == 0).then_some(-12.5 + 0.1 * k as f64),
            truth: Some([0.1, -0.2, 3.0]),
            truth_bias: (k > 10).then_some([1e-4, -2e-4, 3e-5]),
            reference: None,
            truth_wind: (k % 3 == 0).then_some([-4.5, 2.0 / 3.0, 0.25]),
        });
    }
    let log = FlightLog { rows };
    let mut buf = Vec::new();
    write_log(&mut buf, &log).unwrap();
    let back = parse_log(buf.as_slice(), "mem").unwrap();
    assert_eq!(back, log);
}

#[test]
fn empty_cells_are_none_and_extra_columns_ignored() {
    let text =
        "extra,az,ay,ax,gz,gy,gx,t,gps_t,vn,ve,vd,airspeed,ref_roll,ref_pitch,ref_yaw,junk\n\
                x,-9.8,0,0,0,0,0,0.0,,,,,,,,,y\n\
                x,-9.8,0,0.5,0,0,0.01,0.01,0.01,10,1,-0.5,15,0.1,0.2,0.3,z\n";
    let log = parse_log(text.as_bytes(), "t").unwrap();
    assert_eq!(log.rows.len(), 2);
    assert_eq!(log.rows[0].gps, None);
    assert_eq!(log.rows[0].airspeed, None);
    assert_eq!(log.rows[0].reference, None);
    let r = log.rows[1];
    assert_eq!(r.t, 0.01);
    assert_eq!(r.gyro, [0.01, 0.0, 0.0]);
    assert_eq!(r.accel, [0.5, 0.0, -9.8]);
    assert_eq!(
        r.gps,
        Some(GpsSample { t: 0.01, vel: [10.0, 1.0, -0.5], speed_acc: None, lla: None })
    );
    assert_eq!(r.airspeed, Some(15.0));
    assert_eq!(r.reference, Some([0.1, 0.2, 0.3]));
    assert_eq!(r.truth, None);
}

#[test]
fn malformed_files_name_line_and_column() {
    let h = "t,gx,gy,gz,ax,ay,az,gps_t,vn,ve,vd\n";
    let e = err_of(&format!("{h}0,0,0,0,0,0,-9.8,,,,\n0.01,0,abc,0,0,0,-9.8,,,,\n"));
    assert!(
        e.contains("line 3") && e.contains("column 3") && e.contains("`gy`") && e.contains("abc"),
        "{e}"
    );
    let e = err_of(&format!("{h}0,0,0,0,0,0,,,,,\n"));
    assert!(e.contains("line 2") && e.contains("`az`") && e.contains("empty"), "{e}");
    let e = err_of(&format!("{h}0,0,0,0,0,0,-9.8,0.0,1,,\n"));
    assert!(e.contains("line 2") && e.contains("vn"), "{e}");
    let e = err_of("t,gx,gy,gz,ax,ay\n0,0,0,0,0,0\n");
    assert!(e.contains("missing required column `az`"), "{e}");
    let e = err_of(&format!("{h}0.02,0,0,0,0,0,-9.8,,,,\n0.01,0,0,0,0,0,-9.8,,,,\n"));
    assert!(e.contains("line 3") && e.contains("backwards"), "{e}");
    let e = err_of(&format!("{h}0,0,0\n"));
    assert!(e.contains("line 2") && e.contains("missing"), "{e}");
    let e = err_of(h);
    assert!(e.contains("no data rows"), "{e}");
    let e = err_of("");
    assert!(e.contains("missing required column"), "{e}");
    // Binary garbage: an error, not a panic.
    let junk: Vec<u8> = (0..2000u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
    assert!(parse_log(junk.as_slice(), "junk").is_err());
}

#[test]
fn estimate_csv_has_the_contract_columns_and_reads_back() {
    let dir = std::env::temp_dir().join(format!("harness_est_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("est.csv");
    let rows = vec![
        EstimateRow {
            t: 0.0,
            att: [0.1, 0.2, -3.0],
            bias: [1e-3, 2e-3, 3e-3],
            sd: [0.01; 6],
            flags: "no_gps_yet|not_aligned".into(),
            ..Default::default()
        },
        EstimateRow {
            t: 0.01,
            att: [0.1, 0.2, -3.0],
            bias: [1e-3, 2e-3, 3e-3],
            sd: [0.01; 6],
            innov: [Some(0.01), Some(-0.02), None],
            innov_sd: [Some(0.02), Some(0.03), None],
            flags: "gate_pitch|yaw_skipped".into(),
            wind: Some(([3.0, -4.5, 0.0], [0.25, 0.5])),
        },
    ];
    let mut w = EstimateWriter::new(std::fs::File::create(&p).unwrap()).unwrap();
    for r in &rows {
        w.write(r).unwrap();
    }
    w.finish().unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert_eq!(
        text.lines().next().unwrap(),
        "t,roll,pitch,yaw,bp,bq,br,sd_roll,sd_pitch,sd_yaw,sd_bp,sd_bq,sd_br,innov_roll,innov_pitch,innov_yaw,innov_sd_roll,innov_sd_pitch,innov_sd_yaw,flags,wind_n,wind_e,wind_d,sd_wind_n,sd_wind_e"
    );
    assert_eq!(COLUMNS.len(), 20);
    assert!(text.lines().nth(1).unwrap().contains(",,,,,,no_gps_yet|not_aligned,,,,,"));
    assert!(text.lines().nth(2).unwrap().ends_with(",3,-4.5,0,0.25,0.5"));
    assert_eq!(read_estimates(&p).unwrap(), rows);
    std::fs::remove_dir_all(&dir).ok();
}

/// docs/formats.md: a NaN or infinite IMU value is refused with its line and column, a
/// `.csv.gz` log is read as the CSV it holds, and the log is the same either way.
#[test]
fn nonfinite_imu_values_are_refused_and_gzip_logs_are_read() {
    use std::io::Write;
    let dir = std::env::temp_dir().join(format!("wing-csv-gz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = "t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,-9.81\n0.01,0,0,0,0,0,-9.81\n";
    let bad = text.replace("0.01,0,0,0,0,0", "0.01,0,0,NaN,0,0");
    let e = sim_harness::csv::parse_log(bad.as_bytes(), "bad.csv").unwrap_err();
    let msg = format!("{e:#}");
    assert!(msg.contains("line 3") && msg.contains("column 4") && msg.contains("gz"), "{msg}");
    let e = sim_harness::csv::parse_log(text.replace("-9.81\n0.01", "inf\n0.01").as_bytes(), "x")
        .unwrap_err();
    assert!(format!("{e:#}").contains("column 7"), "{e:#}");
    let gz = dir.join("log.csv.gz");
    let mut enc = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::default(),
    );
    enc.write_all(text.as_bytes()).unwrap();
    enc.finish().unwrap();
    let plain = sim_harness::csv::parse_log(text.as_bytes(), "plain").unwrap();
    let read = sim_harness::import::load_any(&gz).unwrap();
    assert_eq!(read, plain);
    assert!(sim_harness::import::is_log_path(gz.to_str().unwrap()));
    std::fs::remove_dir_all(&dir).ok();
}
