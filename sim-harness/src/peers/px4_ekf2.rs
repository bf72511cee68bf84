//! PX4's EKF2 (crate `ekf2` 0.1: PX4's C++ behind a safe API) in its fixed-wing
//! configuration without a magnetometer: GNSS velocity and position, barometer (where the
//! log has `baro_alt`), true airspeed and synthetic sideslip, the fixed-wing and in-air
//! flags, and its own Gaussian-sum yaw estimator (EKF-GSF) for heading.
//!
//! Inputs: IMU as delta angle / delta velocity over the row's interval (FRD, rad and m/s —
//! EKF2's own convention, no sign change); each fix stamped with its epoch (`gps_t`) and
//! handed over with PPS compensation, so EKF2 applies no `EKF2_GPS_DELAY` of its own and
//! sees the same latency as every other estimator. Output: the quaternion (body FRD → NED,
//! w x y z) of its output predictor, as PX4 publishes it.
//!
//! Parameters (docs/peers.md, in one place in `px4_ekf2_feed.rs`): PX4's fixed-wing
//! defaults (`rc.fw_defaults`: `EKF2_ARSP_THR` 8 m/s, `EKF2_FUSE_BETA` 1, its `EKF2_REQ_*`)
//! and parameter-file defaults where the C++ struct is stale (`EKF2_GPS_CTRL` 7,
//! `EKF2_GPS_V_NOISE` 0.3 m/s, `EKF2_ACC_B_NOISE` 3e-3, `EKF2_WIND_NSD` 0.05,
//! `EKF2_BARO_NOISE` 3.5 m, `EKF2_HGT_REF` GNSS); from the log, `EKF2_DELAY_MAX` (its oldest fix),
//! `EKF2_REQ_GPS_H` (1 s for a start in the air) and `EKF2_ASP_DELAY` 0; matched, the
//! spec's IMU, bias, GNSS-velocity and airspeed noise ([`Setup::ekf2`]).

use super::gnss_feed::{micros, GnssFeed, H_ACC, V_ACC};
use super::px4_ekf2_feed::{self as feed, Fix};
use super::setup::Setup;
use super::{euler_of_quat, Estimator, StepClock, YawSource};
use crate::log::LogRow;
use ekf2::Ekf;

/// Table name.
pub const NAME: &str = "PX4 EKF2 (ekf2 0.1)";

/// The EKF2 peer.
pub struct Px4Ekf2 {
    ekf: Ekf<'static>,
    clock: StepClock,
    feed: GnssFeed,
    synthetic_pos: bool,
    in_air: bool,
}

impl Px4Ekf2 {
    /// EKF2 as the M4F bench runs it ([`feed::Params::IN_AIR`]), for a log with nominal IMU
    /// period `dt`, s.
    pub fn new(dt: f64) -> Self {
        Self::with_params(dt, &feed::Params::IN_AIR)
    }

    /// EKF2 set up for one log.
    pub fn with_setup(setup: &Setup) -> Self {
        Px4Ekf2 { feed: setup.gnss_feed(), ..Self::with_params(setup.dt, &setup.ekf2()) }
    }

    /// EKF2 with explicit parameters.
    ///
    /// # Panics
    /// If the C++ side cannot allocate the filter (out of memory).
    pub fn with_params(dt: f64, params: &feed::Params) -> Self {
        let ekf = feed::with(params).expect("EKF2 allocation failed");
        Px4Ekf2 {
            ekf,
            clock: StepClock::new(dt),
            feed: GnssFeed::new(),
            synthetic_pos: false,
            in_air: false,
        }
    }
}

impl Px4Ekf2 {
    /// The wrapped filter (diagnostics).
    pub fn ekf(&self) -> &Ekf<'static> {
        &self.ekf
    }
    /// The wrapped filter, to change a parameter (diagnostics: `examples/ekf2_real.rs`).
    pub fn ekf_mut(&mut self) -> &mut Ekf<'static> {
        &mut self.ekf
    }
}

impl Estimator for Px4Ekf2 {
    fn name(&self) -> &str {
        NAME
    }
    fn step(&mut self, row: &LogRow) {
        let dt = self.clock.dt(row.t);
        let t_us = micros(row.t);
        let d = |v: [f64; 3]| v.map(|x| (x * dt) as f32);
        let fix = self.feed.fix(row).map(|f| {
            self.synthetic_pos |= f.synthetic;
            Fix {
                time_us: f.time_us,
                lla: f.lla,
                vel: f.vel.map(|v| v as f32),
                h_acc: H_ACC as f32,
                v_acc: V_ACC as f32,
                sacc: f.sacc as f32,
            }
        });
        let baro = row.baro_alt.map(|b| b as f32);
        let va = row.airspeed.map(|v| v as f32);
        feed::step(
            &mut self.ekf,
            &mut self.in_air,
            t_us,
            d(row.gyro),
            d(row.accel),
            dt as f32,
            fix,
            baro,
            va,
        );
    }
    fn attitude(&self) -> [f64; 3] {
        let q = self.ekf.quaternion().map(f64::from);
        euler_of_quat(q[0], q[1], q[2], q[3])
    }
    fn estimates_bias(&self) -> bool {
        true
    }
    fn uses_gps(&self) -> bool {
        true
    }
    fn yaw_source(&self) -> YawSource {
        YawSource::YawEstimator
    }
    fn synthetic_position(&self) -> bool {
        self.synthetic_pos
    }
}
