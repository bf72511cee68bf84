//! The facade: the one type an interrupt handler or a replay loop drives.
//!
//! One call per IMU sample, [`Ahrs::step`], defines the per-sample order for the
//! firmware and the host replay alike:
//! 1. the IMU sample — validate, predict;
//! 2. the airspeed sample, if one came with it;
//! 3. each GPS fix that became available since the previous sample.
//!
//! Every call is O(1), allocation-free and panic-free; bad input is counted in
//! [`Health`] and never reaches the state.

use crate::ahrs::{EulerAhrs, GpsOutcome};
use crate::config::{Config, Filter};
use crate::fix::GpsFix;
use crate::health::{Flags, Health, UpdateRecord};
use crate::math::Vec3;
use crate::mekf::QuatAhrs;
use crate::rotation::Euler;

/// The attitude estimator: the filter `Config::filter` selects.
#[derive(Debug, Clone)]
pub struct Ahrs {
    inner: Inner,
}

#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // one estimator per board: no boxing (no alloc)
enum Inner {
    Quaternion(QuatAhrs),
    Euler(EulerAhrs),
}

/// One IMU sample and what came with it, for [`Ahrs::step`].
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
            Inner::Euler(e) => e.$f($($a),*),
        }
    };
    (mut $self:expr, $f:ident ( $($a:expr),* )) => {
        match &mut $self.inner {
            Inner::Quaternion(q) => q.$f($($a),*),
            Inner::Euler(e) => e.$f($($a),*),
        }
    };
}

impl Ahrs {
    /// A new estimator (not yet aligned: it aligns from the first measurements).
    pub fn new(cfg: Config) -> Self {
        let inner = match cfg.filter {
            Filter::Quaternion => Inner::Quaternion(QuatAhrs::new(cfg)),
            Filter::Euler => Inner::Euler(EulerAhrs::new(cfg)),
        };
        Ahrs { inner }
    }

    /// One IMU sample with its airspeed, then the GPS fixes that arrived since the last
    /// sample, in order. Returns whether the IMU sample was accepted.
    pub fn step(&mut self, s: &Sample, fixes: &[GpsFix]) -> bool {
        let ok = self.on_imu(s.t_us, s.gyro, s.accel);
        if let Some(va) = s.airspeed {
            self.on_airspeed(s.t_us, va);
        }
        for f in fixes {
            self.on_gps(f);
        }
        ok
    }

    /// One IMU sample at local time `t_us` (µs): gyro (rad/s) and specific force
    /// (m/s²), both body FRD. Returns `false` if the sample was rejected (and counted).
    pub fn on_imu(&mut self, t_us: u64, gyro: Vec3, accel: Vec3) -> bool {
        both!(mut self, on_imu(t_us, gyro, accel))
    }

    /// One true-airspeed sample, m/s, at local time `t_us`.
    pub fn on_airspeed(&mut self, t_us: u64, va: f32) -> bool {
        both!(mut self, on_airspeed(t_us, va))
    }

    /// One GPS fix.
    pub fn on_gps(&mut self, fix: &GpsFix) -> GpsOutcome {
        both!(mut self, on_gps(fix))
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
    /// The quaternion filter maps its NED attitude error to Euler angles to first order.
    pub fn covariance(&self) -> [[f32; 6]; 6] {
        match &self.inner {
            Inner::Quaternion(q) => q.euler_covariance(),
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
            Inner::Euler(e) => crate::mekf::quat::from_euler(&e.attitude()),
        }
    }

    /// The quaternion filter's error covariance `[δθ (rad, NED axes), δb]`: the
    /// attitude's uncertainty without Euler singularities. `None` for the Euler filter.
    pub fn error_covariance(&self) -> Option<[[f32; 6]; 6]> {
        match &self.inner {
            Inner::Quaternion(q) => Some(*q.error_covariance()),
            Inner::Euler(_) => None,
        }
    }

    /// Wind `[w_N, w_E, w_D]` (m/s, NED, the air mass' velocity; w_D is not estimated)
    /// and the 1-σ of its horizontal components, m/s. `None` before it is estimated
    /// and for the Euler filter.
    pub fn wind(&self) -> Option<(Vec3, [f32; 2])> {
        match &self.inner {
            Inner::Quaternion(q) => q.wind(),
            Inner::Euler(_) => None,
        }
    }

    /// The latest measurement update (check `seq` to see whether a new one ran).
    pub fn last_update(&self) -> &UpdateRecord {
        both!(self, last_update())
    }

    /// Event counters.
    pub fn health(&self) -> Health {
        match &self.inner {
            Inner::Quaternion(q) => q.health(),
            Inner::Euler(e) => *e.health(),
        }
    }

    /// Status flags.
    pub fn flags(&self) -> Flags {
        both!(self, flags())
    }

    /// Whether the thesis-exact EKF1 form is active (for labelling output).
    pub fn is_thesis_exact(&self) -> bool {
        match &self.inner {
            Inner::Quaternion(_) => false,
            Inner::Euler(e) => e.is_thesis_exact(),
        }
    }
}
