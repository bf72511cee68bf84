//! PX4 EKF2 (crate `ekf2` 0.1, PX4's C++ cross-compiled with arm-none-eabi-g++) fed exactly
//! as `sim-harness/src/peers/px4_ekf2.rs` feeds it on the host: the same parameters
//! (docs/peers.md), flags, noise figures and call order. Kept as a copy because that
//! adapter is written against the host harness's row type.

use crate::record::Record;
use ekf2::params::GnssControl;
use ekf2::types::{AirspeedSample, BaroSample, GnssSample, ImuSample, SystemFlagUpdate};
use ekf2::{Ekf, EkfConfig};

/// Receiver figures EKF2 checks before it uses GNSS, and the position accuracies, m
/// (`gnss_feed::H_ACC`, `V_ACC`): the host adapter's.
const PDOP: f32 = 1.2;
const NSATS: u8 = 14;
const FIX_3D: u8 = 3;
const H_ACC: f32 = 1.0;
const V_ACC: f32 = 1.5;
/// Nominal IMU period, s (the host's `nominal_dt` of the simulated flights), and the
/// step clamp of its `StepClock` (10 × nominal).
const NOMINAL_DT: f32 = 0.01;

pub struct Peer {
    ekf: Ekf<'static>,
    last_us: Option<u64>,
}

impl Peer {
    pub const KEY: &'static str = "ekf2";
    pub fn new() -> Self {
        let cfg = EkfConfig { delay_max_ms: 300.0, ..EkfConfig::default() };
        let mut ekf = Ekf::with_config(cfg).unwrap_or_else(|_| crate::fail());
        {
            let mut p = ekf.params_mut();
            p.set_gps_control(GnssControl::HPOS | GnssControl::VPOS | GnssControl::VEL);
            p.set_gps_vel_noise(0.3);
            p.set_airspeed_delay_ms(0.0);
            p.set_sideslip_fusion_enabled(true);
        }
        ekf.update_parameters();
        Peer { ekf, last_us: None }
    }
    pub fn step(&mut self, r: &Record) {
        let dt = match self.last_us {
            Some(l) if r.t_us > l => ((r.t_us - l) as f32 * 1e-6).min(10.0 * NOMINAL_DT),
            _ => NOMINAL_DT,
        };
        self.last_us = Some(r.t_us);
        let d = |v: [f32; 3]| v.map(|x| x * dt);
        self.ekf.set_imu_data(&ImuSample::new(r.t_us, d(r.gyro), d(r.accel), dt, dt));
        if r.fix {
            // Fixed wing in the air, republished at every fix as PX4's ekf2 module does.
            let mut flags = SystemFlagUpdate::new(r.t_us);
            flags.in_air = true;
            flags.is_fixed_wing = true;
            self.ekf.set_system_flag_data(&flags);
            let g = GnssSample::new(
                r.fix_t_us,
                r.lla[0],
                r.lla[1],
                r.lla[2] as f32,
                r.vel,
                H_ACC,
                V_ACC,
                r.sacc,
                PDOP,
                FIX_3D,
                NSATS,
            );
            self.ekf.set_gps_data_with_pps(&g, true);
        }
        if !r.baro_alt.is_nan() {
            self.ekf.set_baro_data(&BaroSample::new(r.t_us, r.baro_alt));
        }
        if !r.airspeed.is_nan() {
            self.ekf.set_airspeed_data(&AirspeedSample::new(r.t_us, r.airspeed, 1.0));
        }
        let _ = self.ekf.update();
    }
    /// Output-predictor quaternion (body FRD → NED, w x y z), as PX4 publishes it.
    pub fn quaternion(&self) -> [f32; 4] {
        self.ekf.quaternion()
    }
    pub fn attitude(&self) -> [f32; 3] {
        crate::euler_of_quat(self.quaternion())
    }
}
