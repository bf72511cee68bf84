//! EKF2 input study: replays a log with EKF1 (for the gyro bias) and at every GPS
//! difference forms the airspeed roll/pitch measurement with several input choices,
//! printing the error of each against truth (or ref_*), per time window.
//! `cargo run --release -p sim-harness --example ekf2_inputs -- LOG.csv [from_s]`
//! (`DUMP=1` also prints the roll-equation terms of every update).
use wing_ahrs::measure::airspeed::{measure, AirData};
use wing_ahrs::measure::gps_delta::{GpsDifferencer, Push};
use wing_ahrs::measure::va_slope::VaSlope;
use wing_ahrs::{Config, Model};

#[derive(Default, Clone)]
struct Acc {
    n: f64,
    s: f64,
    ss: f64,
}
impl Acc {
    fn add(&mut self, x: f64) {
        if x.is_finite() {
            self.n += 1.0;
            self.s += x;
            self.ss += x * x;
        }
    }
    fn fmt(&self) -> String {
        let m = self.s / self.n;
        format!("{:6.2}±{:5.2}", m, (self.ss / self.n - m * m).max(0.0).sqrt())
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or_else(|| anyhow::anyhow!("usage: ekf2_inputs LOG.csv [from_s] [min_airspeed]"))?;
    let log = sim_harness::csv::read_log(std::path::Path::new(path))?;
    let from: f64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(45.0);
    let min_va: f32 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(8.0);
    let mut ahrs =
        wing_ahrs::Ahrs::try_new(Config::euler().with_model(Model::Ekf1(Default::default())))
            .expect("a valid configuration");
    let mut diff = GpsDifferencer::default();
    let mut vas = VaSlope::new(0.1);
    let (mut sa, mut sg, mut std_, mut st, mut sn) = ([0f64; 3], [0f64; 3], 0f64, [0f64; 3], 0f64);
    const V: usize = 7;
    let names = [
        "latest",
        "mean acc",
        "mean acc+rates",
        "+air gamma",
        "+gdot=0",
        "+vadot=0",
        "mean, tdot=q c - r s",
    ];
    let mut er: Vec<Acc> = vec![Acc::default(); V];
    let mut ep: Vec<Acc> = vec![Acc::default(); V];
    for row in &log.rows {
        let t_us = sim_harness::replay::to_us(row.t);
        sim_harness::replay::step(&mut ahrs, row);
        let truth = row.truth.or(row.reference).unwrap_or([f64::NAN; 3]);
        let b = ahrs.gyro_bias();
        let x = ahrs.attitude();
        let rates =
            [row.gyro[0] as f32 - b[0], row.gyro[1] as f32 - b[1], row.gyro[2] as f32 - b[2]];
        let (sf, cf) = (x.roll.sin(), x.roll.cos());
        let td = rates[1] * cf - rates[2] * sf;
        for i in 0..3 {
            sa[i] += row.accel[i];
            sg[i] += rates[i] as f64;
            st[i] += truth[i];
        }
        std_ += td as f64;
        sn += 1.0;
        if let Some(v) = row.airspeed {
            vas.push(t_us, v as f32);
        }
        let Some(fix) = sim_harness::replay::fix_for_row(row) else { continue };
        let Push::Delta(d) = diff.push(&fix, 0.02, 1.5) else {
            (sa, sg, std_, st, sn) = ([0.0; 3], [0.0; 3], 0.0, [0.0; 3], 0.0);
            continue;
        };
        let m = |a: [f64; 3]| [(a[0] / sn) as f32, (a[1] / sn) as f32, (a[2] / sn) as f32];
        let (macc, mrate, mtruth, mtd) = (m(sa), m(sg), m(st), (std_ / sn) as f32);
        (sa, sg, std_, st, sn) = ([0.0; 3], [0.0; 3], 0.0, [0.0; 3], 0.0);
        if row.t < from {
            continue;
        }
        let Some(e) = vas.estimate(8) else { continue };
        let lacc = [row.accel[0] as f32, row.accel[1] as f32, row.accel[2] as f32];
        let base = AirData {
            va: e.va,
            va_dot: e.va_dot,
            gamma: d.gamma(),
            gamma_dot: d.gamma_dot(),
            theta_dot: td,
            rates,
        };
        let air_gamma = (-d.vel[2] / e.va.max(1.0)).clamp(-1.0, 1.0).asin();
        let pred = (truth[0] as f32, truth[1] as f32);
        let mpred = (mtruth[0], mtruth[1]);
        let variants: [(AirData, [f32; 3], (f32, f32)); V] = [
            (base, lacc, pred),
            (base, macc, mpred),
            (AirData { rates: mrate, theta_dot: mtd, ..base }, macc, mpred),
            (AirData { rates: mrate, theta_dot: mtd, gamma: air_gamma, ..base }, macc, mpred),
            (
                AirData { rates: mrate, theta_dot: mtd, gamma: air_gamma, gamma_dot: 0.0, ..base },
                macc,
                mpred,
            ),
            (
                AirData { rates: mrate, theta_dot: mtd, gamma: air_gamma, va_dot: 0.0, ..base },
                macc,
                mpred,
            ),
            (
                AirData {
                    rates: mrate,
                    theta_dot: mrate[1] * mtruth[0].cos() - mrate[2] * mtruth[0].sin(),
                    ..base
                },
                macc,
                mpred,
            ),
        ];
        if std::env::var("DUMP").is_ok() {
            let z = measure(macc, &variants[2].0, mpred, min_va);
            let a = &variants[2].0;
            let al = mtruth[1] - d.gamma();
            println!(
                "{:.2},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                row.t,
                mtruth[0],
                mtruth[1],
                z.roll.unwrap_or(f32::NAN),
                z.pitch.unwrap_or(f32::NAN),
                -macc[1],
                a.va * a.rates[2] * al.cos(),
                -a.va * a.rates[0] * al.sin(),
                a.va,
                a.rates[0],
                a.rates[1],
                a.rates[2],
                macc[0],
                macc[2]
            );
        }
        for (k, (air, acc, p)) in variants.iter().enumerate() {
            let z = measure(*acc, air, *p, min_va);
            let w = |a: f64| {
                (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                    - std::f64::consts::PI
            };
            if let Some(r) = z.roll {
                er[k].add(w(r as f64 - p.0 as f64).to_degrees());
            }
            if let Some(q) = z.pitch {
                ep[k].add((q as f64 - p.1 as f64).to_degrees());
            }
        }
    }
    for k in 0..V {
        println!(
            "{:24} n {:5} roll err {}  pitch err {}",
            names[k],
            er[k].n,
            er[k].fmt(),
            ep[k].fmt()
        );
    }
    Ok(())
}
