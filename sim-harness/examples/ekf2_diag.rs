//! EKF2 diagnostics: one CSV row per measurement update with the measured roll/pitch,
//! innovations, gate status, airspeed, rates and truth/reference, for offline analysis.
//! `cargo run --release -p sim-harness --example ekf2_diag -- LOG.csv [ekf1|ekf2] > diag.csv`
use wing_ahrs::{AxisStatus, Config, Model};

fn st(s: AxisStatus) -> u8 {
    match s {
        AxisStatus::Accepted => 1,
        AxisStatus::Gated => 2,
        AxisStatus::ForcedAfterGate => 3,
        AxisStatus::Initialised => 4,
        AxisStatus::NotMeasured => 0,
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let path =
        args.get(1).ok_or_else(|| anyhow::anyhow!("usage: ekf2_diag LOG.csv [ekf1|ekf2]"))?;
    let log = sim_harness::csv::read_log(std::path::Path::new(path))?;
    let model = if args.get(2).map(|s| s.as_str()) == Some("ekf1") {
        Model::Ekf1(Default::default())
    } else {
        Model::Ekf2(Default::default())
    };
    let mut cfg = Config::euler().with_model(model);
    // Overrides for studies (EKF2 only): EKF2_WINDOW (s), EKF2_SLIP (m/s²).
    if let Some(e2) = cfg.ekf2_mut() {
        if let Some(w) = std::env::var("EKF2_WINDOW").ok().and_then(|v| v.parse().ok()) {
            e2.window = w;
        }
        if let Some(w) = std::env::var("EKF2_SLIP").ok().and_then(|v| v.parse().ok()) {
            e2.max_lateral_accel = w;
        }
    }
    let mut seq = 0;
    let mut va = f64::NAN;
    println!("t,tr,tp,ty,xr,xp,xy,zr,zp,zy,nr,np,ny,sr,sp,sy,va,p,q,r,ax,ay,az,vn,ve,vd");
    sim_harness::replay::run(&log, cfg, |row, a| {
        if let Some(v) = row.airspeed {
            va = v;
        }
        let u = a.last_update();
        if u.seq == seq {
            return;
        }
        seq = u.seq;
        let tr = row.truth.or(row.reference).unwrap_or([f64::NAN; 3]);
        let x = a.attitude();
        let b = a.body_rates();
        let g = row.gps.map(|g| g.vel).unwrap_or([f64::NAN; 3]);
        let ax = &u.axes;
        let z = |i: usize| if ax[i].status == AxisStatus::NotMeasured { f32::NAN } else { ax[i].z };
        let n = |i: usize| {
            if ax[i].status == AxisStatus::NotMeasured {
                f32::NAN
            } else {
                ax[i].innovation
            }
        };
        println!(
            "{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            row.t,
            tr[0],
            tr[1],
            tr[2],
            x.roll,
            x.pitch,
            x.yaw,
            z(0),
            z(1),
            z(2),
            n(0),
            n(1),
            n(2),
            st(ax[0].status),
            st(ax[1].status),
            st(ax[2].status),
            va,
            b[0],
            b[1],
            b[2],
            row.accel[0],
            row.accel[1],
            row.accel[2],
            g[0],
            g[1],
            g[2]
        );
    });
    Ok(())
}
