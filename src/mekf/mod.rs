//! The quaternion filter: a six-state multiplicative EKF (attitude error + gyro
//! biases) valid at every attitude, with one file per aid source, each holding its
//! own control policy and fusion (the layout of PX4's EKF2):
//!
//! - [`gps_accel`] — the GPS acceleration against the accelerometer, as a 3-D vector;
//! - [`heading_accel`] — the heading solved from the horizontal GPS acceleration while it
//!   is too uncertain for the linear update (after alignment, after a long straight leg);
//! - [`course`] — the air-relative course, for the heading where nothing else sees it;
//! - [`wind`] — the wind (from airspeed, or from turn circles without it), along the
//!   air-velocity direction of [`aoa`]'s learnt angle of attack.
//!
//! [`filter`] holds the state and covariance, [`dv_window`] pairs IMU samples with
//! GPS intervals, [`quat`] the rotation algebra.

pub mod aoa;
pub mod course;
pub mod dv_window;
pub mod filter;
pub mod gps_accel;
pub mod heading_accel;
pub mod latency;
pub mod quat;
#[cfg(feature = "gyro-scale-states")]
pub mod scale;
pub mod unmodelled;
pub mod vel_noise;
pub mod vibration;
pub mod wind;

use crate::estimator::GpsOutcome;
use crate::config::{Config, QuatConfig, GRAVITY};
use crate::fix::GpsFix;
use crate::health::{AxisStatus, AxisUpdate, Flags, Health, UpdateRecord};
use crate::math::{Mat3, Vec3};
use crate::measure::gps_delta::{GpsDelta, GpsDifferencer, Push};
use crate::rotation::Euler;
use aoa::AngleOfAttack;
use dv_window::{DvWindow, WindowMean};
use filter::{Mekf, Noise};
use heading_accel::HeadingFromAccel;
use latency::{Jerk, LatencyTracker};
use vel_noise::VelNoise;
use wind::{Wind, WindNoise};

/// The angle of attack allowed for when a banked course aligns the heading, rad.
const ALPHA_ALLOWANCE: f32 = 0.15;

/// Fix intervals shorter than this (s) run the wind filter every other fix.
const WIND_MIN_INTERVAL: f32 = 0.15;

/// The variance of a heading nothing has measured, rad² (1 rad σ): before the first
/// course, and after the GPS acceleration failed its gate persistently.
const UNKNOWN_HEADING_VAR: f32 = 1.0;

/// Each gated GPS-acceleration update multiplies the attitude variance by this: the
/// residual says the attitude is further off than P claims (σ × 1.41 per gated update).
const GATE_INFLATION: f32 = 2.0;
/// No inflation beyond this attitude variance per axis, rad² ((10°)²): further off, the
/// linear update is no longer a correction, and the re-alignment of
/// `gate_max_consecutive` takes over.
const MAX_INFLATED_VAR: f32 = 0.0305;

/// Consecutive gated updates that make the attitude doubtful (`Flags::UNRELIABLE`), and
/// consecutive accepted ones that clear it again.
const DOUBT_AFTER: u16 = 3;
const TRUST_AFTER: u16 = 10;

/// The yaw variance of an alignment on a course the slip may be off (lateral specific
/// force beyond the limit, or banked beyond it), rad² ((15°)² on top of the crab angle).
const SLIPPING_COURSE_VAR: f32 = 0.0685;

/// Largest receiver latency tracked, s (the delay line spans 0.4 s at 160 Hz).
const MAX_LATENCY: f32 = 0.3;

/// Configuration thresholds in the form the hot paths compare with, computed once in
/// [`QuatAhrs::new`]: f32 ↔ u64 conversions and sines are library calls on the M4F.
#[derive(Debug, Clone, Copy)]
struct Limits {
    /// `gps_timeout`, µs.
    gps_timeout_us: u64,
    /// `wind_heading_memory`, µs.
    wind_memory_us: u64,
    /// `course_interval`, µs.
    course_interval_us: u64,
    /// sin `course_max_bank`, and sin of the wider bank allowed while aligning.
    sin_bank: f32,
    sin_align_bank: f32,
    /// [`vibration::limit`] of the configuration.
    vib: f32,
}

impl Limits {
    fn new(cfg: &Config, q: &QuatConfig) -> Self {
        let us = |s: f32| (s.max(0.0) * 1e6) as u64;
        Limits {
            gps_timeout_us: us(cfg.gps_timeout),
            wind_memory_us: us(q.wind_heading_memory),
            course_interval_us: us(q.course_interval),
            sin_bank: crate::math::sin(q.course_max_bank),
            sin_align_bank: crate::math::sin(q.course_max_bank.max(q.course_align_max_bank)),
            vib: vibration::limit(q.vibration_ratio, q.accel_noise_density),
        }
    }
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
    gyro: Vec3,
    since_propagation: u8,
    airspeed_sum: f32,
    airspeed_n: u16,
    tilt_aligned: bool,
    yaw_aligned: bool,
    gate_streak: u16,
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
    /// [`unmodelled::heading_drift_variance`] as of the last update, rad²: added to each
    /// reported heading variance (kept, not computed per sample: a u64 → f32 conversion is
    /// a library call on the M4F, and every sample reports σ).
    heading_drift: f32,
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
            trust_streak: 0,
            health: Health::default(),
            flags,
            last_update: UpdateRecord::default(),
            unmodelled: unmodelled::body_variance(&q),
            heading_bias: unmodelled::HeadingBias::default(),
            heading_drift: 0.0,
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

    /// The attitude step, the NED velocity increment at the step's mid-attitude
    /// (`R·(f − ½ φ × f)·Δt`) into the GPS window, and P every N samples.
    #[inline]
    fn integrate(&mut self, t_us: u64, gyro: Vec3, accel: Vec3, dt: f32) {
        let phi = self.ekf.step(gyro, dt);
        let c = quat::cross(phi, accel);
        let f_mid = [accel[0] - 0.5 * c[0], accel[1] - 0.5 * c[1], accel[2] - 0.5 * c[2]];
        let r = self.ekf.dcm();
        let dv = quat::rotate(r, [f_mid[0] * dt, f_mid[1] * dt, f_mid[2] * dt]);
        self.window.push(t_us, dv, accel, dt);
        self.since_propagation += 1;
        if self.since_propagation >= self.cfg.covariance_decimation.max(1) {
            self.propagate();
        }
    }

    fn propagate(&mut self) {
        self.ekf.propagate(&self.noise);
        self.since_propagation = 0;
    }

    /// Before any GPS: roll and pitch from the accelerometer as if unaccelerated.
    fn level_from_accel(&mut self, f: Vec3) {
        let roll = crate::math::atan2(-f[1], -f[2]);
        let pitch = crate::math::atan2(f[0], crate::math::hypot(f[1], f[2]));
        let va = self.cfg.init_sigma_attitude * self.cfg.init_sigma_attitude;
        let q = quat::from_euler(&Euler { roll, pitch, yaw: 0.0 });
        self.ekf.reset_attitude(q, [va, va, UNKNOWN_HEADING_VAR]);
    }

    fn check_gps_timeout(&mut self, t_us: u64) {
        if let Some(tf) = self.last_fix_t {
            let lost = t_us.saturating_sub(tf) > self.lim.gps_timeout_us;
            if lost && !self.flags.has(Flags::GPS_LOST) {
                self.health.gps_outages = self.health.gps_outages.wrapping_add(1);
                self.gps.reset();
            }
            self.flags.set(Flags::GPS_LOST, lost);
        }
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
        let in_order = self.last_fix_t.is_none_or(|t| fix.t_us > t);
        let vel_ok = fix.velocity_within(self.cfg.velocity_range);
        if !(fix.usable() && vel_ok && in_order && fix.speed_acc.is_none_or(|a| a >= 0.0)) {
            self.health.gps_rejected = self.health.gps_rejected.wrapping_add(1);
            return GpsOutcome::Rejected;
        }
        self.last_fix_t = Some(fix.t_us);
        self.flags.set(Flags::NO_GPS_YET, false);
        self.flags.set(Flags::GPS_LOST, false);
        self.health.gps_fixes = self.health.gps_fixes.wrapping_add(1);
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
            let v_air = self.air_velocity(d.vel);
            let (r, min_speed) = (self.ekf.dcm(), self.cfg.min_ground_speed_yaw);
            let sin_max = self.course_sin_bank();
            let course_ok = course::usable(r, v_air, w.f_body[1], &self.quat, min_speed, sin_max);
            let flying = v_air[0] * v_air[0] + v_air[1] * v_air[1] >= min_speed * min_speed;
            self.align(d, w, course_ok, flying);
        } else {
            self.fuse_gps_accel(t_us, d, w, vel_var);
        }
        self.update_wind(t_us, d, w, vel_var[1]);
        self.fuse_course(t_us, d, w, vel_var[1]);
        self.heading_drift = self.heading_seen_t.map_or(0.0, |seen| {
            unmodelled::heading_drift_variance(t_us, seen, self.quat.heading_rate_sigma)
        });
        self.health.updates = self.health.updates.wrapping_add(1);
        self.flags.set(Flags::ALIGNED, self.tilt_aligned && self.yaw_aligned);
        self.flags
            .set(Flags::SIDESLIP, libm::fabsf(w.f_body[1]) > self.quat.course_max_lateral);
        let vib = vibration::excessive(w, self.lim.vib);
        self.flags.set(Flags::VIBRATION, vib);
        self.health.vibration = self.health.vibration.wrapping_add(vib as u32);
    }

    /// The two fixes' velocity variances, (m/s)²: each fix's report (or the guess) times the
    /// learnt scale of the reports; or as reported.
    fn vel_var(&mut self, d: &GpsDelta) -> [f32; 2] {
        let guess = self.quat.unreported_vel_sigma;
        if self.quat.learn_vel_noise {
            let n = &mut self.vel_noise;
            n.reference(d.speed_acc[1].unwrap_or(guess));
            return d.speed_acc.map(|a| n.variance(a.unwrap_or(guess)));
        }
        d.speed_acc.map(|a| {
            let s = a.unwrap_or(guess);
            s * s
        })
    }

    /// Ground velocity minus the wind estimate (the ground velocity before it starts).
    fn air_velocity(&self, v: Vec3) -> Vec3 {
        let w = if self.wind.started() { self.wind.wind() } else { [0.0; 3] };
        [v[0] - w[0], v[1] - w[1], v[2]]
    }

    /// Aligns the attitude with the interval's specific forces: the shortest rotation
    /// that takes the IMU's NED specific force onto the GPS one (any attitude: nothing
    /// assumes upright flight), after turning the heading onto the course when usable.
    ///
    /// In flight the course gives the heading first even where it is not `course_ok`
    /// (slipping, steeply banked: a wider σ), because the specific force is only matched
    /// as a vector: in a turn its horizontal part, rotated by a wrong heading, would be
    /// read as tilt. The tilt's variance takes the heading's share, `(|f_h|/|f|)²·σ_ψ²`.
    fn align(&mut self, d: &GpsDelta, w: &WindowMean, course_ok: bool, flying: bool) {
        let heading_known = course_ok || flying;
        if heading_known {
            let (y, _, _) = course::residual(&self.flow_axis(w), d.vel, 0.0, 0.0, &self.quat);
            self.ekf.set_heading(y, 1.0);
        }
        let r = *self.ekf.dcm();
        let f_imu = quat::rotate(&r, w.f_body);
        let f_gps = [d.accel_ned[0], d.accel_ned[1], d.accel_ned[2] - GRAVITY];
        let f_gps = if d.vd_valid { f_gps } else { [f_gps[0], f_gps[1], -GRAVITY] };
        let q = quat::mul(&quat::between(f_imu, f_gps), &self.ekf.quaternion());
        let s = 3.0 * crate::math::PI / 180.0;
        let yaw_var = match (course_ok, flying) {
            (true, _) => self.crab_var(d.vel),
            (false, true) => self.crab_var(d.vel) + SLIPPING_COURSE_VAR,
            _ => UNKNOWN_HEADING_VAR,
        };
        let fh2 = f_gps[0] * f_gps[0] + f_gps[1] * f_gps[1];
        let f2 = crate::math::max(fh2 + f_gps[2] * f_gps[2], 1.0);
        let tilt_var = s * s + crate::math::min(fh2 / f2, 1.0) * yaw_var;
        self.ekf.reset_attitude(q, [tilt_var, tilt_var, yaw_var]);
        self.tilt_aligned = true;
        self.yaw_aligned = heading_known;
        self.trust_streak = 0;
        self.latency.restart();
        self.vel_noise.restart();
        self.heading_accel.reset(); // the attitude was reset: the sums describe another heading
        self.gate_streak = 0;
        self.last_update.axes[0].status = AxisStatus::Initialised;
        self.last_update.axes[1].status = AxisStatus::Initialised;
    }

    /// Turns the heading by `angle` (rad, about NED down) with variance `var` (rad²); the
    /// direct solution's sums no longer describe the new heading.
    fn set_heading(&mut self, angle: f32, var: f32) {
        self.ekf.set_heading(angle, var);
        self.heading_accel.reset();
        self.vel_noise.restart();
    }

    /// The attitude at the epoch of the newest fix, `gps_latency` ago: the present one
    /// turned back about NED down by the heading rate (the course is compared near
    /// wings-level, where that is the whole of the change). In a 13°/s turn a 0.2 s
    /// receiver delay is 2.6° of heading.
    fn dcm_at_epoch(&self) -> Mat3 {
        let r = self.ekf.dcm();
        let w = self.body_rates();
        let psi_dot = r[2][0] * w[0] + r[2][1] * w[1] + r[2][2] * w[2];
        let (s, c) = crate::math::sincos(-psi_dot * self.latency.value());
        let mut out = *r;
        for j in 0..3 {
            out[0][j] = c * r[0][j] - s * r[1][j];
            out[1][j] = s * r[0][j] + c * r[1][j];
        }
        out
    }

    /// The variance of the course as a heading while the wind is unknown: the crab
    /// angle `crab_wind` could cause at this speed, the slip floor, and in a bank the
    /// angle of attack's share (`α·sin φ`, the body axis above the velocity).
    fn crab_var(&self, v: Vec3) -> f32 {
        let speed = crate::math::max(crate::math::hypot(v[0], v[1]), 1.0);
        let s = crate::math::min(self.quat.crab_wind / speed, 1.0);
        let bank = ALPHA_ALLOWANCE * self.ekf.dcm()[2][1];
        s * s + self.quat.course_sigma * self.quat.course_sigma + bank * bank
    }

    /// The sine of the bank limit for a course: wider while the heading is not yet
    /// aligned (a loiter may never level its wings; the crab allowance covers the α
    /// offset).
    fn course_sin_bank(&self) -> f32 {
        if self.heading_coarse() {
            self.lim.sin_align_bank
        } else {
            self.lim.sin_bank
        }
    }

    /// Whether the heading is unaligned or too uncertain for linear updates
    /// ([`heading_accel::COARSE_VAR`]): then it is solved directly, not fused.
    fn heading_coarse(&self) -> bool {
        !self.yaw_aligned || self.ekf.covariance()[2][2] > heading_accel::COARSE_VAR
    }

    /// A latency error δd leaves `δd·ȧ` in the GPS-acceleration residual, and in a
    /// steady turn `δd·ω` of heading error looks the same: R gets `(σ_d·ȧ)²` per axis.
    fn widen_for_latency(&self, m: &mut gps_accel::Measurement, jerk: Option<Jerk>) {
        if let Some(Jerk { j, .. }) = jerk {
            let s2 = self.quat.latency_sigma * self.quat.latency_sigma;
            for i in 0..3 {
                m.r[i] += s2 * j[i] * j[i];
            }
        }
    }

    fn fuse_gps_accel(&mut self, t_us: u64, d: &GpsDelta, w: &WindowMean, vel_var: [f32; 2]) {
        let lag = self.latency.value();
        let p = self.ekf.covariance();
        let att_var = [p[0][0], p[1][1], p[2][2]];
        let mut m = gps_accel::measurement(
            d,
            w,
            self.ekf.dcm(),
            vel_var,
            &self.quat,
            self.noise.gyro_psd,
            lag,
            att_var,
        );
        let jerk = self.latency.jerk(w.f_ned, w.duration);
        self.widen_for_latency(&mut m, jerk);
        let coarse = self.heading_coarse();
        let sees_heading = !coarse && gps_accel::sees_heading(&m, w, att_var);
        // The noise of one horizontal axis before the heading's share is folded in, with
        // the tilt's: what the direct heading solution compares against.
        let h_var = if coarse {
            0.5 * (m.r[0] + m.r[1]) + GRAVITY * GRAVITY * crate::math::max(att_var[0], att_var[1])
        } else {
            0.0
        };
        if !sees_heading {
            // The heading is unknown, or the horizontal specific force is no larger than
            // what tilt error and noise make of it: the heading is noise to the
            // horizontal axes here, not a state (else GPS noise across a spurious
            // horizontal f̄ would be read as heading).
            let pyaw = att_var[2];
            for i in 0..3 {
                let hd = m.h[i][2];
                m.r[i] += hd * hd * pyaw;
                m.h[i][2] = 0.0;
            }
        }
        // Learnt, the noise is white by construction; as reported, only when both are.
        let reported = d.speed_acc[0].is_some() && d.speed_acc[1].is_some();
        let white_known = reported || self.quat.learn_vel_noise;
        let fix_var = (white_known && self.quat.fix_noise_states).then_some(vel_var);
        let res = gps_accel::fuse(&mut self.ekf, &m, fix_var, d.dt, &self.quat);
        if self.quat.learn_vel_noise {
            self.learn_vel_noise(&m, w, &res, d);
        }
        let status = if res.applied { AxisStatus::Accepted } else { AxisStatus::Gated };
        for i in 0..3 {
            self.last_update.axes[i] = AxisUpdate {
                z: d.accel_ned[i],
                innovation: m.y[i],
                variance: res.s_diag[i],
                status,
            };
        }
        if res.applied {
            self.gate_streak = 0;
            self.trust_streak = self.trust_streak.saturating_add(1);
            if self.trust_streak >= TRUST_AFTER {
                self.flags.set(Flags::UNRELIABLE, false);
            }
            let f_var = w.noise_sq[0] + w.noise_sq[1] + w.noise_sq[2];
            if self.latency.observe(m.y, w.f_ned, f_var, w.duration, d.vd_valid, jerk) {
                self.window.set_delay(self.latency.value());
            }
            if sees_heading {
                let fh2 = w.f_ned[0] * w.f_ned[0] + w.f_ned[1] * w.f_ned[1];
                self.heading_bias.observe(fh2, self.quat.accel_bias_sigma);
                // For the wind, only a manoeuvre (the direct solution's threshold, a 17°
                // bank) counts: turbulence passes the 3σ test too, and a wind fitted to a
                // heading it barely saw would hold it.
                if heading_accel::manoeuvre(fh2) {
                    self.heading_seen_t = Some(t_us);
                }
            } else if coarse {
                let pyaw = self.ekf.covariance()[2][2];
                let a = d.accel_ned;
                if let Some((dpsi, var)) = self.heading_accel.observe(w.f_ned, a, h_var, pyaw) {
                    self.set_heading(dpsi, var);
                    self.yaw_aligned = true;
                    self.heading_seen_t = Some(t_us);
                    self.last_update.axes[2].status = AxisStatus::Initialised;
                }
            }
            return;
        }
        self.health.gate_rejections[0] = self.health.gate_rejections[0].wrapping_add(1);
        self.gate_streak = self.gate_streak.saturating_add(1);
        let p = self.ekf.covariance();
        // From the second in a row once settled (one gated update is an outlier as often
        // as not), from the first while settling after an alignment or a doubt.
        let settling = self.trust_streak < TRUST_AFTER;
        let due = self.gate_streak >= 2 || settling;
        if due && crate::math::max(p[0][0], p[1][1]) < MAX_INFLATED_VAR {
            self.ekf.inflate_attitude(GATE_INFLATION);
        }
        if self.gate_streak >= DOUBT_AFTER {
            self.flags.set(Flags::UNRELIABLE, true);
            self.trust_streak = 0;
        }
        if self.gate_streak < self.quat.gate_max_consecutive {
            return;
        }
        self.gate_streak = 0;
        if !coarse {
            // The heading first: on straight legs only the course vouches for it, through
            // a wind fitted with that same heading, so both can be wrong together and
            // confident (a crosswind read as no crab); the first loop then fails every
            // update. Let both go: the direct solution finds the heading again from the
            // manoeuvre, and the tilt is kept.
            self.health.gate_resets[2] = self.health.gate_resets[2].wrapping_add(1);
            self.set_heading(0.0, UNKNOWN_HEADING_VAR);
            self.wind.reset();
            return;
        }
        // Still failing with the heading out: diverged (or a long slip of the sensors),
        // align again from the measurement.
        self.health.gate_resets[0] = self.health.gate_resets[0].wrapping_add(1);
        self.tilt_aligned = false;
    }

    /// Teaches [`vel_noise`] this interval's residual (every interval: what the GPS
    /// acceleration must be weighed with includes what a manoeuvre adds to it, and the
    /// clamped log-mean keeps a short one from moving it far).
    fn learn_vel_noise(&mut self, m: &gps_accel::Measurement, w: &WindowMean, res: &filter::Fused, d: &GpsDelta) {
        let h = filter::minus_skew(w.f_ned);
        self.vel_noise.observe(m.y, &h, res.dtheta, d.dt, d.vd_valid);
    }

    /// The wind filter: carried every interval; fused only while the heading was seen by
    /// the GPS acceleration within `wind_heading_memory` (in straight flight crosswind and
    /// heading error look alike, and a wind fitted to a drifted heading would hold it).
    fn update_wind(&mut self, t_us: u64, d: &GpsDelta, w: &WindowMean, vel_var: f32) {
        // At most ~5 Hz: the wind changes over tens of seconds, and every other 10 Hz fix
        // left out is a sixth of the fix sample's work on the M4F.
        self.wind_dt += w.duration;
        self.wind_skip = !self.wind_skip && d.dt < WIND_MIN_INTERVAL;
        if self.wind_skip {
            return;
        }
        let r = self.ekf.dcm();
        let dt = core::mem::take(&mut self.wind_dt);
        self.wind.predict(dt, w.f_body[0], GRAVITY * r[2][0], &self.wind_noise);
        if !self.tilt_aligned {
            return;
        }
        if self.quat.learn_alpha && d.latest_vd_valid {
            self.learn_alpha(d, w, dt);
        }
        let memory = self.lim.wind_memory_us;
        let recent = self.heading_seen_t.is_some_and(|t| t_us.saturating_sub(t) <= memory);
        if !recent && self.wind.started() {
            return;
        }
        let flow_axis = self.flow_axis(w);
        let heading_var =
            if self.yaw_aligned { self.ekf.covariance()[2][2] } else { UNKNOWN_HEADING_VAR };
        let n = &self.wind_noise;
        self.wind.fuse_ground_velocity(d.vel, vel_var, flow_axis, heading_var, dt, n);
        if self.airspeed_n > 0 {
            let va = self.airspeed_sum / self.airspeed_n as f32;
            let s = self.quat.airspeed_sigma;
            self.wind.fuse_airspeed(va, s * s);
            self.airspeed_sum = 0.0;
            self.airspeed_n = 0;
        }
    }

    /// Teaches the angle-of-attack model this fix's vertical velocity, once the attitude
    /// has settled (an unsettled pitch would be learnt as α).
    fn learn_alpha(&mut self, d: &GpsDelta, w: &WindowMean, dt: f32) {
        let c = self.ekf.covariance();
        if self.yaw_aligned && c[0][0] + c[1][1] < 3e-4 {
            let (va, nz) = (self.wind.airspeed(), -w.f_body[2]);
            self.aoa.learn(&self.dcm_at_epoch(), d.vel[2], va, nz, dt);
        }
    }

    /// The air-velocity direction at the fix epoch, NED: the body x-axis, pitched by the
    /// learnt α at the interval's load and the estimated airspeed with `learn_alpha`.
    fn flow_axis(&self, w: &WindowMean) -> Vec3 {
        let r = self.dcm_at_epoch();
        if !self.quat.learn_alpha {
            return [r[0][0], r[1][0], r[2][0]];
        }
        let alpha = self.aoa.alpha(-w.f_body[2], self.wind.airspeed());
        AngleOfAttack::flow_axis(&r, alpha)
    }

    /// The course: aligns the heading while it is unknown, then aids it at most every
    /// `course_interval` while the wind is known well enough.
    fn fuse_course(&mut self, t_us: u64, d: &GpsDelta, w: &WindowMean, vel_var: f32) {
        let speed_ok = d.vel[0] * d.vel[0] + d.vel[1] * d.vel[1]
            >= self.cfg.min_ground_speed_yaw * self.cfg.min_ground_speed_yaw;
        self.flags.set(Flags::YAW_UNOBSERVABLE, !speed_ok);
        if !self.tilt_aligned {
            return;
        }
        // Due first: the usability test (a sine, the wind) is most of the cost here.
        let interval = self.lim.course_interval_us;
        let due = self.last_course_t.is_none_or(|t| t_us.saturating_sub(t) >= interval);
        if self.yaw_aligned && !due {
            return;
        }
        let v_air = self.air_velocity(d.vel);
        let q = &self.quat;
        let (r, min_speed) = (self.ekf.dcm(), self.cfg.min_ground_speed_yaw);
        if !course::usable(r, v_air, w.f_body[1], q, min_speed, self.course_sin_bank()) {
            self.health.yaw_skipped_sideslip = self.health.yaw_skipped_sideslip.wrapping_add(1);
            return;
        }
        if !self.yaw_aligned {
            let (y, _, _) = course::residual(&self.flow_axis(w), d.vel, vel_var, 0.0, q);
            let var = self.crab_var(d.vel);
            self.set_heading(y, var);
            self.yaw_aligned = true;
            self.last_update.axes[2].status = AxisStatus::Initialised;
            return;
        }
        self.last_course_t = Some(t_us);
        // With the wind known: the air-relative course. Without: the ground course, with
        // the crab angle an unknown wind could cause as its error.
        let sw = self.wind.sigma();
        let wind_var = sw[0] * sw[0] + sw[1] * sw[1];
        let known = wind_var <= q.wind_max_sigma * q.wind_max_sigma;
        let (y, h, var) = if known {
            let gusts = self.wind.gust_var();
            course::residual(&self.flow_axis(w), v_air, vel_var, wind_var + gusts, q)
        } else {
            // The crab allowance only bounds a drifting heading: once the GPS acceleration
            // knows the heading far better, a course could only pull it off.
            let crab = self.crab_var(d.vel);
            if self.ekf.covariance()[2][2] < 0.1 * crab {
                return;
            }
            let (y, h, _) = course::residual(&self.flow_axis(w), d.vel, vel_var, 0.0, q);
            (y, h, crab)
        };
        let res = course::fuse(&mut self.ekf, y, h, var, q);
        if res.applied {
            self.heading_accel.reset();
        } else {
            self.health.gate_rejections[2] = self.health.gate_rejections[2].wrapping_add(1);
        }
        self.last_update.course = AxisUpdate {
            z: crate::math::atan2(v_air[1], v_air[0]),
            innovation: y,
            variance: res.s_diag[0],
            status: if res.applied { AxisStatus::Accepted } else { AxisStatus::Gated },
        };
    }

    /// The attitude as 3-2-1 Euler angles, rad.
    pub fn attitude(&self) -> Euler {
        quat::to_euler(&self.ekf.quaternion())
    }

    /// The attitude quaternion, body → NED.
    pub fn quaternion(&self) -> quat::Quat {
        self.ekf.quaternion()
    }

    /// Gyro bias estimate, rad/s.
    pub fn gyro_bias(&self) -> Vec3 {
        self.ekf.bias()
    }

    /// The gyro scale factors about body x and y, when carried.
    pub fn gyro_scale(&self) -> Option<[f32; 2]> {
        #[cfg(feature = "gyro-scale-states")]
        return self.ekf.scale();
        #[cfg(not(feature = "gyro-scale-states"))]
        None
    }

    /// The latest gyro sample minus the bias, rad/s.
    pub fn body_rates(&self) -> Vec3 {
        let b = self.ekf.bias();
        [self.gyro[0] - b[0], self.gyro[1] - b[1], self.gyro[2] - b[2]]
    }

    /// The error-state covariance `[δθ (NED), δb]` as of the last propagation, with the
    /// attitude error no state holds added ([`unmodelled`]): the body terms, the heading
    /// share of the accelerometer bias and the heading drift since the GPS acceleration
    /// last saw the heading.
    pub fn error_covariance(&self) -> filter::Mat6 {
        let mut p = *self.ekf.covariance();
        unmodelled::add_to_ned(&mut p, self.ekf.dcm(), self.unmodelled);
        p[2][2] += self.heading_bias.variance();
        p[2][2] += self.heading_drift;
        p
    }

    /// The covariance mapped to `[φ, θ, ψ, bp, bq, br]` (first order: `δe = E(φ,θ)·R̂ᵀ·δθ`;
    /// roll and yaw σ grow without bound towards ±90° pitch, where they are undefined).
    pub fn euler_covariance(&self) -> [[f32; 6]; 6] {
        let j = euler_jacobian(self.ekf.dcm(), &self.attitude());
        let p = &self.error_covariance();
        let mut t = [[0.0f32; 6]; 6];
        for i in 0..6 {
            for k in 0..6 {
                t[i][k] = if i < 3 { (0..3).map(|l| j[i][l] * p[l][k]).sum() } else { p[i][k] };
            }
        }
        let mut out = [[0.0f32; 6]; 6];
        for i in 0..6 {
            for k in 0..6 {
                out[i][k] = if k < 3 { (0..3).map(|l| t[i][l] * j[k][l]).sum() } else { t[i][k] };
            }
        }
        out
    }

    /// Wind estimate `[w_N, w_E, w_D]` (m/s, NED; w_D is not estimated: 0) and the σ of
    /// its horizontal components (m/s), once the wind filter has started.
    pub fn wind(&self) -> Option<(Vec3, [f32; 2])> {
        self.wind.started().then(|| (self.wind.wind(), self.wind.sigma()))
    }

    /// See [`crate::Ahrs::health`].
    pub fn health(&self) -> Health {
        let mut h = self.health;
        h.covariance_repairs = self.ekf.repairs();
        h
    }

    /// See [`crate::Ahrs::flags`].
    pub fn flags(&self) -> Flags {
        self.flags
    }

    /// See [`crate::Ahrs::last_update`].
    pub fn last_update(&self) -> &UpdateRecord {
        &self.last_update
    }

    /// The fixes' velocity σ in use, m/s: learnt (`QuatConfig::learn_vel_noise`), or
    /// `None` before the first fix interval or without learning.
    pub fn gps_vel_sigma(&self) -> Option<f32> {
        self.vel_noise.sigma().filter(|_| self.quat.learn_vel_noise)
    }

    /// The receiver latency in use (configured, or as tracked), s.
    pub fn gps_latency(&self) -> f32 {
        self.latency.value()
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        &self.cfg
    }
}

/// `∂[φ, θ, ψ]/∂δθ_NED = E(φ, θ)·R̂ᵀ`, E the body-rate-to-Euler-rate matrix (|cos θ| ≥ 1e-3).
fn euler_jacobian(r: &Mat3, e: &Euler) -> Mat3 {
    let (sf, cf) = crate::math::sincos(e.roll);
    let (st, ct) = crate::math::sincos(e.pitch);
    let ct = if libm::fabsf(ct) < 1e-3 { 1e-3 } else { ct };
    let tt = st / ct;
    let em = [[1.0, sf * tt, cf * tt], [0.0, cf, -sf], [0.0, sf / ct, cf / ct]];
    let mut j = [[0.0f32; 3]; 3];
    for i in 0..3 {
        for k in 0..3 {
            // (E·Rᵀ)[i][k] = Σ_l E[i][l]·R[k][l].
            j[i][k] = (0..3).map(|l| em[i][l] * r[k][l]).sum();
        }
    }
    j
}
