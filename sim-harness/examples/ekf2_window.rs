//! EKF2 window study: forms the airspeed roll/pitch measurement from means over the
//! last K GPS intervals (K = 1 is per-interval) and prints its error against the mean
//! truth (or ref_*) over the same window.
//! `cargo run --release -p sim-harness --example ekf2_window -- LOG.csv from_s K...`
use std::collections::VecDeque;
use wing_ahrs::measure::airspeed::{measure, AirData};
use wing_ahrs::measure::gps_delta::{GpsDifferencer, Push};
use wing_ahrs::measure::va_slope::VaSlope;
use wing_ahrs::{Config, Model};

#[derive(Default, Clone, Copy)]
struct Sums {
    n: f64,
    acc: [f64; 3],
    rate: [f64; 3],
    truth: [f64; 3],
    va: f64,
    nva: f64,
    t0: f64,
    t1: f64,
    v0: [f64; 3],
    v1: [f64; 3],
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        anyhow::bail!("usage: ekf2_window LOG.csv from_s K...  (K = GPS intervals per window)");
    }
    let log = sim_harness::csv::read_log(std::path::Path::new(&args[1]))?;
    let from: f64 = args[2].parse()?;
    let ks: Vec<usize> = args[3..].iter().map(|s| s.parse()).collect::<Result<_, _>>()?;
    if ks.contains(&0) {
        anyhow::bail!("K must be ≥ 1");
    }
    let mut ahrs =
        wing_ahrs::Ahrs::try_new(Config::euler().with_model(Model::Ekf1(Default::default())))
            .expect("a valid configuration");
    let mut diff = GpsDifferencer::default();
    let mut hist: VecDeque<Sums> = VecDeque::new();
    let mut cur = Sums::default();
    let mut res: Vec<[Vec<f64>; 2]> = ks.iter().map(|_| [vec![], vec![]]).collect();
    let mut vas = VaSlope::new(0.1);
    let mut va_hist: VecDeque<(f64, f64)> = VecDeque::new();
    for row in &log.rows {
        sim_harness::replay::step(&mut ahrs, row);
        let truth = row.truth.or(row.reference).unwrap_or([f64::NAN; 3]);
        let b = ahrs.gyro_bias();
        for i in 0..3 {
            cur.acc[i] += row.accel[i];
            cur.rate[i] += row.gyro[i] - b[i] as f64;
            cur.truth[i] += truth[i];
        }
        cur.n += 1.0;
        if let Some(v) = row.airspeed {
            cur.va += v;
            cur.nva += 1.0;
            va_hist.push_back((row.t, v));
            vas.push(sim_harness::replay::to_us(row.t), v as f32);
        }
        while va_hist.front().is_some_and(|f| f.0 < row.t - 5.0) {
            va_hist.pop_front();
        }
        let Some(fix) = sim_harness::replay::fix_for_row(row) else { continue };
        let g = row.gps.unwrap().vel;
        match diff.push(&fix, 0.02, 1.5) {
            Push::Delta(_) => {
                cur.t1 = row.t;
                cur.v1 = g;
                hist.push_back(cur);
                if hist.len() > 64 {
                    hist.pop_front();
                }
            }
            _ => hist.clear(),
        }
        cur = Sums { t0: row.t, v0: g, ..Sums::default() };
        if row.t < from {
            continue;
        }
        for (ki, &k) in ks.iter().enumerate() {
            if hist.len() < k {
                continue;
            }
            let w: Vec<&Sums> = hist.iter().rev().take(k).collect();
            let (t0, t1) = (w[k - 1].t0, w[0].t1);
            let (v0, v1) = (w[k - 1].v0, w[0].v1);
            let n: f64 = w.iter().map(|s| s.n).sum();
            let m = |f: &dyn Fn(&Sums) -> [f64; 3]| {
                let mut a = [0.0; 3];
                for s in &w {
                    let x = f(s);
                    for i in 0..3 {
                        a[i] += x[i];
                    }
                }
                [a[0] / n, a[1] / n, a[2] / n]
            };
            let acc = m(&|s| s.acc);
            let rate = m(&|s| s.rate);
            let tr = m(&|s| s.truth);
            // Va slope: least squares over airspeed samples in [t0, t1].
            let pts: Vec<(f64, f64)> =
                va_hist.iter().filter(|p| p.0 >= t0 && p.0 <= t1).cloned().collect();
            if pts.len() < 3 {
                continue;
            }
            let np = pts.len() as f64;
            let mt = pts.iter().map(|p| p.0).sum::<f64>() / np;
            let mv = pts.iter().map(|p| p.1).sum::<f64>() / np;
            let stt: f64 = pts.iter().map(|p| (p.0 - mt).powi(2)).sum();
            let stv: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - mv)).sum();
            let vdot = if stt > 0.0 { stv / stt } else { 0.0 };
            let vm = [(v0[0] + v1[0]) / 2.0, (v0[1] + v1[1]) / 2.0, (v0[2] + v1[2]) / 2.0];
            let gamma = (-vm[2] / mv.max(1.0)).clamp(-1.0, 1.0).asin();
            let air = AirData {
                va: mv as f32,
                va_dot: vdot as f32,
                gamma: gamma as f32,
                gamma_dot: 0.0,
                theta_dot: 0.0,
                rates: [rate[0] as f32, rate[1] as f32, rate[2] as f32],
            };
            let f = |a: [f64; 3]| [a[0] as f32, a[1] as f32, a[2] as f32];
            let z = measure(f(acc), &air, (tr[0] as f32, tr[1] as f32), 8.0);
            if let (Some(r), Some(p)) = (z.roll, z.pitch) {
                res[ki][0].push((r as f64 - tr[0]).to_degrees());
                res[ki][1].push((p as f64 - tr[1]).to_degrees());
            }
            if std::env::var("DUMP").ok().and_then(|s| s.parse::<usize>().ok()) == Some(k) {
                println!(
                    "{:.2},{},{},{},{}",
                    row.t,
                    tr[0],
                    tr[1],
                    z.roll.unwrap_or(f32::NAN),
                    z.pitch.unwrap_or(f32::NAN)
                );
            }
        }
    }
    let st = |v: &Vec<f64>| {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let s = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt();
        let mut a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        a.sort_by(|x, y| x.partial_cmp(y).unwrap());
        format!(
            "{:6.2}±{:5.2} p95|e| {:5.2}",
            m,
            s,
            a.get((0.95 * n) as usize).copied().unwrap_or(f64::NAN)
        )
    };
    for (ki, k) in ks.iter().enumerate() {
        println!(
            "K {:2} n {:4} roll {}  pitch {}",
            k,
            res[ki][0].len(),
            st(&res[ki][0]),
            st(&res[ki][1])
        );
    }
    Ok(())
}
