//! Host throughput of the GPS byte parser: prints `key: value` lines.
//!
//! `cargo run --release --example gps_bench`
//!
//! Streams are generated with the crate's own encoders from a simulated 10 Hz
//! flight: UBX NAV-PVT only, NMEA RMC+VTG+GGA, and both interleaved. Each is fed
//! byte by byte (the ISR path, `GpsParser::push`) for at least 0.5 s of wall time.
//! Wall-clock figures depend on machine load; for a load-independent figure run
//! `valgrind --tool=callgrind target/release/examples/gps_bench --once` and divide
//! the inclusive instruction count of `wing_ahrs::gps::count_fixes` by the bytes
//! (the `--once [ubx_nav_pvt|nmea_rmc_vtg_gga|mixed]` mode prints the byte counts).

use std::hint::black_box;
use std::time::Instant;
use wing_ahrs::gps::{encode, GpsParser};
use wing_ahrs::{FixType, GpsFix};

fn fixes(n: usize) -> Vec<GpsFix> {
    (0..n)
        .map(|k| {
            let t = k as f32 * 0.1;
            let chi = 0.2 * t;
            GpsFix {
                t_us: 0,
                itow_ms: Some(43_200_000 + 100 * k as u32),
                fix_type: FixType::Fix3D,
                fix_ok: true,
                vel_ne: [25.0 * chi.cos(), 25.0 * chi.sin()],
                vel_d: Some(-1.5 * (0.3 * t).sin()),
                speed_acc: Some(0.3),
                num_sats: 14,
                lat_e7: 473_977_420 + (k as i32) * 17,
                lon_e7: 85_455_940 + (k as i32) * 23,
                alt_msl_mm: 500_000 + k as i32 * 10,
            }
        })
        .collect()
}

fn stream(fs: &[GpsFix], ubx: bool, nmea: bool) -> Vec<u8> {
    let mut out = Vec::new();
    let mut b = [0u8; 128];
    for f in fs {
        if nmea {
            let n = encode::nmea_rmc(f, 220426, &mut b).unwrap();
            out.extend_from_slice(&b[..n]);
            let n = encode::nmea_vtg(f, &mut b).unwrap();
            out.extend_from_slice(&b[..n]);
            let n = encode::nmea_gga(f, &mut b).unwrap();
            out.extend_from_slice(&b[..n]);
        }
        if ubx {
            let n = encode::nav_pvt(f, &mut b).unwrap();
            out.extend_from_slice(&b[..n]);
        }
    }
    out
}

fn bench(name: &str, bytes: &[u8]) {
    let mut total = 0u64;
    let mut fix_count = 0u64;
    let start = Instant::now();
    while start.elapsed().as_secs_f64() < 0.5 {
        let mut p = GpsParser::new();
        for (i, &b) in bytes.iter().enumerate() {
            if black_box(p.push(black_box(b), i as u64)).is_some() {
                fix_count += 1;
            }
        }
        total += bytes.len() as u64;
    }
    let secs = start.elapsed().as_secs_f64();
    println!("{name}_bytes_per_s: {:.0}", total as f64 / secs);
    println!("{name}_ns_per_byte: {:.2}", secs * 1e9 / total as f64);
    println!("{name}_fixes_per_pass: {}", fix_count * bytes.len() as u64 / total);
}

fn main() {
    let fs = fixes(1000);
    let ubx = stream(&fs, true, false);
    let nmea = stream(&fs, false, true);
    let mixed = stream(&fs, true, true);
    if std::env::args().any(|a| a == "--once") {
        // One pass of each through the never-inlined `count_fixes`, for valgrind.
        let only: Option<String> = std::env::args().skip_while(|a| a != "--once").nth(1);
        for (name, s) in [("ubx_nav_pvt", &ubx), ("nmea_rmc_vtg_gga", &nmea), ("mixed", &mixed)] {
            if only.as_deref().is_some_and(|o| o != name) {
                continue;
            }
            println!("{name}_bytes: {}", s.len());
            println!("{name}_fixes: {}", wing_ahrs::gps::count_fixes(black_box(s)));
        }
        return;
    }
    println!("parser_state_bytes: {}", std::mem::size_of::<GpsParser>());
    println!("ubx_bytes_per_epoch: {}", ubx.len() / fs.len());
    println!("nmea_bytes_per_epoch: {}", nmea.len() / fs.len());
    bench("ubx_nav_pvt", &ubx);
    bench("nmea_rmc_vtg_gga", &nmea);
    bench("mixed", &mixed);
}
