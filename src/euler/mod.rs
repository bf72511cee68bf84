//! The thesis' Euler-state filter ([`crate::config::Filter::Euler`]), driven through
//! the facade [`crate::Ahrs`]. Its aid sources, each with its control policy:
//! [`gps_accel`] (EKF1: roll/pitch from the GPS acceleration), [`airspeed`] (EKF2:
//! roll/pitch from the airspeed) and [`course`] (yaw); [`update`] runs one fix interval.
//!
//! Call order per IMU sample (the firmware and the host replay use the same):
//! 1. [`Ahrs::on_imu`] — validate, predict;
//! 2. [`Ahrs::on_airspeed`] — if an airspeed sample came with it;
//! 3. [`Ahrs::on_gps`] — for each GPS fix that became available since the last sample.
//!
//! Every call is O(1), allocation-free and panic-free; bad input is counted in
//! [`Health`] and never reaches the state.

mod airspeed;
mod course;
mod gps_accel;
mod update;

use crate::config::{BiasModel, Config, Ekf1Form, Ekf2Config, EulerConfig, Model};
use crate::ekf::fix_noise::FixNoise;
use crate::ekf::{Ekf, PendingCovariance, ProcessNoise, VarianceCaps};
use crate::estimator::GpsOutcome;
use crate::fix::{admit, GpsFix};
use crate::health::{Flags, Health, UpdateRecord};
use crate::math::Vec3;
use crate::measure::air_window::AirWindow;
use crate::measure::gps_delta::{GpsDifferencer, Push};
use crate::measure::interval::IntervalAccumulator;
use crate::measure::va_slope::VaSlope;
use crate::rotation::Euler;
use update::IntervalRefs;

/// The Euler-state estimator: six-state half-EKF plus its measurement models.
#[derive(Debug, Clone)]
pub struct EulerAhrs {
    cfg: Config,
    /// The options `cfg.filter` holds.
    euler: EulerConfig,
    ekf: Ekf,
    pending: PendingCovariance,
    noise: ProcessNoise,
    caps: VarianceCaps,
    min_cos_pitch: f32,
    gps_timeout_us: u64,
    last_imu_t: Option<u64>,
    gyro: Vec3,
    accel: Vec3,
    theta_dot: f32,
    interval: IntervalAccumulator,
    gps: GpsDifferencer,
    last_fix_t: Option<u64>,
    va: VaSlope,
    air_window: AirWindow,
    airborne_since: Option<u64>,
    health: Health,
    flags: Flags,
    last_update: UpdateRecord,
    gate_streak: [u16; 3],
    aligned: [bool; 3],
    fix_noise: FixNoise,
    /// Updates left before the settled covariance decimation applies.
    settling: u16,
    /// Largest admissible |gyro bias| per axis, rad/s: beyond it the filter has diverged
    /// and is re-seeded (`Ekf::check_state`).
    bias_limit: f32,
    /// `Ekf::flips` as the fix-noise cross-covariance last followed it.
    seen_flips: u32,
    /// `Ekf::resets` as last acted on (re-alignment).
    seen_resets: u32,
}

impl EulerAhrs {
    /// A new estimator at x(0|0) = 0 with P(0|0) from the configured initial σ: the shared
    /// options of `cfg` and the Euler filter's `e` (those `cfg.filter` holds; the facade
    /// passes them).
    pub fn new(cfg: Config, e: EulerConfig) -> Self {
        let (bias_psd, inv_tau) = match cfg.bias_model {
            BiasModel::GaussMarkov { sigma, tau } if tau.is_finite() && tau > 0.0 => {
                (2.0 * sigma * sigma / tau, 1.0 / tau)
            }
            BiasModel::GaussMarkov { .. } => (0.0, 0.0),
            BiasModel::RandomWalk { density } => (density * density, 0.0),
        };
        let va = cfg.init_sigma_attitude * cfg.init_sigma_attitude;
        let vb = cfg.init_sigma_bias * cfg.init_sigma_bias;
        let mut flags = Flags::default();
        flags.set(Flags::NO_GPS_YET, true);
        flags.set(Flags::ALIGNED, !e.init_from_measurement);
        EulerAhrs {
            ekf: Ekf::new([0.0; 6], [va, va, va, vb, vb, vb]),
            pending: PendingCovariance::default(),
            noise: ProcessNoise {
                gyro_psd: cfg.gyro_noise_density * cfg.gyro_noise_density,
                bias_psd,
                lambda: e.bias_lambda,
                attitude_psd: e.attitude_process_noise * e.attitude_process_noise,
                inv_tau,
            },
            // σ ≤ 1 rad: beyond that an angle is simply unknown, and larger values only cost precision.
            caps: VarianceCaps { attitude: 1.0, bias: (100.0 * vb).max(vb) },
            min_cos_pitch: crate::math::cos(e.gimbal_limit),
            gps_timeout_us: (cfg.gps_timeout.max(0.0) * 1e6) as u64,
            cfg,
            last_imu_t: None,
            gyro: [0.0; 3],
            accel: [0.0; 3],
            theta_dot: 0.0,
            interval: IntervalAccumulator::new(cfg.gps_latency),
            gps: GpsDifferencer::default(),
            last_fix_t: None,
            // EKF1 never pushes to it.
            va: VaSlope::new(match e.model {
                Model::Ekf2(e2) => e2.va_bin,
                Model::Ekf1(_) => Ekf2Config::THESIS.va_bin,
            }),
            air_window: AirWindow::default(),
            airborne_since: None,
            health: Health::default(),
            flags,
            last_update: UpdateRecord::default(),
            gate_streak: [0; 3],
            aligned: [!e.init_from_measurement; 3],
            fix_noise: FixNoise::default(),
            settling: e.covariance_settling_updates,
            // The bias σ cap (10× the initial σ: 20°/s by default), within the gyro's range.
            bias_limit: crate::math::sqrt((100.0 * vb).max(vb)).min(cfg.gyro_range),
            seen_flips: 0,
            seen_resets: 0,
            euler: e,
        }
    }

    /// After the filter was re-seeded (`Ekf::check_state`, or a non-finite P in
    /// `Ekf::condition`): every axis aligns again from the next measurement (as at start,
    /// when `init_from_measurement`), the fix-noise states and gate streaks start over.
    /// `Flags::ALIGNED` is clear until then; `Health::covariance_repairs` counted it.
    #[cold]
    fn after_reset(&mut self) {
        self.seen_resets = self.ekf.resets();
        self.seen_flips = self.ekf.flips();
        self.aligned = [!self.euler.init_from_measurement; 3];
        self.flags.set(Flags::ALIGNED, !self.euler.init_from_measurement);
        self.fix_noise.reset();
        self.gate_streak = [0; 3];
        self.restart_settling();
        self.health.covariance_repairs = self.ekf.repairs();
    }

    /// The filter (re)starts — initialisation, an axis (re)aligned, a gate recovery, a GPS
    /// re-seed: P follows at the settling decimation again (see the config fields).
    fn restart_settling(&mut self) {
        self.settling = self.euler.covariance_settling_updates;
    }

    /// IMU samples per covariance propagation now: the settling decimation until
    /// `covariance_settling_updates` updates have run since the filter last (re)started.
    fn decimation(&self) -> u8 {
        let n = self.cfg.covariance_decimation;
        if self.settling > 0 {
            n.min(self.euler.covariance_decimation_settling)
        } else {
            n
        }
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// One IMU sample at local time `t_us` (µs): gyro (rad/s) and specific force
    /// (m/s²), both body FRD. Runs the predict step over the time since the previous
    /// accepted sample. Returns `false` if the sample was rejected (and counted).
    pub fn on_imu(&mut self, t_us: u64, gyro: Vec3, accel: Vec3) -> bool {
        let within = crate::math::within;
        if !(within(&gyro, self.cfg.gyro_range) && within(&accel, self.cfg.accel_range)) {
            self.health.imu_rejected = self.health.imu_rejected.wrapping_add(1);
            return false;
        }
        if let Some(last) = self.last_imu_t {
            if t_us <= last {
                self.health.dt_nonpositive = self.health.dt_nonpositive.wrapping_add(1);
                return false;
            }
            // u32 µs → f32 is one instruction on the M4F; u64 → f32 is a library call.
            let dt_us = (t_us - last).min(u32::MAX as u64) as u32;
            let mut dt = dt_us as f32 * 1e-6;
            if dt > self.cfg.dt_max {
                dt = self.cfg.dt_max;
                self.health.dt_clamped = self.health.dt_clamped.wrapping_add(1);
            }
            let every = self.decimation();
            let (rates, guarded) = self.ekf.predict_decimated(
                dt,
                gyro,
                &self.noise,
                self.min_cos_pitch,
                self.caps,
                &mut self.pending,
                every,
            );
            self.theta_dot = rates[1];
            self.health.covariance_repairs = self.ekf.repairs();
            if self.ekf.resets() != self.seen_resets {
                self.after_reset();
            }
            self.flags.set(Flags::NEAR_GIMBAL_LOCK, guarded);
            if guarded {
                self.health.gimbal_steps = self.health.gimbal_steps.wrapping_add(1);
            }
        }
        self.last_imu_t = Some(t_us);
        self.gyro = gyro;
        self.accel = accel;
        self.health.imu_samples = self.health.imu_samples.wrapping_add(1);
        let x = self.ekf.x;
        self.interval.push(t_us, accel, [x[0], x[1], x[2]]);
        if self.ekf2_windowed() {
            self.air_window.push_imu(accel, gyro, x[0], x[1]);
        }

        if let Some(tf) = self.last_fix_t {
            let lost = t_us.saturating_sub(tf) > self.gps_timeout_us;
            if lost && !self.flags.has(Flags::GPS_LOST) {
                self.health.gps_outages = self.health.gps_outages.wrapping_add(1);
                self.gps.reset();
            }
            self.flags.set(Flags::GPS_LOST, lost);
        }
        true
    }

    /// One airspeed sample (true airspeed, m/s) at local time `t_us`. Used by EKF2.
    pub fn on_airspeed(&mut self, t_us: u64, va: f32) -> bool {
        if !(va.is_finite() && (0.0..=self.cfg.airspeed_range).contains(&va)) {
            self.health.airspeed_rejected = self.health.airspeed_rejected.wrapping_add(1);
            return false;
        }
        // Only EKF2 uses airspeed: EKF1 does not pay for its binning (a u64 division per
        // bin on the M4F, on the same samples as the 10 Hz GPS updates) or the window.
        if let Model::Ekf2(e2) = self.euler.model {
            self.va.push(t_us, va);
            self.air_window.push_airspeed(t_us, va);
            if va >= e2.min_airspeed {
                self.airborne_since.get_or_insert(t_us);
            } else {
                self.airborne_since = None;
            }
        }
        true
    }

    fn ekf2_windowed(&self) -> bool {
        matches!(self.euler.model, Model::Ekf2(e2) if e2.window > 0.0)
    }

    /// One GPS fix. Validates it, differences it against the previous fix and, when a
    /// difference is available, forms `z = [φm, θm, ψm]` with the configured model and
    /// runs the sequential update.
    pub fn on_gps(&mut self, fix: &GpsFix) -> GpsOutcome {
        let range = self.cfg.velocity_range;
        if !admit(fix, range, &mut self.last_fix_t, &mut self.flags, &mut self.health) {
            return GpsOutcome::Rejected;
        }
        let delta = match self.gps.push(fix, self.cfg.gps_min_interval, self.cfg.gps_max_interval) {
            Push::TooSoon => return GpsOutcome::Ignored,
            Push::Seeded => {
                self.health.gps_reseeds = self.health.gps_reseeds.wrapping_add(1);
                self.interval.restart();
                self.fix_noise.reset();
                self.restart_settling();
                self.air_window.restart(fix.t_us, fix.vel_ned_or_level());
                return GpsOutcome::Seeded;
            }
            Push::Delta(d) => d,
        };
        if self.euler.gps_disjoint_pairs {
            self.gps.reset();
        }
        let means = self.interval.take();
        self.update(fix.t_us, &delta, means, fix.vel_ned_or_level());
        GpsOutcome::Updated
    }


    /// Estimated attitude (rad).
    pub fn attitude(&self) -> Euler {
        Euler { roll: self.ekf.x[0], pitch: self.ekf.x[1], yaw: self.ekf.x[2] }
    }

    /// Estimated gyro bias [bp, bq, br], rad/s.
    pub fn gyro_bias(&self) -> Vec3 {
        [self.ekf.x[3], self.ekf.x[4], self.ekf.x[5]]
    }

    /// Latest bias-corrected body rates [p, q, r], rad/s.
    pub fn body_rates(&self) -> Vec3 {
        let b = self.gyro_bias();
        [self.gyro[0] - b[0], self.gyro[1] - b[1], self.gyro[2] - b[2]]
    }

    /// The full state `[φ, θ, ψ, bp, bq, br]`.
    #[cfg(any(test, feature = "internals"))]
    pub fn state(&self) -> [f32; 6] {
        self.ekf.x
    }

    /// The covariance P (symmetric, 6×6), as of the last covariance propagation: with
    /// `covariance_decimation` N > 1 it lags the state by up to N − 1 IMU samples.
    pub fn covariance(&self) -> &[[f32; 6]; 6] {
        &self.ekf.p
    }

    /// The covariance diagonal (rad², (rad/s)²).
    #[cfg(any(test, feature = "internals"))]
    pub fn covariance_diag(&self) -> [f32; 6] {
        core::array::from_fn(|i| self.ekf.p[i][i])
    }

    /// 1-σ of each state from P (rad, rad/s).
    #[cfg(any(test, feature = "internals"))]
    pub fn std_dev(&self) -> [f32; 6] {
        core::array::from_fn(|i| crate::math::sqrt(self.ekf.p[i][i]))
    }

    /// The latest measurement update (check `seq` to see whether a new one ran).
    pub fn last_update(&self) -> &UpdateRecord {
        &self.last_update
    }

    /// Event counters.
    pub fn health(&self) -> &Health {
        &self.health
    }

    /// Status flags.
    pub fn flags(&self) -> Flags {
        self.flags
    }

    /// Whether the thesis-exact EKF1 form is active (for labelling output).
    pub fn is_thesis_exact(&self) -> bool {
        matches!(self.euler.model, Model::Ekf1(e1) if e1.form == Ekf1Form::ThesisExact)
    }
}
