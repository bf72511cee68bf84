//! PX4 EKF2 (crate `ekf2` 0.1, PX4's C++ cross-compiled with arm-none-eabi-g++) fed exactly
//! as the host adapter feeds it: both go through `sim-harness/src/peers/px4_ekf2_feed.rs`
//! (parameters, flags, receiver figures and call order in one place).

use crate::record::Record;
use ekf2::Ekf;

#[path = "../../sim-harness/src/peers/px4_ekf2_feed.rs"]
mod feed;

/// Position accuracies, m (`gnss_feed::H_ACC`, `V_ACC` on the host).
const H_ACC: f32 = 1.0;
const V_ACC: f32 = 1.5;
/// Nominal IMU period, s (the host's `nominal_dt` of the simulated flights), and the
/// step clamp of its `StepClock` (10 × nominal).
const NOMINAL_DT: f32 = 0.01;

pub struct Peer {
    ekf: Ekf<'static>,
    last_us: Option<u64>,
    in_air: bool,
}

impl Peer {
    pub const KEY: &'static str = "ekf2";
    pub fn new() -> Self {
        let ekf = feed::new().unwrap_or_else(|| crate::fail());
        Peer { ekf, last_us: None, in_air: false }
    }
    pub fn step(&mut self, r: &Record) {
        let dt = match self.last_us {
            Some(l) if r.t_us > l => ((r.t_us - l) as f32 * 1e-6).min(10.0 * NOMINAL_DT),
            _ => NOMINAL_DT,
        };
        self.last_us = Some(r.t_us);
        let d = |v: [f32; 3]| v.map(|x| x * dt);
        let fix = r.fix.then_some(feed::Fix {
            time_us: r.fix_t_us,
            lla: r.lla,
            vel: r.vel,
            h_acc: H_ACC,
            v_acc: V_ACC,
            sacc: r.sacc,
        });
        let baro = (!r.baro_alt.is_nan()).then_some(r.baro_alt);
        let va = (!r.airspeed.is_nan()).then_some(r.airspeed);
        feed::step(
            &mut self.ekf,
            &mut self.in_air,
            r.t_us,
            d(r.gyro),
            d(r.accel),
            dt,
            fix,
            baro,
            va,
        );
    }
    /// Output-predictor quaternion (body FRD → NED, w x y z), as PX4 publishes it.
    pub fn quaternion(&self) -> [f32; 4] {
        self.ekf.quaternion()
    }
    pub fn attitude(&self) -> [f32; 3] {
        crate::euler_of_quat(self.quaternion())
    }
}
