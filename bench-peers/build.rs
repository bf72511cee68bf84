//! Packs the flight named by `BENCH_PEERS_LOG` (a flight-log CSV) into `OUT_DIR/samples.bin`
//! for the firmware to embed, through the host comparison's own GNSS feed, so both see the
//! same fixes and the same (synthesised where absent) positions. Record layout (LE):
//! t_us u64 | gyro 3×f32 | accel 3×f32 | airspeed f32 (NaN: none) | fix u32 (0/1) |
//! fix_t_us u64 | vel 3×f32 | sacc f32 | lat, lon, alt 3×f64 | baro_alt f32 (NaN: none) |
//! true roll, pitch, yaw 3×f32 (rad; NaN: none), 104 B in all. The truth is read only outside
//! the counted step (`bench-peers/src/truth.rs`).
//!
//! With the `ekf2` feature it also runs the host's PX4 EKF2 adapter over the same log and
//! stores its quaternion (w x y z, 4×f32) every 100 samples in `OUT_DIR/host_ekf2.bin`, so
//! the firmware can check that the cross-compiled EKF2 computes the same filter.

use std::io::Write;

fn main() -> anyhow::Result<()> {
    println!("cargo:rerun-if-env-changed=BENCH_PEERS_LOG");
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR")?);
    // memory.x (QEMU board) comes from the wing-ahrs build script, on the link path.
    let path = std::env::var("BENCH_PEERS_LOG").map_err(|_| {
        anyhow::anyhow!("set BENCH_PEERS_LOG to a flight-log CSV (cargo xtask bench-peers does)")
    })?;
    println!("cargo:rerun-if-changed={path}");
    let log = sim_harness::csv::read_log(std::path::Path::new(&path))?;
    let mut feed = sim_harness::peers::gnss_feed::GnssFeed::new();
    let mut buf = Vec::with_capacity(log.rows.len() * 104);
    for row in &log.rows {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        buf.write_all(&sim_harness::peers::gnss_feed::micros(row.t).to_le_bytes())?;
        for x in f(row.gyro).into_iter().chain(f(row.accel)) {
            buf.write_all(&x.to_le_bytes())?;
        }
        buf.write_all(&row.airspeed.map_or(f32::NAN, |v| v as f32).to_le_bytes())?;
        let fix = feed.fix(row);
        buf.write_all(&(fix.is_some() as u32).to_le_bytes())?;
        let fx = fix.unwrap_or(sim_harness::peers::gnss_feed::Fix {
            time_us: 0,
            lla: [0.0; 3],
            vel: [0.0; 3],
            sacc: 0.0,
            synthetic: false,
        });
        buf.write_all(&fx.time_us.to_le_bytes())?;
        for x in f(fx.vel) {
            buf.write_all(&x.to_le_bytes())?;
        }
        buf.write_all(&(fx.sacc as f32).to_le_bytes())?;
        for x in fx.lla {
            buf.write_all(&x.to_le_bytes())?;
        }
        buf.write_all(&row.baro_alt.map_or(f32::NAN, |v| v as f32).to_le_bytes())?;
        for x in row.truth.map_or([f32::NAN; 3], f) {
            buf.write_all(&x.to_le_bytes())?;
        }
    }
    std::fs::write(out.join("samples.bin"), buf)?;
    let mut reference = Vec::new();
    if std::env::var_os("CARGO_FEATURE_EKF2").is_some() {
        use sim_harness::peers::Estimator;
        let mut ekf =
            sim_harness::peers::px4_ekf2::Px4Ekf2::new(sim_harness::compare::nominal_dt(&log));
        for (k, row) in log.rows.iter().enumerate() {
            ekf.step(row);
            if k % 100 == 99 {
                for x in ekf.ekf().quaternion() {
                    reference.write_all(&x.to_le_bytes())?;
                }
            }
        }
    }
    std::fs::write(out.join("host_ekf2.bin"), reference)?;
    Ok(())
}
