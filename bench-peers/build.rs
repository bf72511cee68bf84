//! Packs the flight named by `BENCH_PEERS_LOG` (a flight-log CSV) into `OUT_DIR/samples.bin`
//! for the firmware to embed, through the host comparison's own GNSS feed, so both see the
//! same fixes and the same (synthesised where absent) positions. Record layout (LE), 96 B:
//! t_us u64 | gyro 3×f32 | accel 3×f32 | airspeed f32 (NaN: none) | fix u32 (0/1) |
//! fix_t_us u64 | vel 3×f32 | sacc f32 | lat, lon, alt 3×f64 | pad 8.

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
    let mut buf = Vec::with_capacity(log.rows.len() * 96);
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
        buf.write_all(&[0u8; 8])?;
    }
    std::fs::write(out.join("samples.bin"), buf)?;
    Ok(())
}
