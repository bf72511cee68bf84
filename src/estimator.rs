//! The facade: the one type an interrupt handler or a replay loop drives.
//!
//! The facade owns the order of one IMU sample, for the firmware, the host replay and
//! the HIL references alike:
//! 1. the IMU sample — validate, predict;
//! 2. the airspeed sample, if one came with it;
//! 3. each GPS fix that became available since the previous sample.
//!
//! [`Ahrs::step`] is all three; [`Ahrs::predict`] (1–2) and [`Ahrs::update`] (3, one
//! fix) are the same order in two calls, for a caller that keeps them apart (the
//! firmware: its interrupt's stack is the larger of the two, not their sum, and it
//! times each). `on_imu`, `on_airspeed` and `on_gps` remain for callers that drive a
//! single sensor.
//!
//! Every call is O(1), allocation-free and panic-free; bad input is counted in
//! [`Health`] and never reaches the state.

#[cfg(feature = "euler")]
use crate::euler::EulerAhrs;
use crate::config::{Config, ConfigErrors, Filter, InFlightMounting, ValidConfig};
use crate::fix::GpsFix;
use crate::health::{Flags, Health, UpdateRecord};
use crate::math::Vec3;
use crate::mekf::QuatAhrs;
use crate::mounting::{
    BoardRotation, FlightSample, InFlightEstimator, LevelCalibration, LevelError, MountingStatus,
};
use crate::rotation::Euler;

/// What [`Ahrs::on_gps`] did with a fix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GpsOutcome {
    /// Not usable (no fix, invalid, non-finite, out of range, out of order): counted, ignored.
    Rejected,
    /// Stored as the first fix of a new differencing sequence; no update.
    Seeded,
    /// Duplicate epoch: ignored.
    Ignored,
    /// A measurement update ran (see [`Ahrs::last_update`]).
    Updated,
}

/// The attitude estimator: the filter `Config::filter` selects.
#[derive(Debug, Clone)]
pub struct Ahrs {
    inner: Inner,
    mount: Mount,
}

/// The facade's own IMU-side state: the board rotation, its in-flight estimate and the
/// clipping counters (in front of either filter).
#[derive(Debug, Clone)]
struct Mount {
    rotation: BoardRotation,
    /// `1/(1 + s)` of `Config::gyro_scale` per board axis; `None` when it is zero.
    gyro_gain: Option<Vec3>,
    /// `Config::accel_bias` per board axis, m/s²; `None` when it is zero.
    accel_bias: Option<Vec3>,
    /// Neither a rotation nor a gyro scale nor an accelerometer bias to apply: the sample
    /// goes to the filter as is.
    plain: bool,
    applied: [f32; 3],
    estimator: InFlightEstimator,
    /// 99 % of `gyro_clip` / `accel_clip`, and their squares.
    gyro_clip: f32,
    accel_clip: f32,
    gyro_clip_sq: f32,
    accel_clip_sq: f32,
    clipped: u32,
    clipped_since_fix: u32,
    clipped_last_interval: u32,
}

impl Mount {
    /// Whether an axis is at ≥ 99 % of full scale. The magnitude is a cheap pre-test
    /// (|v|² ≥ lim² whenever an axis ≥ lim): the per-axis test runs only near full scale
    /// (the per-axis test on every sample cost ~40 of ~480 M4F instructions per predict).
    #[inline(always)]
    fn clipped(&self, g: &Vec3, a: &Vec3) -> bool {
        let n = |v: &Vec3| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (n(g) >= self.gyro_clip_sq) | (n(a) >= self.accel_clip_sq) {
            return self.clipped_axis(g, a);
        }
        false
    }

    #[cold]
    #[inline(never)]
    fn clipped_axis(&self, g: &Vec3, a: &Vec3) -> bool {
        let at = |v: &Vec3, lim: f32| v.iter().any(|x| libm::fabsf(*x) >= lim);
        at(g, self.gyro_clip) || at(a, self.accel_clip)
    }

    /// Board offsets `[roll, pitch, yaw]` (rad) from the next sample on.
    fn set_rotation(&mut self, offsets: [f32; 3]) {
        self.rotation = BoardRotation::new(offsets);
        self.applied = offsets;
        self.plain =
            self.rotation.is_identity() && self.gyro_gain.is_none() && self.accel_bias.is_none();
    }

    fn new(cfg: &Config) -> Self {
        let s = cfg.gyro_scale;
        let mut m = Mount {
            gyro_gain: (s != [0.0; 3]).then(|| s.map(|s| 1.0 / (1.0 + s))),
            accel_bias: (cfg.accel_bias != [0.0; 3]).then_some(cfg.accel_bias),
            plain: false,
            rotation: BoardRotation::new([0.0; 3]),
            applied: [0.0; 3],
            estimator: InFlightEstimator::default(),
            gyro_clip: 0.99 * cfg.gyro_clip,
            accel_clip: 0.99 * cfg.accel_clip,
            gyro_clip_sq: (0.99 * cfg.gyro_clip) * (0.99 * cfg.gyro_clip),
            accel_clip_sq: (0.99 * cfg.accel_clip) * (0.99 * cfg.accel_clip),
            clipped: 0,
            clipped_since_fix: 0,
            clipped_last_interval: 0,
        };
        m.set_rotation(cfg.mounting.offsets);
        m
    }
}

#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // one estimator per board: no boxing (no alloc)
enum Inner {
    Quaternion(QuatAhrs),
    #[cfg(feature = "euler")]
    Euler(EulerAhrs),
}

/// One IMU sample and what came with it, for [`Ahrs::step`] and [`Ahrs::predict`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// Local time, µs (the clock of the GPS fixes' `t_us`).
    pub t_us: u64,
    /// Gyro, rad/s, body FRD.
    pub gyro: Vec3,
    /// Specific force, m/s², body FRD.
    pub accel: Vec3,
    /// True airspeed, m/s, if a sample came with this one.
    pub airspeed: Option<f32>,
}

macro_rules! both {
    ($self:expr, $f:ident ( $($a:expr),* )) => {
        match &$self.inner {
            Inner::Quaternion(q) => q.$f($($a),*),
            #[cfg(feature = "euler")]
            Inner::Euler(e) => e.$f($($a),*),
        }
    };
    (mut $self:expr, $f:ident ( $($a:expr),* )) => {
        match &mut $self.inner {
            Inner::Quaternion(q) => q.$f($($a),*),
            #[cfg(feature = "euler")]
            Inner::Euler(e) => e.$f($($a),*),
        }
    };
}

impl Ahrs {
    /// A new estimator (not yet aligned: it aligns from the first measurements), on a
    /// configuration that passed [`Config::validate`] ([`Config::validated`]).
    pub fn new(cfg: ValidConfig) -> Self {
        let cfg = *cfg.config();
        #[cfg(feature = "euler")]
        if let Filter::Euler(e) = cfg.filter {
            return Ahrs { mount: Mount::new(&cfg), inner: Inner::Euler(EulerAhrs::new(cfg, e)) };
        }
        // Without the `euler` feature `validate` refuses `Filter::Euler`: the default is never
        // taken. One call of `QuatAhrs::new`, inlined: the firmware builds its state in place.
        let q = if let Filter::Quaternion(q) = cfg.filter { q } else { Default::default() };
        Ahrs { mount: Mount::new(&cfg), inner: Inner::Quaternion(QuatAhrs::new(cfg, q)) }
    }

    /// [`Ahrs::new`] on `cfg` if it validates, else every field out of range.
    // Every error at once without an allocator (~0.5 KB); built once, never per sample.
    #[allow(clippy::result_large_err)]
    pub fn try_new(cfg: Config) -> Result<Self, ConfigErrors> {
        cfg.validated().map(Self::new)
    }

    /// One IMU sample with its airspeed, then the GPS fixes that arrived since the last
    /// sample, in order: [`Ahrs::predict`], then [`Ahrs::update`] per fix. Returns whether
    /// the IMU sample was accepted.
    pub fn step(&mut self, s: &Sample, fixes: &[GpsFix]) -> bool {
        let ok = self.predict(s);
        for f in fixes {
            self.update(f);
        }
        ok
    }

    /// The first half of [`Ahrs::step`]: the IMU sample ([`Ahrs::on_imu`]), then its
    /// airspeed if it has one. Returns whether the IMU sample was accepted. Follow it
    /// with [`Ahrs::update`] for each GPS fix completed since the previous sample.
    #[inline]
    pub fn predict(&mut self, s: &Sample) -> bool {
        let ok = self.on_imu(s.t_us, s.gyro, s.accel);
        if let Some(va) = s.airspeed {
            self.on_airspeed(s.t_us, va);
        }
        ok
    }

    /// The second half of [`Ahrs::step`], once per GPS fix completed since the previous
    /// sample, in order, after that sample's [`Ahrs::predict`]. The fix's `t_us` is the
    /// time it is consumed at: a caller that queues fixes stamps them with the sample's
    /// time, as the firmware does.
    #[inline]
    pub fn update(&mut self, fix: &GpsFix) -> GpsOutcome {
        self.on_gps(fix)
    }

    /// One IMU sample at local time `t_us` (µs): gyro (rad/s) and specific force
    /// (m/s²), both in the IMU board's axes (FRD; body axes when `Config::mounting` has
    /// no offsets): rotated into body axes by the mounting before the filter sees them.
    /// A sample at the sensor's full scale is integrated but counted as clipped.
    /// Returns `false` if the sample was rejected (and counted).
    pub fn on_imu(&mut self, t_us: u64, gyro: Vec3, accel: Vec3) -> bool {
        if !self.mount.plain {
            return self.on_imu_rotated(t_us, gyro, accel);
        }
        self.on_imu_body(t_us, gyro, accel)
    }

    /// A sample already in body axes: the clipping test, then the filter.
    #[inline(always)]
    fn on_imu_body(&mut self, t_us: u64, gyro: Vec3, accel: Vec3) -> bool {
        let clipped = self.mount.clipped(&gyro, &accel);
        let ok = both!(mut self, on_imu(t_us, gyro, accel));
        if clipped & ok {
            self.count_clipped();
        }
        ok
    }

    /// Out of line, so the plain path the default configuration takes stays lean (the
    /// clipping test reads the raw sample: the sensor's axes saturate). The gyro scale and
    /// accelerometer bias calibrations first (they are the sensor's), then the board
    /// rotation.
    #[inline(never)]
    fn on_imu_rotated(&mut self, t_us: u64, gyro: Vec3, accel: Vec3) -> bool {
        let m = &self.mount;
        let clipped = m.clipped(&gyro, &accel);
        let gyro = m.gyro_gain.map_or(gyro, |k| [gyro[0] * k[0], gyro[1] * k[1], gyro[2] * k[2]]);
        let accel = m.accel_bias.map_or(accel, |b| [accel[0] - b[0], accel[1] - b[1], accel[2] - b[2]]);
        let (gyro, accel) = if m.rotation.is_identity() {
            (gyro, accel)
        } else {
            (m.rotation.rotate_to_body(gyro), m.rotation.rotate_to_body(accel))
        };
        let ok = both!(mut self, on_imu(t_us, gyro, accel));
        if clipped & ok {
            self.count_clipped();
        }
        ok
    }

    #[cold]
    #[inline(never)]
    fn count_clipped(&mut self) {
        self.mount.clipped = self.mount.clipped.wrapping_add(1);
        self.mount.clipped_since_fix = self.mount.clipped_since_fix.saturating_add(1);
    }

    /// IMU samples clipped since the previous [`Ahrs::on_gps`] call (any outcome): what
    /// the GPS interval now closing contains. Reset when `on_gps` returns.
    pub fn imu_clipped_since_fix(&self) -> u32 {
        self.mount.clipped_since_fix
    }

    /// IMU samples clipped between the last two [`Ahrs::on_gps`] calls.
    pub fn imu_clipped_last_interval(&self) -> u32 {
        self.mount.clipped_last_interval
    }

    /// The mounting applied to the IMU samples and its in-flight estimate.
    pub fn mounting(&self) -> MountingStatus {
        let e = &self.mount.estimator;
        let on = self.config().mounting.in_flight != InFlightMounting::Off;
        MountingStatus {
            applied: self.mount.applied,
            estimated: e
                .estimate()
                .filter(|_| on)
                .map(|[pitch, yaw]| [self.mount.applied[0], pitch, yaw]),
            averaged_s: e.averaged_s(),
        }
    }

    /// Applies board offsets `[roll, pitch, yaw]` (rad) from the next IMU sample on,
    /// without restarting the filter: its attitude then moves by the change until the
    /// aiding corrects it (use [`Ahrs::calibrate_level`] on the ground instead).
    pub fn set_mounting(&mut self, offsets: [f32; 3]) {
        self.mount.set_rotation(offsets);
    }

    /// Applies a level calibration (taken from raw IMU samples, airframe at rest and
    /// level): the board's roll and pitch from it, the configured yaw offset kept, and
    /// the estimator restarted with them (meant for the ground, before take-off).
    /// Returns the offsets now applied, or why the samples were refused (nothing changed).
    pub fn calibrate_level(&mut self, cal: &LevelCalibration) -> Result<[f32; 3], LevelError> {
        let (roll, pitch) = cal.offsets()?;
        let mut cfg = *self.config();
        cfg.mounting.offsets = [roll, pitch, self.mount.applied[2]];
        // The rest validated when this estimator was built: only a non-finite offset fails.
        let valid = cfg.validated().map_err(|_| LevelError::NonFiniteSamples { count: 0 })?;
        *self = Ahrs::new(valid);
        Ok(cfg.mounting.offsets)
    }

    /// One true-airspeed sample, m/s, at local time `t_us`.
    pub fn on_airspeed(&mut self, t_us: u64, va: f32) -> bool {
        both!(mut self, on_airspeed(t_us, va))
    }

    /// One GPS fix.
    pub fn on_gps(&mut self, fix: &GpsFix) -> GpsOutcome {
        let out = both!(mut self, on_gps(fix));
        self.mount.clipped_last_interval = self.mount.clipped_since_fix;
        self.mount.clipped_since_fix = 0;
        if out == GpsOutcome::Updated && self.config().mounting.in_flight != InFlightMounting::Off {
            self.estimate_mounting(fix);
        }
        out
    }

    /// One interval of the in-flight mounting estimate (see `mounting::InFlightEstimator`):
    /// aligned, GPS, coordinated flight, a measured vertical velocity and, for the
    /// quaternion filter, a wind known to `QuatConfig::wind_max_sigma` (the Euler filter has no
    /// wind: the ground velocity is used, and a crab angle biases the yaw estimate).
    fn estimate_mounting(&mut self, fix: &GpsFix) {
        let flags = self.flags();
        let steady = flags.has(Flags::ALIGNED) && !flags.has(Flags::SIDESLIP);
        let (Some(vd), true) = (fix.vel_d, steady) else {
            return;
        };
        let v = [fix.vel_ne[0], fix.vel_ne[1], vd];
        let v_air = match (&self.inner, self.wind()) {
            #[cfg(feature = "euler")]
            (Inner::Euler(_), _) => Some(v),
            (_, Some((w, sw)))
                if self
                    .config()
                    .quat()
                    .is_some_and(|q| crate::math::hypot(sw[0], sw[1]) <= q.wind_max_sigma) =>
            {
                Some([v[0] - w[0], v[1] - w[1], v[2] - w[2]])
            }
            _ => None,
        };
        let Some(v_air_ned) = v_air else {
            return;
        };
        let s = FlightSample {
            t_us: fix.t_us,
            v_air_ned,
            r_nb: crate::mekf::quat::to_dcm(&self.quaternion()),
            body_rates: self.body_rates(),
            roll: self.attitude().roll,
        };
        let cfg = self.config().mounting;
        let m = &mut self.mount;
        if m.estimator.push(&cfg, &m.rotation, &s) {
            if let Some(o) = m.estimator.offsets_to_apply(&cfg, m.applied) {
                m.set_rotation(o);
            }
        }
    }

    /// The configuration in use.
    pub fn config(&self) -> &Config {
        both!(self, config())
    }

    /// Estimated attitude, 3-2-1 Euler angles, rad (NED → FRD).
    pub fn attitude(&self) -> Euler {
        both!(self, attitude())
    }

    /// Estimated gyro bias [bp, bq, br], rad/s.
    pub fn gyro_bias(&self) -> Vec3 {
        both!(self, gyro_bias())
    }

    /// Latest bias-corrected body rates [p, q, r], rad/s.
    pub fn body_rates(&self) -> Vec3 {
        both!(self, body_rates())
    }

    /// `[φ, θ, ψ, bp, bq, br]`, rad and rad/s.
    pub fn state(&self) -> [f32; 6] {
        let e = self.attitude();
        let b = self.gyro_bias();
        [e.roll, e.pitch, e.yaw, b[0], b[1], b[2]]
    }

    /// The covariance of [`Ahrs::state`] (symmetric 6×6), as of the last propagation.
    /// The quaternion filter maps its NED attitude error to Euler angles to first order,
    /// and includes the accelerometer bias and mounting it has no states for
    /// ([`QuatConfig::accel_bias_sigma`](crate::QuatConfig::accel_bias_sigma), `mounting_sigma`).
    pub fn covariance(&self) -> [[f32; 6]; 6] {
        match &self.inner {
            Inner::Quaternion(q) => q.euler_covariance(),
            #[cfg(feature = "euler")]
            Inner::Euler(e) => *e.covariance(),
        }
    }

    /// The covariance diagonal (rad², (rad/s)²).
    pub fn covariance_diag(&self) -> [f32; 6] {
        let p = self.covariance();
        core::array::from_fn(|i| p[i][i])
    }

    /// 1-σ of each state (rad, rad/s).
    pub fn std_dev(&self) -> [f32; 6] {
        self.covariance_diag().map(crate::math::sqrt)
    }

    /// The attitude quaternion `[w, x, y, z]`, body → NED.
    pub fn quaternion(&self) -> [f32; 4] {
        match &self.inner {
            Inner::Quaternion(q) => q.quaternion(),
            #[cfg(feature = "euler")]
            Inner::Euler(e) => crate::mekf::quat::from_euler(&e.attitude()),
        }
    }

    /// The quaternion filter's error covariance `[δθ (rad, NED axes), δb]`: the
    /// attitude's uncertainty without Euler singularities, with the accelerometer bias and
    /// mounting it has no states for added (as [`Ahrs::covariance`]). `None` for the Euler
    /// filter.
    pub fn error_covariance(&self) -> Option<[[f32; 6]; 6]> {
        match &self.inner {
            Inner::Quaternion(q) => Some(q.error_covariance()),
            #[cfg(feature = "euler")]
            Inner::Euler(_) => None,
        }
    }

    /// The gyro scale factors about body x and y (dimensionless: the gyro reads `(1 + s)·ω`)
    /// when the quaternion filter carries them (`QuatConfig::gyro_scale_state_sigma` > 0).
    pub fn gyro_scale(&self) -> Option<[f32; 2]> {
        match &self.inner {
            Inner::Quaternion(q) => q.gyro_scale(),
            #[cfg(feature = "euler")]
            Inner::Euler(_) => None,
        }
    }

    /// Wind `[w_N, w_E, w_D]` (m/s, NED, the air mass' velocity; w_D is not estimated)
    /// and the 1-σ of its horizontal components, m/s, with the share of the heading's error
    /// the estimate holds (docs/design.md, "The wind holds part of the heading's error").
    /// `None` before it is estimated and for the Euler filter.
    pub fn wind(&self) -> Option<(Vec3, [f32; 2])> {
        match &self.inner {
            Inner::Quaternion(q) => q.wind(),
            #[cfg(feature = "euler")]
            Inner::Euler(_) => None,
        }
    }

    /// The GPS receiver latency the filter compensates, s: the quaternion filter's
    /// tracked estimate (`QuatConfig::latency_gain`), else the configured value.
    pub fn gps_latency(&self) -> f32 {
        match &self.inner {
            Inner::Quaternion(q) => q.gps_latency(),
            #[cfg(feature = "euler")]
            Inner::Euler(e) => e.config().gps_latency,
        }
    }

    /// The GPS velocity noise σ the quaternion filter learnt from the fixes, m/s
    /// (`QuatConfig::learn_vel_noise`); `None` before the first fix interval, without
    /// learning, or with the Euler filter.
    pub fn gps_vel_sigma(&self) -> Option<f32> {
        match &self.inner {
            Inner::Quaternion(q) => q.gps_vel_sigma(),
            #[cfg(feature = "euler")]
            Inner::Euler(_) => None,
        }
    }

    /// The latest measurement update (check `seq` to see whether a new one ran).
    pub fn last_update(&self) -> &UpdateRecord {
        both!(self, last_update())
    }

    /// Event counters.
    pub fn health(&self) -> Health {
        let mut h = match &self.inner {
            Inner::Quaternion(q) => q.health(),
            #[cfg(feature = "euler")]
            Inner::Euler(e) => *e.health(),
        };
        h.imu_clipped = self.mount.clipped;
        h
    }

    /// Status flags.
    pub fn flags(&self) -> Flags {
        let mut f = both!(self, flags());
        let m = &self.mount;
        f.set(Flags::IMU_CLIPPED, (m.clipped_since_fix | m.clipped_last_interval) != 0);
        f
    }

    /// Whether the thesis-exact EKF1 form is active (for labelling output).
    pub fn is_thesis_exact(&self) -> bool {
        match &self.inner {
            Inner::Quaternion(_) => false,
            #[cfg(feature = "euler")]
            Inner::Euler(e) => e.is_thesis_exact(),
        }
    }
}
