//! fusion-nav 0.1 fed exactly as `sim-harness/src/peers/fusion_nav.rs` feeds it on the host
//! (same configuration, noise rules and call order; see docs/peers.md). Kept as a copy
//! because that adapter is written against the host harness's row type.

use crate::record::Record;
use fusion_nav::prelude::*;

const VEL_FLOOR: f32 = 0.3;
const POS_FLOOR_H: f32 = 0.5;
const POS_FLOOR_V: f32 = 0.75;
const H_ACC: f32 = 1.0;
const V_ACC: f32 = 1.5;

pub struct Peer {
    eskf: Eskf,
    started: bool,
    last_us: Option<u64>,
}

impl Peer {
    pub const KEY: &'static str = "fusion-nav";
    pub fn new() -> Self {
        let mut c = Config::default();
        c.init.sigma_gyro_bias = RadiansPerSecond::from_rad_per_s(0.044);
        let eskf = Eskf::new(c).unwrap_or_else(|_| crate::fail());
        Peer { eskf, started: false, last_us: None }
    }
    pub fn step(&mut self, r: &Record) {
        let dt = match self.last_us {
            Some(l) if r.t_us > l => ((r.t_us - l) as f32 * 1e-6).min(0.1),
            _ => 0.01,
        };
        self.last_us = Some(r.t_us);
        let [gx, gy, gz] = r.gyro;
        let [ax, ay, az] = r.accel;
        let imu = ImuSample::from_rates(
            Timestamp::from_micros(r.t_us),
            AngularRate::body(gx, gy, gz),
            Acceleration::body(ax, ay, az),
            Seconds::from_secs(dt),
        );
        if !self.started {
            self.started = self.eskf.initialize_coarse(imu).is_ok();
        } else {
            let _ = self.eskf.predict(imu);
        }
        if !(r.fix && self.started) {
            return;
        }
        let time = Timestamp::from_micros(r.fix_t_us);
        let vel_noise = VelocityNoise::clamped(
            r.sacc,
            1.5 * r.sacc,
            SigmaBounds::at_least(VEL_FLOOR),
            SigmaBounds::at_least(1.5 * VEL_FLOOR),
        );
        let pos_noise = PositionNoise::clamped(
            H_ACC,
            V_ACC,
            SigmaBounds::new(POS_FLOOR_H, 100.0),
            SigmaBounds::new(POS_FLOOR_V, 100.0),
        );
        let [lat, lon, alt] = r.lla;
        let fix = Geodetic::from_degrees(lat, lon, alt);
        let _ = self.eskf.fuse_gnss_geodetic(time, fix, pos_noise, Position::zero());
        let [vn, ve, vd] = r.vel;
        let v = Velocity::ned(vn, ve, vd);
        let _ = self.eskf.fuse_gnss_velocity(time, v, vel_noise, Position::zero());
    }
    pub fn attitude(&self) -> [f32; 3] {
        let (r, p, y) = self.eskf.state().attitude.euler_angles();
        [r, p, y]
    }
}
