//! The thesis' Euler-state filter ([`crate::config::Filter::Euler`]), driven through
//! the facade [`crate::Ahrs`].
//!
//! Call order per IMU sample (the firmware and the host replay use the same):
//! 1. [`Ahrs::on_imu`] — validate, predict;
//! 2. [`Ahrs::on_airspeed`] — if an airspeed sample came with it;
//! 3. [`Ahrs::on_gps`] — for each GPS fix that became available since the last sample.
//!
//! Every call is O(1), allocation-free and panic-free; bad input is counted in
//! [`Health`] and never reaches the state.

use crate::config::{
    AccelAlignment, BiasModel, Config, Ekf1Form, Ekf2Config, EulerConfig, MeasNoise, Model,
    RotationHeading, GRAVITY,
};
use crate::ekf::fix_noise::{Coupling, FixNoise};
use crate::ekf::{Ekf, PendingCovariance, ProcessNoise, VarianceCaps};
use crate::fix::GpsFix;
use crate::health::{AxisStatus, AxisUpdate, Flags, Health, UpdateRecord};
use crate::math::{sincos, wrap_pi, Vec3};
use crate::measure::air_window::AirWindow;
use crate::measure::airspeed::{self, AirData};
use crate::measure::gps_delta::{GpsDelta, GpsDifferencer, Push};
use crate::measure::heading::{
    angle_of_attack_trig, course, sin_flight_path_angle, yaw_and_sin_cos_from_velocity,
    RollPitchTrig,
};
use crate::measure::interval::{IntervalAccumulator, IntervalMean};
use crate::measure::va_slope::VaSlope;
use crate::measure::{gps_accel, noise, RollPitch};
use crate::rotation::Euler;

/// What [`Ahrs::on_gps`](crate::Ahrs::on_gps) did with a fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GpsOutcome {
    /// Not usable (no fix, invalid, non-finite, out of range, out of order): counted, ignored.
    Rejected,
    /// Stored as the first fix of a new differencing sequence; no update.
    Seeded,
    /// Duplicate epoch: ignored.
    Ignored,
    /// A measurement update ran (see [`Ahrs::last_update`](crate::Ahrs::last_update)).
    Updated,
}

/// Airspeed samples older than this are not used by EKF2, µs.
const AIRSPEED_MAX_AGE_US: u64 = 500_000;

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
            bias_limit: libm::sqrtf((100.0 * vb).max(vb)).min(cfg.gyro_range),
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
        let in_order = self.last_fix_t.is_none_or(|t| fix.t_us > t);
        if !(fix.usable() && fix.velocity_within(self.cfg.velocity_range) && in_order) {
            self.health.gps_rejected = self.health.gps_rejected.wrapping_add(1);
            return GpsOutcome::Rejected;
        }
        self.last_fix_t = Some(fix.t_us);
        self.flags.set(Flags::NO_GPS_YET, false);
        self.flags.set(Flags::GPS_LOST, false);
        self.health.gps_fixes = self.health.gps_fixes.wrapping_add(1);
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


    /// Forms z and runs the three scalar updates. Not inlined: it runs once per fix, and
    /// kept out of the per-sample path it leaves that path compact (fewer saved registers
    /// and stack per IMU sample).
    #[inline(never)]
    fn update(&mut self, t_us: u64, d: &GpsDelta, means: Option<IntervalMean>, fix_vel: Vec3) {
        // P is propagated mid-way between fixes, not here (see `PendingCovariance::stagger`):
        // the update uses P as of the last propagation, at most N − 1 samples old.
        self.pending.stagger(self.decimation());
        self.settling = self.settling.saturating_sub(1);
        // P must be positive definite for the gains to mean anything (repaired if not);
        // its factor bounds the fix-noise cross-covariance below.
        let chol = self.ekf.ensure_positive_definite();
        if (self.ekf.flips() ^ self.seen_flips) & 1 != 0 {
            self.fix_noise.flip_pitch();
        }
        self.seen_flips = self.ekf.flips();
        let x = self.ekf.x;
        let now = ([x[0], x[1], x[2]], self.accel);
        // The attitude the measurement refers to, the accelerometer paired with it, and
        // the velocity whose course is the yaw measurement (the mean of the two fixes, or
        // the newest one: `mean_vel` says which, for its variance).
        let alignment = match self.euler.model {
            Model::Ekf1(e1) => Some(e1.accel_alignment),
            Model::Ekf2(_) => None,
        };
        let (att, accel, vel, mean_vel) = match (alignment, means) {
            (Some(AccelAlignment::IntervalMean), Some(m)) => (m.att, m.accel, d.mean_vel, true),
            (Some(AccelAlignment::Latest), Some(m)) => (m.latest_att, m.latest_accel, d.vel, false),
            _ => (now.0, now.1, d.vel, false),
        };
        // Sideslip test on the interval-mean lateral specific force, above its own noise
        // (real airframes vibrate: a 5 Hz GPS interval mean can carry ~0.5 m/s² of noise).
        // Compared as squares: |ay| > max(limit, 3·sem) ⟺ ay² > max(limit², 9·sem²).
        let ay_noise_sq = means.map_or(0.0, |m| 9.0 * m.accel_sem_sq[1]);
        let ay = means.map_or(self.accel[1], |m| m.accel[1]);
        let limit = self.euler.max_lateral_accel_yaw;
        let slipping = ay * ay > limit * limit && ay * ay > ay_noise_sq;
        // sin/cos of the referenced roll and pitch, once for every model below (near the
        // state's: from the predict's carried sin/cos).
        let trig = RollPitchTrig::from_sin_cos(self.ekf.roll_pitch_sin_cos(att[0], att[1]));

        // Yaw from course, optionally corrected for α in banked flight.
        let yaw_ok = vel[0] * vel[0] + vel[1] * vel[1]
            >= self.cfg.min_ground_speed_yaw * self.cfg.min_ground_speed_yaw;
        self.flags.set(Flags::YAW_UNOBSERVABLE, !yaw_ok);
        let aoa = if self.euler.heading_aoa_correction {
            let sin_gamma = if d.vd_valid { sin_flight_path_angle(vel) } else { 0.0 };
            angle_of_attack_trig(&trig, sin_gamma)
        } else {
            None
        };
        self.flags.set(Flags::SIDESLIP, slipping);
        // With its sin/cos: the yaw measurement is also the heading that rotates the GPS acceleration.
        let yaw_sc = if yaw_ok {
            Some(yaw_and_sin_cos_from_velocity(vel[0], vel[1], &trig, aoa.map(|a| a.sin_cos)))
        } else {
            None
        };
        let yaw = yaw_sc.map(|y| y.0);
        // In a slip the course is off by β: once yaw is aligned, the gyro carries it and the
        // course-derived yaw is not used as a measurement.
        let withhold_yaw = yaw.is_some() && slipping && self.aligned[2];
        if !yaw_ok {
            self.health.yaw_skipped_low_speed = self.health.yaw_skipped_low_speed.wrapping_add(1);
        } else if withhold_yaw {
            self.health.yaw_skipped_sideslip = self.health.yaw_skipped_sideslip.wrapping_add(1);
        }

        // Measurement variances: fixed (thesis), or from the inputs' noise plus a floor.
        let sq = |x: f32| x * x;
        // EKF2's roll/pitch R is its own (`Ekf2Config::rp_sigma`) whatever the noise model;
        // EKF1's is `sigma` when fixed, and set below from the sensors otherwise.
        let ekf2_rp = match self.euler.model {
            Model::Ekf1(_) => None,
            Model::Ekf2(e2) => Some(e2.rp_sigma),
        };
        let (mut var, sensor_noise, correlated_fix_noise) = match self.euler.meas_noise {
            MeasNoise::FromSensors { vel_sigma, floor, correlated_fix_noise } => {
                let [v0, v1] = d.speed_acc.map(|a| sq(a.unwrap_or(vel_sigma)));
                // The interval-mean velocity is half of each fix.
                let vel_var = if mean_vel { 0.25 * (v0 + v1) } else { v1 };
                let rp = ekf2_rp.unwrap_or([0.0; 2]);
                let yaw = sq(floor[2]) + noise::course_variance(vel_var, vel);
                ([sq(rp[0]), sq(rp[1]), yaw], Some((v0, v1, floor)), correlated_fix_noise)
            }
            MeasNoise::Fixed { sigma } => {
                let rp = ekf2_rp.unwrap_or([sigma[0], sigma[1]]);
                ([sq(rp[0]), sq(rp[1]), sq(sigma[2])], None, false)
            }
        };
        // EKF1 with R from the sensors: the fix shared with the previous difference (and the
        // heading shared with the yaw measurement) as states — when both fixes report their
        // speed accuracy. The states carry a posterior mean of the fix noise into the next
        // measurement, so a wrong σ injects error where the white model only loses gain: with
        // a guessed σ (NMEA) the white model stays (the PX4 logs, no sAcc, with arrival-time
        // jitter: their differenced acceleration has lag-1 correlation +0.3…+0.7, not −½).
        let reported = d.speed_acc[0].is_some() && d.speed_acc[1].is_some();
        let correlated =
            matches!(self.euler.model, Model::Ekf1(_)) && correlated_fix_noise && reported;
        let mut coupling: [Option<Coupling>; 3] = [None; 3];

        // The roll/pitch the measurement refers to (EKF2 windowed: the window's mean).
        let mut rp_att = [att[0], att[1]];
        let rp: RollPitch = match self.euler.model {
            Model::Ekf1(e1) => {
                // Before yaw is aligned the prediction is meaningless: use the course.
                // Without a usable course, the predicted yaw is the only heading there is.
                // With the heading's variance: the yaw measurement's R, or the predicted yaw's P.
                let p_yaw = self.ekf.p[2][2];
                // `shared`: the heading is the yaw measurement itself (its error is common).
                // The heading as (sin, cos).
                let (heading, heading_var, shared) = match (e1.rotation_heading, yaw_sc)
                {
                    (RotationHeading::PredictedYaw, Some((_, y))) if !self.aligned[2] => {
                        (y, var[2], !withhold_yaw)
                    }
                    (RotationHeading::Course, Some(_)) => {
                        (sincos(course(vel[0], vel[1])), var[2], false)
                    }
                    (RotationHeading::CorrectedCourse, Some(_)) if withhold_yaw => {
                        (sincos(att[2]), p_yaw, false)
                    }
                    (RotationHeading::CorrectedCourse, Some((_, y))) => (y, var[2], true),
                    _ => (sincos(att[2]), p_yaw, false),
                };
                let r = gps_accel::heading_frame_specific_force_sc(d.accel_ned, heading);
                let rp = gps_accel::measure_near(e1.form, accel, r, &trig);
                if let Some((v0, v1, floor)) = sensor_noise {
                    let sem_sq = means.map_or([0.0; 3], |m| m.accel_sem_sq);
                    let r_var = noise::differenced_accel_variance(v0 + v1, d.dt);
                    let pitch_sc = rp.pitch_sin_cos.unwrap_or((trig.st, trig.ct));
                    let n = noise::ekf1_roll_pitch_noise(
                        e1.form,
                        accel,
                        sem_sq,
                        r,
                        pitch_sc,
                    );
                    let shared = correlated && shared;
                    if correlated {
                        // C from the last update to now, linearised at the interval's mean attitude.
                        let lin = crate::ekf::process::linearize_sc(
                            (trig.sf, trig.cf),
                            (trig.st, trig.ct),
                            self.body_rates(),
                            self.min_cos_pitch,
                        );
                        self.fix_noise.begin(
                            &lin.a,
                            &lin.b,
                            self.noise.inv_tau,
                            d.dt,
                            v0,
                            if shared { var[2] } else { 0.0 },
                        );
                        if self.fix_noise.bound_cross(&chol) {
                            self.ekf.count_repair();
                        }
                    }
                    for j in 0..2 {
                        // White: floor and accelerometer; the rotation heading's error (white,
                        // or a state shared with the yaw measurement); the GPS part as white,
                        // or through the fix-noise states.
                        let white = sq(floor[j]) + n.accel_var[j];
                        // (The white model predates the heading term and keeps its figures.)
                        let hdg =
                            if correlated { sq(n.heading_gain[j]) * heading_var } else { 0.0 };
                        let gps = n.gain_sq[j] * r_var;
                        var[j] = white + hdg + gps;
                        if correlated {
                            let k = if shared { n.heading_gain[j] } else { 0.0 };
                            coupling[j] = Some(Coupling {
                                h: n.gain(j) / d.dt,
                                fresh_var: v1,
                                k,
                                white_var: var[j],
                            });
                            var[j] = white + if shared { 0.0 } else { hdg };
                        }
                    }
                    if shared {
                        // The yaw measurement's whole variance is e's.
                        coupling[2] =
                            Some(Coupling { k: 1.0, white_var: var[2], ..Coupling::default() });
                        var[2] = 0.0;
                    }
                }
                rp
            }
            Model::Ekf2(e2) if e2.window > 0.0 => {
                let (rp, mean_att, spread_var) =
                    self.airspeed_roll_pitch_windowed(&e2, t_us, fix_vel);
                rp_att = mean_att;
                var[0] += spread_var[0];
                var[1] += spread_var[1];
                rp
            }
            Model::Ekf2(e2) => self.airspeed_roll_pitch(&e2, t_us, d, (att[0], att[1])),
        };
        self.health.solver_clamped = self.health.solver_clamped.wrapping_add(rp.clamped as u32);
        if rp.degenerate {
            self.health.solver_degenerate = self.health.solver_degenerate.wrapping_add(1);
        }

        let alpha_sin_cos = aoa.map_or((0.0, 0.0), |a| a.sin_cos);
        let z = [rp.roll, rp.pitch, if withhold_yaw { None } else { yaw }];
        let att = [rp_att[0], rp_att[1], att[2]];
        // Written in place (no 72-byte record copy at the end).
        self.last_update = UpdateRecord {
            t_us,
            seq: self.last_update.seq.wrapping_add(1),
            axes: [AxisUpdate::default(); 3],
            course: AxisUpdate::default(),
            alpha_sin_cos,
        };
        // Yaw first when its error is a shared state: the yaw innovation then tells the
        // heading error (to within the yaw estimate's σ) before roll and pitch use it — the
        // same posterior in any order, but the roll/pitch gates and NIS see e's posterior,
        // not the yaw R's sideslip allowance (2°, set for slipping flight).
        let order: [usize; 3] = if correlated { [2, 0, 1] } else { [0, 1, 2] };
        for i in order {
            let c = coupling[i];
            let Some(zi) = z[i] else {
                // Not measured: the new fix's noise on this axis stays its prior.
                if let (Some(c), true) = (c, i < 2) {
                    self.fix_noise.forget(i, c.fresh_var);
                }
                continue;
            };
            // Refer the measurement to the current time: the innovation is taken
            // against the attitude it was measured at (`att`), applied to the state now.
            let shift = if i == 1 { x[i] - att[i] } else { wrap_pi(x[i] - att[i]) };
            let a = self.update_axis(i, zi, shift, var[i], c, correlated);
            self.last_update.axes[i] = a;
        }
        self.ekf.normalize_angles();
        self.ekf.check_state(self.caps, self.bias_limit);
        self.health.covariance_repairs = self.ekf.repairs();
        if self.ekf.resets() != self.seen_resets {
            self.after_reset();
        }
        self.health.updates = self.health.updates.wrapping_add(1);
        if self.ekf2_windowed() {
            self.air_window.shift_att(wrap_pi(self.ekf.x[0] - x[0]), self.ekf.x[1] - x[1]);
        }
        let all = self.aligned.iter().all(|a| *a);
        self.flags.set(Flags::ALIGNED, all);
    }

    /// EKF2 roll/pitch from airspeed.
    fn airspeed_roll_pitch(
        &self,
        e2: &Ekf2Config,
        t_us: u64,
        d: &GpsDelta,
        pred: (f32, f32),
    ) -> RollPitch {
        let est = self
            .va
            .estimate(e2.va_dot_window)
            .filter(|e| t_us.saturating_sub(e.t_us) <= AIRSPEED_MAX_AGE_US);
        let Some(est) = est else {
            return RollPitch { degenerate: true, ..RollPitch::default() };
        };
        let air = AirData {
            va: est.va,
            va_dot: est.va_dot,
            gamma: d.gamma(),
            gamma_dot: d.gamma_dot(),
            theta_dot: self.theta_dot,
            rates: self.body_rates(),
        };
        airspeed::measure(self.accel, &air, pred, e2.min_airspeed)
    }

    /// EKF2 roll/pitch from the means over the window that the fix at `t_us` closes
    /// (`measure::air_window`), referred to the window's mean predicted roll/pitch
    /// (returned with it). No measurement while the window is shorter than
    /// `Ekf2Config::window`, before `airborne_hold` s of airspeed ≥ `min_airspeed`, or between
    /// flight and the ground mode (`ground_speed_static`).
    /// Also returns the variance (rad²) the window's inner scatter adds to roll and pitch.
    fn airspeed_roll_pitch_windowed(
        &mut self,
        c: &Ekf2Config,
        t_us: u64,
        vel: Vec3,
    ) -> (RollPitch, [f32; 2], [f32; 2]) {
        let none = RollPitch::default();
        // Before roll/pitch are aligned the predicted attitude is not yet a reference
        // that can carry a window mean to the present (its gyro-propagated change over
        // the window is wrong): initialise from one GPS interval.
        let min_s = if self.aligned[0] && self.aligned[1] { c.window } else { 0.0 };
        let Some(w) = self.air_window.close_interval(t_us, vel, min_s) else {
            return (none, [0.0; 2], [0.0; 2]);
        };
        let x = &self.ekf.x;
        let held = self
            .airborne_since
            .is_some_and(|s| t_us.saturating_sub(s) as f32 * 1e-6 >= c.airborne_hold);
        let has_va = w.va_samples > 0;
        let coordinated = w.lateral_max <= c.max_lateral_accel;
        let flying = has_va && held && w.va_range[0] >= c.min_airspeed && coordinated;
        let parked =
            has_va && w.va_range[1] < c.min_airspeed && w.ground_speed_max < c.ground_speed_static;
        let air = if flying {
            // γ of the air-relative velocity (vD is not changed by a horizontal wind).
            let gamma = crate::math::asin((-w.vel[2] / w.va).clamp(-1.0, 1.0));
            // k = q − α̇: the mean of α̇ over the window is Δα/W, neglected like Δ(Va sβ)/W.
            AirData {
                va: w.va,
                va_dot: w.va_dot,
                gamma,
                gamma_dot: 0.0,
                theta_dot: 0.0,
                rates: [w.gyro[0] - x[3], w.gyro[1] - x[4], w.gyro[2] - x[5]],
            }
        } else if parked {
            AirData {
                va: 0.0,
                va_dot: 0.0,
                gamma: 0.0,
                gamma_dot: 0.0,
                theta_dot: 0.0,
                rates: [0.0; 3],
            }
        } else {
            return (none, w.att, [0.0; 2]);
        };
        let rp = airspeed::measure(
            w.accel,
            &air,
            (w.att[0], w.att[1]),
            if flying { c.min_airspeed } else { 0.0 },
        );
        // Scatter of the per-interval right-hand sides (Dutch roll, turbulence): their
        // standard error, mapped to angle by ∂(g sφ cθ)/∂φ and ∂(g sθ)/∂θ.
        let (sa, ca) = crate::math::sincos(w.att[1] - air.gamma);
        let k = w.intervals;
        let roll_rhs =
            self.air_window.spread(k, [0.0, -1.0, 0.0], [-air.va * sa, 0.0, air.va * ca])
                / k as f32;
        let pitch_rhs =
            self.air_window.spread(k, [1.0, 0.0, 0.0], [0.0, -air.va * sa, 0.0]) / k as f32;
        let (cr, cp) =
            (crate::math::cos(w.att[0]).abs().max(0.2), crate::math::cos(w.att[1]).abs().max(0.2));
        let g2 = GRAVITY * GRAVITY;
        (rp, w.att, [roll_rhs / (g2 * cr * cr * cp * cp), pitch_rhs / (g2 * cp * cp)])
    }

    /// Initialises, gates and applies one axis with measurement variance `r` (rad²).
    /// `shift` = x_now − x_at_measurement. `correlated`: the update runs on the filter
    /// augmented by the fix-noise states (`ekf::fix_noise`), `coupling` says how this
    /// axis depends on them (`r` is then the white part only).
    fn update_axis(
        &mut self,
        i: usize,
        z: f32,
        shift: f32,
        r: f32,
        coupling: Option<Coupling>,
        correlated: bool,
    ) -> AxisUpdate {
        let z_now = if i == 1 { z + shift } else { wrap_pi(z + shift) };
        if !self.aligned[i] {
            let nu = wrap_pi(z_now - self.ekf.x[i]);
            let r_init = coupling.map_or(r, |c| c.white_var);
            self.ekf.reset_axis(i, z_now, r_init);
            if correlated {
                self.fix_noise.decorrelate(i);
                if let (Some(c), true) = (coupling, i < 2) {
                    self.fix_noise.forget(i, c.fresh_var);
                }
            }
            self.aligned[i] = true;
            self.restart_settling();
            return AxisUpdate {
                z,
                innovation: nu,
                variance: r_init,
                status: AxisStatus::Initialised,
            };
        }
        let gate = self.euler.gate_chi2[i];
        let mut res = if correlated {
            self.fix_noise.update_axis(
                &mut self.ekf,
                i,
                z_now,
                r,
                coupling.unwrap_or_default(),
                gate,
            )
        } else {
            self.ekf.update_axis(i, z_now, r, gate)
        };
        let mut status = AxisStatus::Accepted;
        if !res.applied {
            self.gate_streak[i] = self.gate_streak[i].saturating_add(1);
            if self.gate_streak[i] >= self.euler.gate_max_consecutive && res.innovation.is_finite() {
                // Recovery: the estimate has left the measurement for too long; trust it again.
                self.ekf.inflate_axis(i, res.innovation * res.innovation);
                // The fix noise of this axis was reset by the gated update: the forced one
                // takes the difference as white (its full variance).
                let r_forced = coupling.map_or(r, |c| c.white_var);
                let forced = if correlated {
                    self.fix_noise.decorrelate(i);
                    self.fix_noise.update_axis(
                        &mut self.ekf,
                        i,
                        z_now,
                        r_forced,
                        Coupling::default(),
                        f32::INFINITY,
                    )
                } else {
                    self.ekf.update_axis(i, z_now, r_forced, f32::INFINITY)
                };
                res = crate::ekf::ScalarUpdate {
                    innovation: res.innovation,
                    variance: res.variance,
                    applied: forced.applied,
                };
                status = AxisStatus::ForcedAfterGate;
                self.health.gate_resets[i] = self.health.gate_resets[i].wrapping_add(1);
                self.restart_settling();
                self.gate_streak[i] = 0;
            } else {
                status = AxisStatus::Gated;
                self.health.gate_rejections[i] = self.health.gate_rejections[i].wrapping_add(1);
            }
        } else {
            self.gate_streak[i] = 0;
        }
        AxisUpdate { z, innovation: res.innovation, variance: res.variance, status }
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
