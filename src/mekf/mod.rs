//! The quaternion filter: a six-state multiplicative EKF (attitude error + gyro
//! biases) valid at every attitude, with one file per aid source, each holding its
//! control policy (`control_*`, a method of [`QuatAhrs`]), its fusion (`fuse`) and its
//! resets, as PX4's EKF2 lays out `aid_sources/`:
//!
//! - [`gps_accel`] — the GPS acceleration against the accelerometer, as a 3-D vector
//!   (status: `UpdateRecord::axes`, m/s² NED);
//! - [`heading_accel`] — the heading solved from the horizontal GPS acceleration while it
//!   is too uncertain for the linear update (after alignment, after a long straight leg);
//! - [`course`] — the air-relative course, for the heading where nothing else sees it
//!   (status: `UpdateRecord::course`, rad);
//! - [`wind`] — the wind (from airspeed, or from turn circles without it), along the
//!   air-velocity direction of [`aoa`]'s learnt angle of attack (status: [`QuatAhrs::wind`]).
//!
//! This file is the loop: per IMU sample the prediction (`predict`), per fix interval
//! the alignment (`align`) or the GPS acceleration, then the wind and the course.
//! [`filter`] holds the state and covariance, [`dv_window`] pairs IMU samples with
//! GPS intervals, [`latency`] tracks the receiver delay, [`vel_noise`] learns the fixes'
//! noise, [`quat`] the rotation algebra; the read-outs are in `outputs`.

mod align;
pub mod aoa;
pub mod consistency;
pub mod course;
pub mod dv_window;
pub mod filter;
pub mod gps_accel;
pub mod heading_accel;
pub mod latency;
pub mod latency_consider;
mod limits;
mod outputs;
mod predict;
pub mod quat;
#[cfg(feature = "gyro-scale-states")]
pub mod scale;
pub mod unmodelled;
pub mod vel_noise;
pub mod vibration;
pub mod wind;

use crate::estimator::GpsOutcome;
use crate::config::{Config, QuatConfig};
use crate::fix::{admit, GpsFix};
use crate::health::{Flags, Health, UpdateRecord};
use crate::math::Vec3;
use crate::measure::gps_delta::{GpsDelta, GpsDifferencer, Push};
use aoa::AngleOfAttack;
use dv_window::{DvWindow, WindowMean};
use filter::{Mekf, Noise};
use heading_accel::HeadingFromAccel;
use latency::LatencyTracker;
use limits::Limits;
use vel_noise::VelNoise;
use wind::{Wind, WindNoise};

/// The variance of a heading nothing has measured, rad² (1 rad σ): before the first
/// course, and after the GPS acceleration failed its gate persistently.
const UNKNOWN_HEADING_VAR: f32 = 1.0;

crate::internal! {
    /// Largest receiver latency tracked, s (the delay line spans 0.4 s at 160 Hz).
    pub const MAX_LATENCY: f32 = 0.3;
}

/// The quaternion attitude estimator (driven through [`crate::Ahrs`]).
#[derive(Debug, Clone)]
pub struct QuatAhrs {
    cfg: Config,
    /// The options `cfg.filter` holds.
    quat: QuatConfig,
    ekf: Mekf,
    noise: Noise,
    wind_noise: WindNoise,
    window: DvWindow,
    latency: LatencyTracker,
    /// The fixes' velocity noise, learnt (`QuatConfig::learn_vel_noise`).
    vel_noise: VelNoise,
    gps: GpsDifferencer,
    wind: Wind,
    aoa: AngleOfAttack,
    last_imu_t: Option<u64>,
    last_fix_t: Option<u64>,
    lim: Limits,
    last_course_t: Option<u64>,
    /// Time since the wind filter last ran, s, and whether this fix skips it.
    wind_dt: f32,
    wind_skip: bool,
    /// When the GPS acceleration last observed the heading (a turn), µs.
    heading_seen_t: Option<u64>,
    heading_accel: HeadingFromAccel,
    /// The variance of the heading rate no state holds since the heading was last seen,
    /// (rad/s)² ([`unmodelled::heading_rate_variance`] at that turn's body rate).
    heading_rate_var: f32,
    /// Consecutive course updates beyond `COURSE_DOUBT_NIS`.
    course_doubt: u8,
    gyro: Vec3,
    since_propagation: u8,
    airspeed_sum: f32,
    airspeed_n: u16,
    tilt_aligned: bool,
    yaw_aligned: bool,
    /// Consecutive GPS intervals refused: gated updates, or while the tilt is unaligned,
    /// intervals whose specific forces disagree in length or over which the body turned.
    gate_streak: u16,
    /// While the tilt is unaligned in a turn: the velocity of the fix the turn's span
    /// starts at (NED, m/s) and the span so far (s) (`align`).
    turn_span: Option<(Vec3, f32)>,
    /// Consecutive accepted GPS-acceleration updates since the attitude became doubtful.
    trust_streak: u16,
    health: Health,
    flags: Flags,
    last_update: UpdateRecord,
    /// [`unmodelled::body_variance`] of the options, rad²: added to each reported covariance.
    unmodelled: [f32; 3],
    /// The heading a body-fixed accelerometer bias leaves, added to each reported
    /// covariance as `unmodelled` is.
    heading_bias: unmodelled::HeadingBias,
    /// [`unmodelled::heading_drift_variance`] plus the untracked latency's `ψ̇²·σ²` as of
    /// the last update, rad²: added to each reported heading variance (kept, not computed
    /// per sample: a u64 → f32 conversion is a library call on the M4F, and every sample
    /// reports σ).
    heading_drift: f32,
    /// The GPS acceleration's recent NIS per degree of freedom: scales the reported
    /// attitude covariance ([`consistency`]).
    consistency: consistency::Consistency,
}

impl QuatAhrs {
    /// A new, unaligned estimator: the shared options of `cfg` and the quaternion filter's
    /// `q` (those `cfg.filter` holds; the facade passes them).
    pub fn new(cfg: Config, q: QuatConfig) -> Self {
        let bias_psd = match cfg.bias_model.random_walk_equivalent() {
            crate::config::BiasModel::RandomWalk { density } => density * density,
            _ => 0.0,
        };
        let vb = cfg.init_sigma_bias * cfg.init_sigma_bias;
        let va = cfg.init_sigma_attitude * cfg.init_sigma_attitude;
        let mut flags = Flags::default();
        flags.set(Flags::NO_GPS_YET, true);
        let latency = LatencyTracker::new(cfg.gps_latency, q.latency_gain, MAX_LATENCY);
        QuatAhrs {
            ekf: Self::filter(&q, [va, va, 1.0, vb, vb, vb]),
            noise: Noise {
                gyro_psd: cfg.gyro_noise_density * cfg.gyro_noise_density,
                bias_psd,
                rate_psd: q.gyro_rate_noise * q.gyro_rate_noise,
                scale_var: q.gyro_scale_sigma * q.gyro_scale_sigma,
                // The scale states hold x and y: the coherent noise keeps z only.
                #[cfg(feature = "gyro-scale-states")]
                scale_var_xy: if q.gyro_scale_state_sigma > 0.0 {
                    0.0
                } else {
                    q.gyro_scale_sigma * q.gyro_scale_sigma
                },
                misalignment_var: q.gyro_misalignment_sigma * q.gyro_misalignment_sigma,
            },
            wind_noise: WindNoise {
                wind_walk: q.wind_walk,
                airspeed_walk: q.airspeed_walk,
                init_sigma: q.wind_init_sigma,
                flow_angle_sigma: q.flow_angle_sigma,
            },
            window: DvWindow::new(cfg.gps_latency),
            latency,
            vel_noise: VelNoise::default(),
            gps: GpsDifferencer::default(),
            wind: Wind::default(),
            aoa: AngleOfAttack::default(),
            last_imu_t: None,
            last_fix_t: None,
            lim: Limits::new(&cfg, &q),
            last_course_t: None,
            wind_dt: 0.0,
            wind_skip: false,
            heading_seen_t: None,
            heading_accel: HeadingFromAccel::default(),
            gyro: [0.0; 3],
            since_propagation: 0,
            airspeed_sum: 0.0,
            airspeed_n: 0,
            tilt_aligned: false,
            yaw_aligned: false,
            gate_streak: 0,
            turn_span: None,
            trust_streak: 0,
            health: Health::default(),
            flags,
            last_update: UpdateRecord::default(),
            unmodelled: unmodelled::body_variance(&q),
            heading_bias: unmodelled::HeadingBias::default(),
            heading_drift: 0.0,
            heading_rate_var: q.heading_rate_sigma * q.heading_rate_sigma,
            course_doubt: 0,
            consistency: consistency::Consistency::default(),
            cfg,
            quat: q,
        }
    }

    /// The six-state filter, with the scale states when configured and compiled in.
    fn filter(q: &QuatConfig, var: [f32; 6]) -> Mekf {
        let ekf = Mekf::new(quat::IDENTITY, var);
        #[cfg(feature = "gyro-scale-states")]
        if q.gyro_scale_state_sigma > 0.0 {
            return ekf.with_scale_states(q.gyro_scale_state_sigma);
        }
        let _ = q;
        ekf
    }

    /// See [`crate::Ahrs::on_imu`].
    pub fn on_imu(&mut self, t_us: u64, gyro: Vec3, accel: Vec3) -> bool {
        let within = crate::math::within;
        if !(within(&gyro, self.cfg.gyro_range) && within(&accel, self.cfg.accel_range)) {
            self.health.imu_rejected = self.health.imu_rejected.wrapping_add(1);
            return false;
        }
        match self.last_imu_t {
            None => self.level_from_accel(accel),
            Some(last) if t_us <= last => {
                self.health.dt_nonpositive = self.health.dt_nonpositive.wrapping_add(1);
                return false;
            }
            Some(last) => {
                let dt_us = (t_us - last).min(u32::MAX as u64) as u32;
                let mut dt = dt_us as f32 * 1e-6;
                if dt > self.cfg.dt_max {
                    dt = self.cfg.dt_max;
                    self.health.dt_clamped = self.health.dt_clamped.wrapping_add(1);
                }
                self.integrate(t_us, gyro, accel, dt);
            }
        }
        self.last_imu_t = Some(t_us);
        self.gyro = gyro;
        self.health.imu_samples = self.health.imu_samples.wrapping_add(1);
        self.check_gps_timeout(t_us);
        true
    }

    /// See [`crate::Ahrs::on_airspeed`]: the mean over each GPS interval aids the wind.
    pub fn on_airspeed(&mut self, _t_us: u64, va: f32) -> bool {
        if !(va.is_finite() && (0.0..=self.cfg.airspeed_range).contains(&va)) {
            self.health.airspeed_rejected = self.health.airspeed_rejected.wrapping_add(1);
            return false;
        }
        self.airspeed_sum += va;
        self.airspeed_n = self.airspeed_n.saturating_add(1);
        true
    }

    /// See [`crate::Ahrs::on_gps`].
    pub fn on_gps(&mut self, fix: &GpsFix) -> GpsOutcome {
        let range = self.cfg.velocity_range;
        if !admit(fix, range, &mut self.last_fix_t, &mut self.flags, &mut self.health) {
            return GpsOutcome::Rejected;
        }
        // Matched by reference: moving the delta out of `Push` was a 76-byte memcpy.
        let push = self.gps.push(fix, self.cfg.gps_min_interval, self.cfg.gps_max_interval);
        let d = match &push {
            Push::TooSoon => return GpsOutcome::Ignored,
            Push::Seeded => {
                self.health.gps_reseeds = self.health.gps_reseeds.wrapping_add(1);
                self.window.restart();
                self.latency.restart();
                self.heading_accel.reset();
                self.ekf.forget_fix_noise();
                self.vel_noise.restart();
                return GpsOutcome::Seeded;
            }
            Push::Delta(d) => d,
        };
        let Some(w) = self.window.take() else {
            self.vel_noise.restart();
            return GpsOutcome::Ignored;
        };
        self.propagate();
        self.update(fix.t_us, d, &w);
        GpsOutcome::Updated
    }

    /// One fix interval: alignment or the GPS-acceleration update, then wind and course.
    #[inline(never)]
    fn update(&mut self, t_us: u64, d: &GpsDelta, w: &WindowMean) {
        let vel_var = self.vel_var(d);
        self.last_update = UpdateRecord {
            t_us,
            seq: self.last_update.seq.wrapping_add(1),
            ..UpdateRecord::default()
        };
        if !self.tilt_aligned {
            self.control_alignment(d, w, vel_var);
        } else {
            self.control_gps_accel(t_us, d, w, vel_var);
            self.check_bias();
        }
        let mut epoch = latency::EpochDcm::default();
        self.control_wind(t_us, d, w, vel_var[1], &mut epoch);
        self.control_course(t_us, d, w, vel_var[1], &mut epoch);
        // In a turn a latency the tracker has not yet learnt, δd, turns the heading by
        // `ψ̇·δd` in every update alike: a heading error no update averages down.
        let psi_dot = self.heading_rate(w);
        self.heading_drift = self.heading_seen_t.map_or(0.0, |seen| {
            unmodelled::heading_drift_variance(t_us, seen, self.heading_rate_var)
        }) + psi_dot * psi_dot * self.latency.untracked_var();
        self.health.updates = self.health.updates.wrapping_add(1);
        self.flags.set(Flags::ALIGNED, self.tilt_aligned && self.yaw_aligned);
        self.flags
            .set(Flags::SIDESLIP, libm::fabsf(w.f_body[1]) > self.quat.course_max_lateral);
        let vib = vibration::excessive(w, self.lim.vib);
        self.flags.set(Flags::VIBRATION, vib);
        self.health.vibration = self.health.vibration.wrapping_add(vib as u32);
    }

}
