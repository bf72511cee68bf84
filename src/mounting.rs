//! IMU mounting: the board's orientation in the airframe, measured on the ground
//! ([`LevelCalibration`]) or in flight (`InFlightEstimator`), and the rotation
//! (`BoardRotation`) that brings every IMU sample into body axes before the filter.
//!
//! Frames: body FRD (the airframe), board (the IMU's axes). The mounting is the 3-2-1
//! rotation body → board, `R_mb = R_BN(roll, pitch, yaw)` with the offsets as angles
//! (the simulator's package misalignment, `sim/sensors/imu.rs`, is the same rotation).

use crate::config::{InFlightMounting, MountingConfig, GRAVITY};
use crate::math::{Mat3, Vec3};
use crate::rotation::{r_bn, Euler};

crate::internal! {
/// The rotation board → body applied to each IMU sample: `v_body = R_mbᵀ·v_board`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardRotation {
    /// `R_mb`, body → board.
    r: Mat3,
    identity: bool,
}
}

impl BoardRotation {
    /// The rotation for board offsets `[roll, pitch, yaw]`, rad.
    pub fn new(offsets: [f32; 3]) -> Self {
        let identity = offsets == [0.0; 3];
        let r = r_bn(&Euler { roll: offsets[0], pitch: offsets[1], yaw: offsets[2] });
        BoardRotation { r, identity }
    }

    /// Whether no rotation runs (all offsets zero).
    pub fn is_identity(&self) -> bool {
        self.identity
    }

    /// `R_mb`, body → board.
    pub fn matrix(&self) -> &Mat3 {
        &self.r
    }

    /// A board-axes vector in body axes (`R_mbᵀ·v`; `v` itself when the identity).
    #[inline]
    pub fn rotate_to_body(&self, v: Vec3) -> Vec3 {
        if self.identity {
            return v;
        }
        let r = &self.r;
        [
            r[0][0] * v[0] + r[1][0] * v[1] + r[2][0] * v[2],
            r[0][1] * v[0] + r[1][1] * v[1] + r[2][1] * v[2],
            r[0][2] * v[0] + r[1][2] * v[1] + r[2][2] * v[2],
        ]
    }
}

crate::internal! {
/// 3-2-1 angles `[roll, pitch, yaw]` of a rotation matrix `R_BN(roll, pitch, yaw)`, rad.
pub fn angles_of(m: &Mat3) -> [f32; 3] {
    let s = (-m[0][2]).clamp(-1.0, 1.0);
    [
        crate::math::atan2(m[1][2], m[2][2]),
        crate::math::asin(s),
        crate::math::atan2(m[0][1], m[0][0]),
    ]
}
}

fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// Why a level calibration was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LevelError {
    /// Fewer samples than [`LevelLimits::min_samples`].
    TooFewSamples {
        /// Finite samples pushed.
        samples: u32,
        /// Samples needed.
        needed: u32,
    },
    /// Some samples were NaN or infinite (the sensor or its driver is faulty).
    NonFiniteSamples {
        /// How many.
        count: u32,
    },
    /// The gyro shows rotation: its largest per-axis standard deviation or mean
    /// magnitude (rad/s) is beyond [`LevelLimits`].
    Rotating {
        /// Largest per-axis standard deviation, rad/s.
        gyro_std: f32,
        /// Magnitude of the mean rate, rad/s.
        gyro_mean: f32,
    },
    /// The accelerometer shows motion or vibration: its largest per-axis standard
    /// deviation, m/s², is beyond [`LevelLimits::max_accel_std`].
    Moving {
        /// Largest per-axis standard deviation, m/s².
        accel_std: f32,
    },
    /// The mean specific force is not 1 g within [`LevelLimits::g_tolerance`]: not at
    /// rest, or the accelerometer's scale is wrong.
    NotOneG {
        /// |mean specific force|, m/s².
        magnitude: f32,
    },
}

/// What a level calibration accepts as "at rest".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelLimits {
    /// Least number of samples (default 200: 2 s at 100 Hz).
    pub min_samples: u32,
    /// Largest per-axis gyro standard deviation, rad/s (default 0.5°/s: several times
    /// a MEMS gyro's noise, far below a hand's tremor).
    pub max_gyro_std: f32,
    /// Largest mean gyro magnitude, rad/s (default 5°/s: above any turn-on bias of a
    /// usable gyro; a steady rotation shows here).
    pub max_gyro_mean: f32,
    /// Largest per-axis accelerometer standard deviation, m/s² (default 0.3).
    pub max_accel_std: f32,
    /// Largest relative deviation of |mean specific force| from 1 g (default 0.05).
    pub g_tolerance: f32,
}

impl Default for LevelLimits {
    fn default() -> Self {
        let deg = crate::math::PI / 180.0;
        LevelLimits {
            min_samples: 200,
            max_gyro_std: 0.5 * deg,
            max_gyro_mean: 5.0 * deg,
            max_accel_std: 0.3,
            g_tolerance: 0.05,
        }
    }
}

/// Per-axis running mean and variance, shifted by the first sample so f32 sums of
/// squares do not cancel (hand-written: six sums, no crate needed).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Moments {
    origin: Vec3,
    sum: Vec3,
    sum_sq: Vec3,
}

impl Moments {
    fn push(&mut self, v: Vec3, first: bool) {
        if first {
            self.origin = v;
        }
        for i in 0..3 {
            let d = v[i] - self.origin[i];
            self.sum[i] += d;
            self.sum_sq[i] += d * d;
        }
    }
    fn mean(&self, n: f32) -> Vec3 {
        core::array::from_fn(|i| self.origin[i] + self.sum[i] / n)
    }
    fn max_std(&self, n: f32) -> f32 {
        (0..3)
            .map(|i| {
                let m = self.sum[i] / n;
                crate::math::sqrt((self.sum_sq[i] / n - m * m).max(0.0))
            })
            .fold(0.0, f32::max)
    }
}

/// Level calibration: push a few seconds of raw (board-axes) IMU samples taken with the
/// airframe at rest and level, then [`LevelCalibration::offsets`] gives the board's roll
/// and pitch in the airframe from the mean specific force direction (yaw is not
/// observable from gravity). The accelerometer bias limits it: b m/s² tilts the result
/// by about b/g rad (0.1 m/s² ≈ 0.6°).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelCalibration {
    limits: LevelLimits,
    n: u32,
    non_finite: u32,
    gyro: Moments,
    accel: Moments,
}

impl LevelCalibration {
    /// An empty accumulator with these limits.
    pub fn new(limits: LevelLimits) -> Self {
        LevelCalibration {
            limits,
            n: 0,
            non_finite: 0,
            gyro: Moments::default(),
            accel: Moments::default(),
        }
    }

    /// One raw sample: gyro rad/s, specific force m/s², board axes.
    pub fn push(&mut self, gyro: Vec3, accel: Vec3) {
        if !(crate::math::all_finite(&gyro) && crate::math::all_finite(&accel)) {
            self.non_finite = self.non_finite.saturating_add(1);
            return;
        }
        let first = self.n == 0;
        self.gyro.push(gyro, first);
        self.accel.push(accel, first);
        self.n = self.n.saturating_add(1);
    }

    /// Finite samples pushed.
    pub fn samples(&self) -> u32 {
        self.n
    }

    /// The board's `(roll, pitch)` in the airframe, rad, or why the samples do not show
    /// an airframe at rest.
    pub fn offsets(&self) -> Result<(f32, f32), LevelError> {
        let l = &self.limits;
        if self.non_finite > 0 {
            return Err(LevelError::NonFiniteSamples { count: self.non_finite });
        }
        if self.n < l.min_samples.max(2) {
            return Err(LevelError::TooFewSamples { samples: self.n, needed: l.min_samples });
        }
        let n = self.n as f32;
        let gyro_std = self.gyro.max_std(n);
        let gyro_mean = crate::math::norm3(self.gyro.mean(n));
        if !(gyro_std <= l.max_gyro_std && gyro_mean <= l.max_gyro_mean) {
            return Err(LevelError::Rotating { gyro_std, gyro_mean });
        }
        let accel_std = self.accel.max_std(n);
        if !(accel_std <= l.max_accel_std) {
            return Err(LevelError::Moving { accel_std });
        }
        let f = self.accel.mean(n);
        let magnitude = crate::math::norm3(f);
        if !(libm::fabsf(magnitude / GRAVITY - 1.0) <= l.g_tolerance) {
            return Err(LevelError::NotOneG { magnitude });
        }
        // At rest and level, f_body = [0, 0, −g]; f_board = R_mb·f_body is −g times the
        // third column of R_BN(φ, θ, ψ) = [−sθ, sφcθ, cφcθ] (independent of ψ).
        let roll = crate::math::atan2(-f[1], -f[2]);
        let pitch = crate::math::atan2(f[0], crate::math::hypot(f[1], f[2]));
        Ok((roll, pitch))
    }
}

impl Default for LevelCalibration {
    fn default() -> Self {
        LevelCalibration::new(LevelLimits::default())
    }
}

/// The mounting as `Ahrs::mounting()` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MountingStatus {
    /// The offsets applied to every IMU sample, `[roll, pitch, yaw]`, rad.
    pub applied: [f32; 3],
    /// The in-flight estimate `[roll, pitch, yaw]`, rad (roll is the applied one: not
    /// observable from the velocity direction; pitch includes the mean angle of attack).
    /// The yaw is only what the filter's heading allows: the quaternion filter's course
    /// aid ties its heading to the air-relative velocity, so a board yaw offset reads
    /// near 0 (simulated 3°: 0.26°, `sim-harness/tests/sim_mounting.rs`); it is reported,
    /// never applied. `None` while off or before any steady flight was averaged.
    pub estimated: Option<[f32; 3]>,
    /// Seconds of steady flight the estimate has averaged.
    pub averaged_s: f32,
}

crate::internal! {
/// One GPS interval's inputs to the in-flight estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlightSample {
    /// Fix time, µs.
    pub t_us: u64,
    /// Air-relative velocity (ground velocity minus wind), NED, m/s.
    pub v_air_ned: Vec3,
    /// The filter's attitude as a DCM, filter body → NED.
    pub r_nb: Mat3,
    /// Latest bias-corrected body rates, rad/s.
    pub body_rates: Vec3,
    /// The filter's roll, rad.
    pub roll: f32,
}
}

crate::internal! {
/// The in-flight estimate of a constant pitch/yaw mounting offset: in steady,
/// coordinated flight the air-relative velocity lies near the body x-axis, so the mean
/// of its direction in the filter's body axes is the residual board rotation (pitch:
/// plus the mean angle of attack; yaw: minus the mean sideslip). Each accepted interval
/// is composed with the applied rotation and averaged with weight `Δt / min(T, t)`: a
/// running mean for the first `estimate_time` T, then an exponential average.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InFlightEstimator {
    pitch: f32,
    yaw: f32,
    elapsed: f32,
    last_t: Option<u64>,
}
}

impl InFlightEstimator {
    /// Folds one interval in, given the applied rotation; returns whether it was used.
    pub fn push(
        &mut self,
        cfg: &MountingConfig,
        applied: &BoardRotation,
        s: &FlightSample,
    ) -> bool {
        let dt = match self.last_t.replace(s.t_us) {
            Some(t) if s.t_us > t => ((s.t_us - t) as f32 * 1e-6).min(1.0),
            _ => return false,
        };
        let rates = crate::math::norm3(s.body_rates);
        let speed = crate::math::norm3(s.v_air_ned);
        if !(rates <= cfg.estimate_max_rate
            && libm::fabsf(s.roll) <= cfg.estimate_max_bank
            && speed >= cfg.estimate_min_speed.max(1.0))
        {
            return false;
        }
        let r = &s.r_nb;
        let v: Vec3 = core::array::from_fn(|i| (0..3).map(|k| r[k][i] * s.v_air_ned[k]).sum());
        // Residual E (body → filter body) of pitch α + δθ and yaw −β + δψ: the velocity
        // [V, 0, 0] in body axes is V·[cθcψ, −sψ, sθcψ] in filter axes (R_BN(0, θ, ψ)).
        let e = r_bn(&Euler {
            roll: 0.0,
            pitch: crate::math::atan2(v[2], v[0]),
            yaw: crate::math::atan2(-v[1], crate::math::hypot(v[0], v[2])),
        });
        let total = angles_of(&mat_mul(applied.matrix(), &e));
        self.elapsed += dt;
        let k = dt / self.elapsed.min(cfg.estimate_time.max(dt));
        self.pitch += k * (total[1] - self.pitch);
        self.yaw += k * crate::math::wrap_pi(total[2] - self.yaw);
        true
    }

    /// `[pitch, yaw]` estimate, rad, once anything was averaged.
    pub fn estimate(&self) -> Option<[f32; 2]> {
        (self.elapsed > 0.0).then_some([self.pitch, self.yaw])
    }

    /// Seconds of steady flight averaged.
    pub fn averaged_s(&self) -> f32 {
        self.elapsed
    }

    /// The offsets to apply under [`InFlightMounting::Apply`], once `estimate_time` has
    /// been averaged: the estimated pitch minus `expected_aoa`; roll and yaw stay as
    /// `applied` (the yaw estimate is not trusted: see [`MountingStatus::estimated`]).
    pub fn offsets_to_apply(&self, cfg: &MountingConfig, applied: [f32; 3]) -> Option<[f32; 3]> {
        let ready = cfg.in_flight == InFlightMounting::Apply && self.elapsed >= cfg.estimate_time;
        ready.then_some([applied[0], self.pitch - cfg.expected_aoa, applied[2]])
    }
}
