//! Estimator configuration: sensor noise, tuning, measurement-model variants and
//! the operational limits of docs/design.md, operational rules. All values SI (rad, s, m/s).

mod validate;
pub use validate::{ConfigError, ConfigErrors};

const DEG: f32 = core::f32::consts::PI / 180.0;

/// Declares a configuration struct whose `pub(crate)` fields are expert tuning: `pub`
/// with the unstable `internals` feature (the harness, the tests), crate-private without,
/// so that the public API is the sensor figures and the few choices a user makes
/// (docs/tuning.md documents every field).
macro_rules! config_struct {
    ($(#[$sm:meta])* pub struct $name:ident { $( $(#[$fm:meta])* $v:vis $field:ident : $ty:ty ),* $(,)? }) => {
        #[cfg(feature = "internals")]
        $(#[$sm])* pub struct $name { $( $(#[$fm])* pub $field: $ty ),* }
        #[cfg(not(feature = "internals"))]
        $(#[$sm])* pub struct $name { $( $(#[$fm])* $v $field: $ty ),* }
    };
}

/// The Euler filter's roll/pitch measurement model, with its options
/// ([`EulerConfig::model`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    /// EKF1: roll and pitch from the accelerometer and GPS-derived acceleration (thesis
    /// §4.2.3). The default (`Ekf1Config::default()`; `Config::thesis()`:
    /// [`Ekf1Config::THESIS`]).
    Ekf1(Ekf1Config),
    /// EKF2: roll and pitch from the accelerometer and airspeed (thesis §4.2.4); needs
    /// `on_airspeed`.
    Ekf2(Ekf2Config),
}

/// How EKF1 solves `A = R_BN(φ, θ)·r` for roll and pitch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ekf1Form {
    /// The thesis' printed `arctan` solutions, eq 4.45 (pitch) and 4.48 (roll, from Ay only).
    /// Defined for |φ|, |θ| < 90° and away from their zero denominators. For reproduction.
    ThesisExact,
    /// The robust `a·sin x + b·cos x = c` solver (docs/design.md, sin/cos solver), root nearest the prediction;
    /// roll from Ay alone.
    RobustSingleAxis,
    /// Robust pitch; roll from both Ay and Az: `φ = atan2(Ay, Az) − atan2(ry, rθ)`,
    /// unique and independent of the specific-force magnitude.
    RobustTwoAxis,
}

/// Which accelerometer value is paired with a GPS-differenced acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AccelAlignment {
    /// The latest IMU sample at the time the fix arrives (thesis).
    Latest,
    /// The mean of the IMU samples over the GPS differencing interval: the GPS
    /// difference is the mean acceleration over that interval, so this pairs like with like.
    IntervalMean,
}

/// Which heading rotates the GPS acceleration into the heading frame (eq 4.40).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RotationHeading {
    /// The measured course ψm (thesis).
    Course,
    /// The predicted yaw ψ of the filter.
    PredictedYaw,
    /// The yaw measurement: course corrected for α in banked flight (equals `Course`
    /// when `heading_aoa_correction` is off); the predicted yaw while sideslip is detected.
    CorrectedCourse,
}

/// Gyro-bias process model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BiasModel {
    /// First-order Gauss-Markov: steady-state σ (rad/s) and correlation time τ (s).
    GaussMarkov {
        /// Steady-state σ, rad/s.
        sigma: f32,
        /// Correlation time τ, s.
        tau: f32,
    },
    /// Random walk (τ = ∞, thesis eq 5.11): rate random walk density, rad/s/√s.
    RandomWalk {
        /// Rate random walk density, rad/s/√s.
        density: f32,
    },
}

/// How the measurement variance R of each GPS-derived update is chosen: EKF1's roll and
/// pitch and the course-derived yaw. EKF2's roll and pitch always use
/// [`Ekf2Config::rp_sigma`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MeasNoise {
    /// A constant R (thesis eq 5.5). `Config::thesis()`: 1° each; `sim-harness --fixed-r`:
    /// [`Config::DEFAULT_FIXED_SIGMA`].
    Fixed {
        /// Measurement 1-σ for roll, pitch, yaw, rad: R = `sigma²` on every update.
        sigma: [f32; 3],
    },
    /// R per update from the noise of the inputs (`measure::noise`): GPS velocity σ
    /// (the fix's speed accuracy, else `vel_sigma`) through the differenced acceleration
    /// and the course, the accelerometer's interval standard error, plus `floor²` for
    /// unmodelled errors (misalignment, lever arm, model error). The default
    /// ([`Config::DEFAULT_MEAS_NOISE`]).
    FromSensors {
        /// GPS velocity 1-σ per NED component when the fix reports no speed accuracy, m/s
        /// (default 0.1).
        vel_sigma: f32,
        /// Unmodelled-error 1-σ for roll, pitch, yaw, rad, added in quadrature (default
        /// 0.2°, 0.2°, 2°).
        floor: [f32; 3],
        /// EKF1: carry the noise of the fix that two consecutive GPS differences share as
        /// two extra states (`ekf::fix_noise`), and the error of the heading that rotates
        /// the GPS acceleration as one error shared with the yaw measurement (default
        /// true). Takes effect on differences whose two fixes report their speed accuracy;
        /// otherwise, and when false, each difference is taken as independent (the thesis).
        /// Not used by EKF2 or the quaternion filter (its counterpart is
        /// `QuatConfig::fix_noise_states`).
        correlated_fix_noise: bool,
    },
}

impl BiasModel {
    /// The random walk with this model's driving density: `√(2σ²/τ)` for a Gauss–Markov
    /// model (the same short-term drift, without the decay of the estimate towards 0).
    pub fn random_walk_equivalent(self) -> BiasModel {
        match self {
            BiasModel::GaussMarkov { sigma, tau } => {
                BiasModel::RandomWalk { density: sigma * crate::math::sqrt(2.0 / tau) }
            }
            rw => rw,
        }
    }
}

/// EKF1 (GPS-derived acceleration) options: [`Model::Ekf1`]. `Default` is the
/// recommended setting, [`Ekf1Config::THESIS`] the thesis'.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ekf1Config {
    /// How `A = R_BN(φ, θ)·r` is solved for roll and pitch (default
    /// [`Ekf1Form::RobustTwoAxis`]; thesis: [`Ekf1Form::ThesisExact`]).
    pub form: Ekf1Form,
    /// Which accelerometer value is paired with the GPS difference (default
    /// [`AccelAlignment::IntervalMean`]; thesis: [`AccelAlignment::Latest`]).
    pub accel_alignment: AccelAlignment,
    /// The heading that rotates the GPS acceleration into the heading frame (default
    /// [`RotationHeading::CorrectedCourse`]; thesis: [`RotationHeading::Course`]).
    pub rotation_heading: RotationHeading,
}

impl Ekf1Config {
    /// The thesis' EKF1: eq 4.45/4.48, the latest accelerometer sample, the course.
    pub const THESIS: Ekf1Config = Ekf1Config {
        form: Ekf1Form::ThesisExact,
        accel_alignment: AccelAlignment::Latest,
        rotation_heading: RotationHeading::Course,
    };
}

impl Default for Ekf1Config {
    /// The robust two-axis form, the interval-mean accelerometer and the α-corrected
    /// course (course ≠ heading in banked flight: on the 6-DoF flights this cuts pitch RMS
    /// from 0.78° to 0.07° on flight1; the predicted yaw does as well in simulation but
    /// worse on the real PX4 flights).
    fn default() -> Self {
        Ekf1Config {
            form: Ekf1Form::RobustTwoAxis,
            accel_alignment: AccelAlignment::IntervalMean,
            // CorrectedCourse, not PredictedYaw: same sim accuracy (flight1 0.08/0.07/0.11°
            // RMS either way) but real PX4 flight b roll/pitch agreement 10.3/14.3° →
            // 5.8/5.6° (an unconverged/crabbed predicted yaw mis-rotates the GPS acceleration).
            rotation_heading: RotationHeading::CorrectedCourse,
        }
    }
}

config_struct! {
/// EKF2 (airspeed) options: [`Model::Ekf2`]. `Default` is the recommended setting,
/// [`Ekf2Config::THESIS`] the thesis'.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ekf2Config {
    /// Averaging window of the measurement, s (default 0.5; thesis 0;
    /// `measure::air_window`): at every fix the model is applied to means over the newest
    /// whole GPS intervals spanning at least this long (a moving window); roll/pitch R is
    /// widened by the scatter of the per-interval values inside the window (Dutch roll,
    /// turbulence). 0 = the thesis' form: latest samples at every fix, V̇a from
    /// `va_bin`/`va_dot_window`, γ̇ from the GPS difference, θ̇ from the prediction.
    /// Range: ≥ 0 s, finite.
    pub window: f32,
    /// Airspeed averaging bin for the V̇a differentiator of the `window = 0` form, s
    /// (default 0.1).
    pub(crate) va_bin: f32,
    /// Number of bins in the least-squares slope that estimates V̇a (2..=16), `window = 0`
    /// (default 8; thesis 4).
    pub(crate) va_dot_window: usize,
    /// Minimum airspeed for the model, m/s (default 8): below it roll/pitch are not
    /// measured (except in the ground mode below).
    pub(crate) min_airspeed: f32,
    /// Windowed form: airspeed must have stayed at or above `min_airspeed` for this long,
    /// s (default 1; thesis 0), and throughout the window, before the model is used — a
    /// launch, a gust on the pitot of a parked aircraft or a hand-carried airframe is not
    /// flight.
    pub(crate) airborne_hold: f32,
    /// Windowed form, ground mode: when every airspeed sample of the window is below
    /// `min_airspeed` and the GPS ground speed at both ends of the window is below this,
    /// m/s (default 2; thesis 0), the aircraft is not flying: roll/pitch are measured from
    /// the mean specific force as gravity alone (the model with Va = 0). 0 disables
    /// (predict only).
    pub(crate) ground_speed_static: f32,
    /// Windowed form: when the lateral specific force |Ay| averaged over any GPS interval
    /// of the window exceeds this, m/s² (default 3; thesis `f32::INFINITY`), the flight is
    /// taken as slipping (β ≠ 0: side force), which the β = 0 model cannot describe —
    /// roll/pitch are not measured. `f32::INFINITY` disables.
    pub(crate) max_lateral_accel: f32,
    /// Measurement 1-σ of EKF2's roll and pitch, rad (default 3° each; thesis 1°): their
    /// R, whatever [`MeasNoise`] is (the windowed form widens it by the window's scatter).
    /// Range: each > 0 rad, finite.
    pub rp_sigma: [f32; 2],
}
}

impl Ekf2Config {
    /// The thesis' EKF2: latest samples at every fix (`window = 0`), no hold, ground mode
    /// or slip limit, 1° R.
    pub const THESIS: Ekf2Config = Ekf2Config {
        window: 0.0,
        va_bin: 0.1,
        va_dot_window: 4,
        min_airspeed: 8.0,
        airborne_hold: 0.0,
        ground_speed_static: 0.0,
        max_lateral_accel: f32::INFINITY,
        rp_sigma: [1.0 * DEG; 2],
    };
}

impl Default for Ekf2Config {
    /// The windowed form. Each value chosen by `SEEDS=16 cargo run --release -p sim-harness
    /// --example ekf2_sweep` (flight1/flight2/aggressive/level over 16 seeds + PX4 a/b),
    /// table in docs/harness.md "EKF2": 0.5 s window (thesis form → this: PX4 b roll/pitch
    /// agreement 46.8/22.0° → 4.2/3.5°, flight1 0.16/0.23° → 0.11/0.11°, aggressive
    /// 0.34/0.31° → 0.24/0.19°; 1 s blurs roll reversals), 1 s airborne hold (longer than
    /// PX4 b's 0.9 s pitot burst on the ground; 3 s starts late on aggressive: 0.35°),
    /// ground mode below 2 m/s (without it PX4 b 17.7/10.5°), slip limit 3 m/s² (flight2
    /// pitch 0.30° → 0.16°; 2 m/s² leaves roll on the gyro through the slips: 0.71°);
    /// roll/pitch σ 3° (at 1° the χ² gates reject ~90 % of real-flight updates).
    fn default() -> Self {
        Ekf2Config {
            window: 0.5,
            va_dot_window: 8,
            airborne_hold: 1.0,
            ground_speed_static: 2.0,
            max_lateral_accel: 3.0,
            rp_sigma: [Config::DEFAULT_FIXED_SIGMA[0], Config::DEFAULT_FIXED_SIGMA[1]],
            ..Ekf2Config::THESIS
        }
    }
}

/// Which attitude filter runs, with the options only that filter reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    /// The multiplicative quaternion EKF (`crate::mekf`): valid at every attitude, aided
    /// by the 3-D GPS acceleration, the wind-corrected course and airspeed. The default
    /// (`QuatConfig::default()`).
    Quaternion(QuatConfig),
    /// The thesis' Euler-state filter (roll, pitch, yaw states; [`EulerConfig::model`]
    /// selects EKF1 or EKF2), kept for reproduction. Singular at ±90° pitch.
    /// `Config::euler()`: `EulerConfig::default()`; `Config::thesis()`:
    /// [`EulerConfig::THESIS`]. Needs the crate feature `euler` (on by default; the
    /// firmware is built without it), else [`Config::validate`] refuses it.
    Euler(EulerConfig),
}

config_struct! {
/// Options of the quaternion filter ([`Filter::Quaternion`]). The sensor noise
/// (`gyro_noise_density`, `bias_model`), ranges, GPS intervals and latency
/// (`gps_latency`) are shared with the Euler filter in [`Config`]; `Default` is the
/// recommended setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuatConfig {
    /// Accelerometer white-noise density, m/s²/√Hz (default 0.01): R of the GPS
    /// acceleration gets `density²/T` per axis for a window of T s.
    /// Range: > 0, finite.
    pub accel_noise_density: f32,
    /// Floor on the GPS-acceleration residual's σ per axis, m/s² (default 0.05): lever
    /// arm, timing and other unmodelled error.
    pub(crate) accel_floor: f32,
    /// A floor proportional to the specific force, as a fraction of |f| (default 0.01):
    /// scale-factor and misalignment error.
    pub(crate) accel_floor_rel: f32,
    /// χ² gate on the 3-D GPS-acceleration innovation (default 16.27: 99.9 %, 3 dof).
    /// Range: > 0 (`f32::INFINITY` disables).
    pub gate_chi2: f32,
    /// χ² gate on a heading (course) innovation (default 10.83: 99.9 %, 1 dof).
    /// Range: > 0 (`f32::INFINITY` disables).
    pub gate_chi2_heading: f32,
    /// After this many consecutive gated GPS-acceleration updates the heading (and the
    /// wind) is let go; after as many more with the heading out, the attitude is aligned
    /// again from the measurement (default 10).
    pub(crate) gate_max_consecutive: u16,
    /// Consecutive course updates with NIS above 4 (a residual beyond 2σ) that reset the
    /// heading and the wind (default 5; 0 never): the course persistently disagrees, so
    /// the heading (or the wind fitted with it) is off by more than its σ, most often
    /// after an in-air switch-on whose first turn left a gyro z bias learnt wrong. The
    /// direct solution finds the heading again in the next manoeuvre; counted in
    /// `Health::gate_resets[2]`.
    pub(crate) course_doubt_after: u8,
    /// A gyro-bias estimate whose magnitude exceeds this many `Config::init_sigma_bias` is
    /// taken as divergence (default 4; 0 never): the biases go back to their turn-on prior
    /// and the attitude is aligned again from the next fix interval, flagged
    /// `Flags::UNRELIABLE` and counted in `Health::gate_resets[1]`. At 4σ a bias drawn from
    /// the prior crosses it with probability 0.1 %; an estimate that far out has taken in an
    /// attitude error no state holds (a latency error read in a 20 Hz turn).
    pub(crate) bias_plausible_sigmas: f32,
    /// σ of the slip and flow-angle offset between course and heading, rad (default 2°).
    pub(crate) course_sigma: f32,
    /// Largest bank and pitch at which the course measures the heading, rad (default 20°).
    pub(crate) course_max_bank: f32,
    /// Largest mean lateral specific force for a course measurement, m/s² (default 0.7):
    /// above it the flight slips.
    pub(crate) course_max_lateral: f32,
    /// Seconds between course updates once the heading is aligned (default 1 s): the
    /// course error (slip) is slow, so faster updates would count it many times.
    pub(crate) course_interval: f32,
    /// Wind speed allowed for before the wind is estimated, m/s (default 10): the
    /// aligning course's σ is the crab angle this wind could cause.
    pub(crate) crab_wind: f32,
    /// The course aids the aligned heading only while the wind σ is below this, m/s
    /// (default 1.5).
    pub(crate) wind_max_sigma: f32,
    /// Velocity σ assumed for fixes that report no speed accuracy (NMEA, most logs), m/s
    /// (default 0.1): the prior of the learnt noise (`learn_vel_noise`), or, without
    /// learning, R of their GPS acceleration (then raise it: such fixes are usually timed
    /// by arrival, whose jitter adds to the differenced acceleration).
    /// Range: > 0 m/s, finite.
    pub unreported_vel_sigma: f32,
    /// Carry the newest fix's velocity noise as a state between GPS-acceleration updates
    /// (`mekf::filter::FixNoise`) when both fixes report their speed accuracy (default
    /// true; false: the differences are taken as independent). The quaternion filter's
    /// counterpart of EKF1's `MeasNoise::FromSensors::correlated_fix_noise`.
    pub(crate) fix_noise_states: bool,
    /// Learn the fixes' velocity noise from the GPS-acceleration residuals
    /// (`mekf::vel_noise`), with the receiver's speed accuracy (or
    /// `unreported_vel_sigma`) as the prior, not the truth (default true; false: R from
    /// the report as given). Receivers report 5–10× their real noise.
    pub learn_vel_noise: bool,
    /// The wind filter fuses the ground velocity while the GPS acceleration has seen the
    /// heading (a turn) within this many seconds (default 60).
    pub(crate) wind_heading_memory: f32,
    /// Wind random walk, m/s/√s (default 0.03).
    pub(crate) wind_walk: f32,
    /// Airspeed random walk beyond its prediction from the specific force, m/s/√s (default 0.5).
    pub(crate) airspeed_walk: f32,
    /// Initial wind σ, m/s (default 10).
    pub(crate) wind_init_sigma: f32,
    /// σ of the flow angles (α, β) in the wind model, rad (default 0.06).
    pub(crate) flow_angle_sigma: f32,
    /// Learn the angle of attack from the load and the vertical velocity
    /// (`mekf/aoa.rs`; docs/design.md) and take the air velocity along it in the wind aid,
    /// instead of the no-slip flow (`mekf/course.rs`; default false). The course always
    /// takes the no-slip flow.
    pub(crate) learn_alpha: bool,
    /// Airspeed sensor σ, m/s (default 1).
    /// Range: > 0 m/s, finite.
    pub airspeed_sigma: f32,
    /// Vibration test of each GPS interval (default 100; `f32::INFINITY` disables): the
    /// interval is counted (`Health::vibration`) and flagged (`Flags::VIBRATION`) when an
    /// axis' accelerometer variance exceeds this many times the white noise of
    /// `accel_noise_density` (100: a σ 10× the spec). Its update is de-weighted by that
    /// scatter in R whether flagged or not, so the flag changes no estimate.
    pub(crate) vibration_ratio: f32,
    /// Attitude noise proportional to the turn rate, 1/√Hz (default 0.002): P grows
    /// by `k²·|ω|²·Δt` per step for gyro scale-factor and axis-misalignment error,
    /// which a bias state cannot hold (0.5 % of a 300 °/s roll is 1.5 °/s).
    pub(crate) gyro_rate_noise: f32,
    /// Gyro scale-factor σ per axis, dimensionless, in [0, 0.1] (default 0.005; 0: off):
    /// each covariance propagation block (`covariance_decimation` samples, or up to a GPS
    /// update) adds `σ²·(Δθᵢ² + 2λΘᵢΔθᵢ)` to the attitude variance about body axis i, Δθ
    /// the block's bias-corrected rotation and Θ that of the blocks before it, decayed over
    /// ~0.5 s, rad — coherent, as a scale error is (0.5 % of a 360° roll is 1.8°), where
    /// `gyro_rate_noise` is white and isotropic (docs/design.md, "Gyro scale factor,
    /// coherent across blocks").
    pub gyro_scale_sigma: f32,
    /// Gyro axis-misalignment σ per cross-axis term, rad, in [0, 0.1] (default 0.2° =
    /// 0.0035; 0: off): a block adds `σ²·(Δθⱼ² + Δθₖ²)` about body axis i (a roll about x
    /// tilts about y and z), with the rotations coherent across blocks as for
    /// `gyro_scale_sigma`.
    pub gyro_misalignment_sigma: f32,
    /// Step of the online GPS-latency tracker, dimensionless (default 0.3; 0: the
    /// latency stays at `Config::gps_latency`, which is also where the tracker starts).
    /// It correlates the GPS-acceleration residual with the jerk (`mekf::latency`).
    pub(crate) latency_gain: f32,
    /// σ of the latency in use, s (default 0.03): R of the GPS acceleration gets
    /// `(σ·ȧ)²` per axis, ȧ the jerk between the IMU windows (a latency error looks like a
    /// heading error of `σ·ω` in a turn). 0 leaves R alone. While the tracker
    /// (`latency_gain` > 0) has seen few informative intervals, `0.1²/(1 + n/20)` s² is
    /// added to σ² (`mekf/latency.rs`): a receiver's latency is unknown until then.
    pub(crate) latency_sigma: f32,
    /// Carry the latency the tracker has not yet learnt (`0.1²/(1 + n/20)` s², above) as a
    /// Schmidt consider parameter of the GPS-acceleration update instead of white noise
    /// in R (`mekf::latency_consider`; default false). Its error repeats in every update
    /// of a manoeuvre, so it is not averaged away: over the robustness suite the
    /// over-confident runs fall by about 40 %, at about 450 more M4F instructions per GPS
    /// update, which the default budget has no room for (docs/tuning.md). Only with the
    /// fix noise as states (`fix_noise_states`, the default), and only in a crate built
    /// with the `latency-consider` feature (else `validate` refuses `true`).
    pub latency_consider: bool,
    /// The bank limit of the course while the heading is not yet aligned or its σ is
    /// above 5°, rad (default 60°): a loitering aircraft may never fly wings-level, and
    /// switched on in a steady turn only the course sees the rotation about the specific
    /// force (`mekf/align.rs`); the course is that of the no-slip flow (no α offset) up to
    /// 45°, of the body x-axis with an α allowance beyond, and before the wind is known the
    /// crab allowance covers the wind.
    pub(crate) course_align_max_bank: f32,
    /// Accelerometer bias σ per axis, m/s² (default 0.1, a calibrated MEMS part): not a
    /// state. The tilt it stands for, σ/g about the horizontal body axes, and the heading
    /// error it leaves in turns, σ/|f_h| (`unmodelled::HeadingBias`), are added to the
    /// covariance the filter reports (`Ahrs::covariance`, `Ahrs::error_covariance`, the σ
    /// in the estimate CSV and in telemetry), not to the P it updates with
    /// (`mekf/unmodelled.rs`).
    /// Range: ≥ 0 m/s², finite.
    pub accel_bias_sigma: f32,
    /// σ per axis of the IMU's mounting against the airframe after calibration, rad
    /// (default 0.3°): added to the reported covariance as `accel_bias_sigma` is. The
    /// package misalignment and the accelerometer triad's axis misalignment from the
    /// datasheet, root-sum-squared, with the board's mounting after a level calibration.
    /// Range: [0, π/2] rad.
    pub mounting_sigma: f32,
    /// σ of a heading rate no state holds, rad/s (default 0.1°/s; 0 off): a gyro-bias
    /// error the bias states took from errors they do not model (scale factor and
    /// misalignment in manoeuvres, a wind fitted with the heading) turns the heading at a
    /// steady rate where nothing measures it. Not a state and no effect on the estimate:
    /// `(σ² + σ_o²·|ω|²)·τ²`, τ the time since the GPS acceleration last saw the heading
    /// in a manoeuvre and ω the body rate then, is added to the reported heading variance
    /// (`mekf/unmodelled.rs`), up to 1 rad². σ_o² is the body offset of
    /// `accel_bias_sigma` and `mounting_sigma`: turning with the aircraft, an offset c is
    /// taken in by the biases as `c × ω`.
    pub(crate) heading_rate_sigma: f32,
    /// Whether the reported attitude covariance follows the GPS acceleration's own
    /// verdict (default true): where the recent mean (10 s) of its NIS per degree of
    /// freedom is above 1, the residuals are larger than P and R explain, and the
    /// attitude block the filter reports is multiplied by that mean (`mekf/consistency.rs`).
    /// Not a state and no effect on the estimate. Off, only the unmodelled terms above
    /// widen it.
    pub(crate) scale_sigma_by_nis: bool,
    /// Prior σ of the gyro scale factors about body x and y as two more states,
    /// dimensionless, in [0, 0.1] (default 0: no states; 0.002 measured best, docs/tuning.md).
    /// The gyro reads `(1 + s)·ω`; the filter learns `s` in rolls and loops and compensates
    /// it, where the bias states would otherwise take it in (`mekf::scale`). Needs the
    /// crate feature `gyro-scale-states` (else `validate` refuses a non-zero value); costs
    /// ~760 more M4F instructions per GPS update. With it, `gyro_scale_sigma` stays
    /// for body z only.
    pub(crate) gyro_scale_state_sigma: f32,
}
}

impl Default for QuatConfig {
    fn default() -> Self {
        let deg = crate::math::PI / 180.0;
        QuatConfig {
            accel_noise_density: 0.01,
            accel_floor: 0.05,
            accel_floor_rel: 0.01,
            gate_chi2: 16.27,
            gate_chi2_heading: 10.83,
            gate_max_consecutive: 10,
            // Since the alignment takes the heading from a turn it fires on no run of the
            // robustness suite's seeds 1-14; on an injected 29° heading kick it takes the
            // summed yaw RMS 193 -> 154° (receiver_robust.rs). The tuning table never fires it.
            course_doubt_after: 5,
            bias_plausible_sigmas: 4.0,
            course_sigma: 2.0 * deg,
            course_max_bank: 20.0 * deg,
            course_max_lateral: 0.7,
            course_interval: 1.0,
            crab_wind: 10.0,
            wind_max_sigma: 1.5,
            // The learner's prior, not R: the receivers of ../shared/data/gnss show 0.012–0.09
            // m/s. Against 0.3 (robustness suite, seeds 1 and 4–22): runs beyond 1.3× of the
            // honest report 123 → 83, over-confident 107 → 104; the real PX4 flights 1.003×
            // (flight b 9.75 → 9.82° total). Before the learner, 0.1 had the χ² gate reject
            // 30–49 % of those flights' updates (`--gps-vel-sigma S`, `--no-learn-vel-noise`).
            unreported_vel_sigma: 0.1,
            // Over the 159-row tuning table: tilt 0.90×, total error 0.92× against white
            // differences; +270 M4F instructions per GPS update (docs/tuning.md).
            fix_noise_states: true,
            learn_vel_noise: true,
            wind_heading_memory: 60.0,
            wind_walk: 0.03,
            airspeed_walk: 0.5,
            wind_init_sigma: 10.0,
            flow_angle_sigma: 0.06,
            // On, over 162 simulated and real flights: wind error 0.964×, total attitude
            // error 0.996×, but the scripted wind suite's yaw 1.057× and worst flight 1.58×
            // (docs/tuning.md): not a win across the table.
            learn_alpha: false,
            airspeed_sigma: 1.0,
            vibration_ratio: 100.0,
            gyro_rate_noise: 0.002,
            // A typical MEMS gyro's (the realistic sensor preset's). Over the 159-row tuning
            // table against off: tilt 0.990×, total 0.990×, no group worse than 1.006×;
            // JSBSim validation 1.005×; random NEES inside its bounds (docs/tuning.md).
            gyro_scale_sigma: 0.005,
            gyro_misalignment_sigma: 0.2 * deg,
            gyro_scale_state_sigma: 0.0,
            latency_gain: 0.3,
            latency_sigma: 0.03,
            // Off: it does not fit the M4F GPS-update budget (docs/tuning.md).
            latency_consider: false,
            course_align_max_bank: 60.0 * deg,
            accel_bias_sigma: 0.1,
            mounting_sigma: 0.3 * deg,
            heading_rate_sigma: 0.1 * deg,
            // The robustness suite's realistic NEES att 3.13–3.20 off, 3.08–3.14 on
            // (docs/tuning.md).
            scale_sigma_by_nis: true,
        }
    }
}

config_struct! {
/// Options of the Euler filter ([`Filter::Euler`]): its measurement model and the
/// noise, gating, initialisation and limits only it reads (the sensor noise, ranges, GPS
/// intervals and latency are shared with the quaternion filter in [`Config`]). `Default`
/// is the recommended setting (`Config::euler()`), [`EulerConfig::THESIS`] the thesis'
/// (`Config::thesis()`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EulerConfig {
    /// Measurement model of roll and pitch, with its options (default
    /// `Model::Ekf1(Ekf1Config::default())`; thesis: `Model::Ekf1(Ekf1Config::THESIS)`).
    pub model: Model,
    /// Correct the course-derived yaw for the nose-to-velocity offset in banked flight
    /// (default true; thesis: false; docs/design.md, heading from the course; thesis
    /// eq 5.9): `ψ = χ + atan2(sα sφ, cα cθ + sα cφ sθ)`.
    pub(crate) heading_aoa_correction: bool,
    /// Bias-convergence gain λ of G (thesis eq 5.6–5.7), dimensionless (default 3;
    /// thesis: 10): larger converges faster and noisier.
    pub(crate) bias_lambda: f32,
    /// Extra attitude process noise for unmodelled effects (integration error,
    /// vibration, misalignment), rad/√s (default 0), added on the attitude diagonal.
    pub(crate) attitude_process_noise: f32,
    /// How R of the GPS-derived measurements is chosen per update, with its options
    /// (default [`Config::DEFAULT_MEAS_NOISE`]; thesis: `Fixed`, 1° each).
    pub meas_noise: MeasNoise,
    /// χ² gate per axis (1 degree of freedom) on `ν²/S`, dimensionless (default 10.83
    /// each, 99.9 %; thesis: `f32::INFINITY`, which disables).
    /// Range: each > 0.
    pub gate_chi2: [f32; 3],
    /// After this many consecutive gate rejections on an axis, the next measurement is
    /// accepted with the axis variance reset — recovery from a diverged estimate (default
    /// 20; thesis: `u16::MAX`).
    pub(crate) gate_max_consecutive: u16,
    /// Initialise roll/pitch/yaw from the first valid measurement instead of x = 0
    /// (default true; thesis: false).
    pub(crate) init_from_measurement: bool,
    /// Above this lateral specific force |Ay|, m/s² (mean over the GPS interval), the
    /// flight is uncoordinated — sideslip makes course ≠ heading — so yaw is not updated
    /// from course; the gyro carries it through the slip (default 0.5; thesis:
    /// `f32::INFINITY`, which disables).
    pub(crate) max_lateral_accel_yaw: f32,
    /// Difference disjoint pairs of fixes (1−0, 3−2, …) instead of every consecutive
    /// pair. Consecutive differences share a fix, so their noise is correlated (lag-1
    /// ρ = −½) and a filter that treats it as white is under-confident; disjoint pairs
    /// make it white at half the update rate. An analysis option (default false: every
    /// pair, more accurate — see the README's consistency section).
    pub(crate) gps_disjoint_pairs: bool,
    /// |θ| beyond which the Euler singularity is flagged and the kinematics guarded, rad
    /// (default 85°).
    pub(crate) gimbal_limit: f32,
    /// N of [`Config::covariance_decimation`] while the filter settles: for the first
    /// `covariance_settling_updates` updates after initialisation, any axis' (re)alignment,
    /// a gate recovery or a GPS re-seed, P is propagated at most every this many samples
    /// (default 10: once per 10 Hz interval; thesis: 1). After initialisation the
    /// attitude–bias cross-covariance builds up from zero; a P that lags it by up to 19
    /// samples steers the bias transient, and in a steady slip (course withheld from yaw)
    /// the yaw-rate bias it leaves is never corrected
    /// (`sim-harness/tests/peers_static_tilt.rs`).
    pub(crate) covariance_decimation_settling: u8,
    /// Updates the settling decimation lasts (default 50; thesis: 0; see
    /// `covariance_decimation_settling`).
    pub(crate) covariance_settling_updates: u16,
}
}

impl EulerConfig {
    /// The thesis' Euler filter: thesis-exact EKF1 (eq 4.45/4.48, latest accelerometer
    /// sample, course rotation), eq 5.5 R (1° each), λ = 10, x(0|0) = 0, no gating, no
    /// heading correction or slip limit, P propagated every sample.
    pub const THESIS: EulerConfig = EulerConfig {
        model: Model::Ekf1(Ekf1Config::THESIS),
        heading_aoa_correction: false,
        bias_lambda: 10.0,
        attitude_process_noise: 0.0,
        meas_noise: MeasNoise::Fixed { sigma: [1.0 * DEG; 3] },
        gate_chi2: [f32::INFINITY; 3],
        gate_max_consecutive: u16::MAX,
        init_from_measurement: false,
        max_lateral_accel_yaw: f32::INFINITY,
        gps_disjoint_pairs: false,
        gimbal_limit: 85.0 * DEG,
        covariance_decimation_settling: 1,
        covariance_settling_updates: 0,
    };
}

impl EulerConfig {
    /// These options with measurement model `model`; EKF2 turns
    /// `MeasNoise::FromSensors::correlated_fix_noise` off (only EKF1 carries the fix noise
    /// as states: [`Config::validate`] refuses the flag with EKF2).
    pub fn with_model(mut self, model: Model) -> Self {
        self.model = model;
        if let (Model::Ekf2(_), MeasNoise::FromSensors { correlated_fix_noise, .. }) =
            (model, &mut self.meas_noise)
        {
            *correlated_fix_noise = false;
        }
        self
    }
}

impl Default for EulerConfig {
    /// The recommended EKF1 (`Ekf1Config::default()`), heading corrected for α, R from
    /// the sensors ([`Config::DEFAULT_MEAS_NOISE`]), χ² gating at 99.9 % (10.83),
    /// initialisation from the first measurement, λ = 3 and the settling decimation.
    /// `sim-harness report --variants` measures the alternatives.
    fn default() -> Self {
        EulerConfig {
            model: Model::Ekf1(Ekf1Config::default()),
            heading_aoa_correction: true,
            gate_chi2: [10.83; 3],
            gate_max_consecutive: 20,
            init_from_measurement: true,
            max_lateral_accel_yaw: 0.5,
            meas_noise: Config::DEFAULT_MEAS_NOISE,
            // Once per 10 Hz interval while settling (see the field). A settling N of 20
            // (static 30° bank throughout) left −9.4° of yaw after 60 s, against +0.01° at
            // N = 1 (`sim-harness/tests/peers_static_tilt.rs`).
            covariance_decimation_settling: 10,
            covariance_settling_updates: 50,
            // λ = 3, not the thesis' 10: with the random-walk bias and per-update R, RMS
            // from 10 s (`report --from 10 --bias-lambda N`), λ = 10 → 3: level
            // 0.036/0.050 → 0.030/0.045°, flight2 0.163/0.097/0.329 → 0.160/0.076/0.205°,
            // aggressive 0.222/0.256/0.473 → 0.237/0.148/0.354°; λ = 1 converges too
            // slowly.
            bias_lambda: 3.0,
            ..EulerConfig::THESIS
        }
    }
}

config_struct! {
/// Full estimator configuration. `Config::default()` is the recommended setting;
/// `Config::thesis()` reproduces the thesis' Table 5.1 / eq 5.3–5.7 choices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// The attitude filter, with the options only it reads (default
    /// `Filter::Quaternion(QuatConfig::default())`; `euler()`:
    /// `Filter::Euler(EulerConfig::default())`; `thesis()`:
    /// `Filter::Euler(EulerConfig::THESIS)`). [`Config::quat_mut`] / [`Config::euler_mut`]
    /// reach the options.
    pub filter: Filter,
    /// Receiver latency, s (default 0): how long after its epoch a fix reaches `on_gps`.
    /// Both filters pair the IMU data with the epoch window, not the arrival window
    /// (capped at ~0.3 s); the quaternion filter's latency tracker starts from it
    /// (`QuatConfig::latency_gain`).
    /// Range: [0, 0.5] s.
    pub gps_latency: f32,

    /// Gyro angle random walk (white-noise density), rad/√s (default 0.05 °/s per sample
    /// at 100 Hz, thesis Table 5.1: 8.7e-5 rad/√s): Q of the attitude. A per-sample σ at
    /// rate f is a density of σ/√f.
    /// Range: > 0, finite.
    pub gyro_noise_density: f32,
    /// Gyro-bias process model: Q of the bias (default the random walk with the thesis'
    /// drift density, [`BiasModel::random_walk_equivalent`] of `thesis()`'s Gauss–Markov
    /// σ = 211 °/h, τ = 382 s).
    pub bias_model: BiasModel,

    /// Initial 1-σ of each attitude angle, rad (default 5°, thesis eq 5.3).
    /// Range: > 0 rad, finite.
    pub init_sigma_attitude: f32,
    /// Initial 1-σ of each gyro bias, rad/s (default 2 °/s, thesis eq 5.3).
    /// Range: > 0 rad/s, finite.
    pub init_sigma_bias: f32,

    /// Below this ground speed, m/s (default 3), the course is unobservable: no yaw update.
    /// Range: ≥ 0 m/s, finite.
    pub min_ground_speed_yaw: f32,
    /// GPS declared lost after this long without a usable fix, s (default 1).
    /// Range: > 0 s, finite.
    pub gps_timeout: f32,
    /// Largest GPS interval over which velocities are differenced, s (default 1.5);
    /// longer → re-seed.
    pub(crate) gps_max_interval: f32,
    /// Smallest GPS interval differenced, s (default 0.075): a fix sooner than this after
    /// the last differenced one is ignored (a duplicate, or every other fix of a receiver
    /// above 13 Hz, which is differenced at half its rate). At 20 Hz one difference carries
    /// `√2·σ_v/0.05 s` of noise (1.7 m/s² per axis for 0.06 m/s fixes) and the receiver's
    /// smoothing and latency, which a pure delay does not model at that bandwidth: the
    /// robustness suite (seeds 1, 4–14, 96 worlds each) lost 152 runs, 40 of them with
    /// NEES above 8, at 0.02 s; 117 and 6 at 0.075 s (docs/tuning.md).
    pub(crate) gps_min_interval: f32,

    /// Largest IMU step, s (default 0.1); longer steps are clamped (and counted).
    pub(crate) dt_max: f32,
    /// Largest accepted gyro magnitude per axis, rad/s (default 35); beyond it a sample
    /// is rejected.
    /// Range: > 0 rad/s (`f32::INFINITY` disables).
    pub gyro_range: f32,
    /// Largest accepted specific force per axis, m/s² (default 200); beyond it a sample
    /// is rejected.
    /// Range: > 0 m/s² (`f32::INFINITY` disables).
    pub accel_range: f32,
    /// Largest accepted GPS velocity component, m/s (default 500); beyond it a fix is
    /// rejected.
    pub(crate) velocity_range: f32,
    /// Largest accepted airspeed, m/s (default 150); beyond it a sample is rejected.
    pub(crate) airspeed_range: f32,
    /// IMU samples per covariance propagation, N, once the filter has settled
    /// (`Config::default()`: 20; `Config::thesis()`: 1, every sample); both filters. The
    /// state is integrated every sample; P is propagated over the accumulated Δt at most
    /// every N samples. The Euler filter linearises at the block's midpoint with its mean
    /// gyro and staggers the propagation to fall between two updates, which use P up to
    /// N − 1 samples old (`Ekf::predict_decimated`, `PendingCovariance::stagger`) — at
    /// 100 Hz IMU and 10 Hz GPS, mid-way through every other GPS interval, never in an
    /// update's interrupt; while it settles it uses
    /// `EulerConfig::covariance_decimation_settling`. Against N = 1: attitude within
    /// 0.01°, σ within 2.5 % (tests/filter.rs).
    /// Range: ≥ 1.
    pub covariance_decimation: u8,

    /// Gyro full scale, rad/s (default 2000°/s): a sample with any axis at ≥ 99 % of it
    /// is taken as clipped — still integrated (it is the best there is), but counted
    /// (`Health::imu_clipped`) and flagged (`Flags::IMU_CLIPPED`). Not a rejection limit
    /// (that is `gyro_range`). `f32::INFINITY` disables.
    pub gyro_clip: f32,
    /// Accelerometer full scale, m/s² (default 16 g), as `gyro_clip`.
    /// Range: > 0 m/s² (`f32::INFINITY` disables).
    pub accel_clip: f32,
    /// The IMU board's mounting in the airframe, and its estimation (`crate::mounting`;
    /// default `MountingConfig::default()`: board axes = body axes, no in-flight estimate).
    pub mounting: MountingConfig,
    /// Gyro scale-factor calibration per board axis, dimensionless, each in [−0.1, 0.1]
    /// (default 0: none, and no cost): the gyro is taken to read `(1 + s)·ω`, and each
    /// sample is divided by `1 + s` before the mounting rotation and the filter. What the
    /// scale states learnt over one of your flight logs is a value for it (`sim-harness
    /// replay LOG --gyro-scale-states 0.002` prints it; body x and y are the board's when
    /// it is mounted square); the firmware then pays three multiplies per sample instead
    /// of the states' ~760 instructions per GPS update.
    pub gyro_scale: [f32; 3],
    /// Accelerometer bias calibration per board axis, m/s², each in [−2, 2] (default 0:
    /// none, and no cost): subtracted from each sample before the mounting rotation and
    /// the filter, which has no accelerometer-bias states. What `sim-harness accel-cal LOG`
    /// learns from one manoeuvring flight log is a value for it (docs/tuning.md).
    pub accel_bias: [f32; 3],
}
}

/// What the in-flight mounting estimator does ([`MountingConfig::in_flight`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InFlightMounting {
    /// Not run (the default).
    Off,
    /// Estimated and reported by `Ahrs::mounting()`, not applied.
    Estimate,
    /// Estimated, and once `estimate_time` of steady flight has been averaged, applied:
    /// the pitch minus `expected_aoa` (roll and yaw stay the configured ones).
    Apply,
}

config_struct! {
/// The IMU board's orientation in the airframe (`crate::mounting`): the 3-2-1 rotation
/// body FRD → board axes. Every IMU sample is rotated back into body axes before the
/// filter sees it, so the attitude is the airframe's, not the board's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MountingConfig {
    /// Board roll, pitch, yaw relative to the airframe, rad (default 0, 0, 0: the board's
    /// axes are the body axes and no rotation runs). A level calibration
    /// (`mounting::LevelCalibration`) measures roll and pitch.
    /// Range: each in [−π, π] rad.
    pub offsets: [f32; 3],
    /// In-flight estimate of a constant pitch (and, reported only, yaw) offset from the
    /// air-relative velocity direction in body axes (default [`InFlightMounting::Off`]:
    /// its pitch includes the mean angle of attack, so applying it needs `expected_aoa`).
    pub in_flight: InFlightMounting,
    /// Averaging time constant of the in-flight estimate, s of accepted steady flight
    /// (default 120 s); also how long it averages before `Apply` applies it.
    pub(crate) estimate_time: f32,
    /// Least air-relative speed for the in-flight estimate, m/s (default 10).
    pub(crate) estimate_min_speed: f32,
    /// Largest body rate magnitude for the in-flight estimate, rad/s (default 5°/s):
    /// steady flight only.
    pub(crate) estimate_max_rate: f32,
    /// Largest bank for the in-flight estimate, rad (default 15°).
    pub(crate) estimate_max_bank: f32,
    /// Mean angle of attack in the steady flight the estimate averages (the cruise α),
    /// rad (default 0). The velocity direction's pitch in body axes is the mounting pitch
    /// *plus* that mean α; `Apply` subtracts this from it (the estimate is reported
    /// without it). An error here is an equal pitch error once applied.
    /// Range: [−π/2, π/2] rad.
    pub expected_aoa: f32,
}
}

impl Default for MountingConfig {
    fn default() -> Self {
        let deg = crate::math::PI / 180.0;
        MountingConfig {
            offsets: [0.0; 3],
            in_flight: InFlightMounting::Off,
            estimate_time: 120.0,
            estimate_min_speed: 10.0,
            estimate_max_rate: 5.0 * deg,
            estimate_max_bank: 15.0 * deg,
            expected_aoa: 0.0,
        }
    }
}

/// Standard gravity, m/s² (docs/design.md, conventions).
pub const GRAVITY: f32 = 9.80665;

/// A [`Config`] that passed [`Config::validate`] ([`Config::validated`]): the only
/// configuration [`crate::Ahrs::new`] takes, so no estimator runs on a field out of range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidConfig(Config);

impl ValidConfig {
    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.0
    }
}

impl TryFrom<Config> for ValidConfig {
    type Error = ConfigErrors;
    // Every error at once without an allocator (~0.5 KB); built once, never per sample.
    #[allow(clippy::result_large_err)]
    fn try_from(c: Config) -> Result<Self, ConfigErrors> {
        c.validated()
    }
}

impl Config {
    /// The thesis' settings: the Euler filter with [`EulerConfig::THESIS`] (thesis-exact
    /// EKF1, eq 5.5 R, λ = 10, x(0|0) = 0, no gating, no heading correction), Table 5.1
    /// sensors and eq 5.3 P(0|0).
    pub fn thesis() -> Self {
        let hz = 100.0f32;
        Config {
            filter: Filter::Euler(EulerConfig::THESIS),
            gps_latency: 0.0,
            gyro_noise_density: 0.05 * DEG / crate::math::sqrt(hz),
            bias_model: BiasModel::GaussMarkov { sigma: 211.0 / 3600.0 * DEG, tau: 382.0 },
            init_sigma_attitude: 5.0 * DEG,
            init_sigma_bias: 2.0 * DEG,
            min_ground_speed_yaw: 3.0,
            gps_timeout: 1.0,
            gps_max_interval: 1.5,
            gps_min_interval: 0.075,
            dt_max: 0.1,
            gyro_range: 35.0,
            accel_range: 200.0,
            velocity_range: 500.0,
            airspeed_range: 150.0,
            covariance_decimation: 1,
            gyro_clip: 2000.0 * DEG,
            accel_clip: 16.0 * GRAVITY,
            mounting: MountingConfig::default(),
            gyro_scale: [0.0; 3],
            accel_bias: [0.0; 3],
        }
    }

    /// σ of [`MeasNoise::Fixed`] for roll, pitch, yaw where a fixed R replaces the default
    /// `FromSensors` (`sim-harness --fixed-r`): 3° each, rad (at 1° the χ² gates reject
    /// ~90 % of real-flight updates).
    pub const DEFAULT_FIXED_SIGMA: [f32; 3] = [3.0 * DEG; 3];

    /// GPS velocity σ assumed for fixes without a speed accuracy (NMEA), m/s.
    pub const DEFAULT_GPS_VEL_SIGMA: f32 = 0.1;

    /// R of `Config::default()`: from the sensors' noise; 0.1 m/s for receivers that
    /// report no speed accuracy (NMEA); floors 0.2° (roll, pitch: the run-averaged NIS
    /// inside its 95 % bounds in ≥ 85 % of updates over 50 Monte Carlo flight1 runs,
    /// `tests/harness_consistency.rs`; 0.3° was that value while the shared fix was
    /// taken as white, 0.25° gives 83 %) and 2° (yaw: sideslip makes course ≠ heading;
    /// smaller floors cost 0.6° of yaw and 0.2° of pitch RMS on the sideslipping flight2).
    pub const DEFAULT_MEAS_NOISE: MeasNoise = MeasNoise::FromSensors {
        vel_sigma: Self::DEFAULT_GPS_VEL_SIGMA,
        floor: [0.2 * DEG, 0.2 * DEG, 2.0 * DEG],
        correlated_fix_noise: true,
    };

    /// The recommended Euler-filter configuration: `Config::default()` with
    /// `Filter::Euler(EulerConfig::default())` (the previous default, kept for comparison
    /// and reproduction).
    pub fn euler() -> Self {
        Config { filter: Filter::Euler(EulerConfig::default()), ..Config::default() }
    }

    /// The Euler filter with this measurement model (and its options), e.g.
    /// `Config::euler().with_model(Model::Ekf2(Ekf2Config::default()))`: an Euler
    /// configuration keeps its other options; a quaternion one becomes the Euler filter
    /// with `EulerConfig::default()`'s.
    pub fn with_model(mut self, model: Model) -> Self {
        let euler = match self.filter {
            Filter::Euler(e) => e,
            Filter::Quaternion(_) => EulerConfig::default(),
        };
        self.filter = Filter::Euler(euler.with_model(model));
        self
    }

    /// The quaternion filter's options, if that is the filter.
    pub fn quat(&self) -> Option<&QuatConfig> {
        match &self.filter {
            Filter::Quaternion(q) => Some(q),
            Filter::Euler(_) => None,
        }
    }

    /// The quaternion filter's options, if that is the filter.
    pub fn quat_mut(&mut self) -> Option<&mut QuatConfig> {
        match &mut self.filter {
            Filter::Quaternion(q) => Some(q),
            Filter::Euler(_) => None,
        }
    }

    /// The Euler filter's options, if that is the filter (`euler()` is the constructor).
    pub fn euler_config(&self) -> Option<&EulerConfig> {
        match &self.filter {
            Filter::Euler(e) => Some(e),
            Filter::Quaternion(_) => None,
        }
    }

    /// The Euler filter's options, if that is the filter.
    pub fn euler_mut(&mut self) -> Option<&mut EulerConfig> {
        match &mut self.filter {
            Filter::Euler(e) => Some(e),
            Filter::Quaternion(_) => None,
        }
    }

    /// EKF1's options, if that is the filter and model.
    pub fn ekf1_mut(&mut self) -> Option<&mut Ekf1Config> {
        match &mut self.euler_mut()?.model {
            Model::Ekf1(e) => Some(e),
            Model::Ekf2(_) => None,
        }
    }

    /// EKF2's options, if that is the filter and model.
    pub fn ekf2_mut(&mut self) -> Option<&mut Ekf2Config> {
        match &mut self.euler_mut()?.model {
            Model::Ekf2(e) => Some(e),
            Model::Ekf1(_) => None,
        }
    }
}

impl Default for Config {
    /// Recommended defaults: the quaternion filter (`QuatConfig::default()`) with the
    /// thesis' sensor model, the bias as a random walk and P propagated every 20 samples.
    /// `Config::euler()` is the recommended Euler filter.
    fn default() -> Self {
        Config {
            // The quaternion filter: in wind, on aerobatics and at every attitude (the
            // Euler filter's course-as-heading fails in wind: `sim-harness report`).
            filter: Filter::Quaternion(QuatConfig::default()),
            // P once per two GPS intervals at 100 Hz / 10 Hz (see the field's
            // documentation). The propagation was a third of the host's per-sample cost at
            // N = 10: N = 20 saves ~5 ns of a ~56 ns step (`compare`).
            covariance_decimation: 20,
            // Random walk with the thesis drift density √(2σ²/τ), not Gauss–Markov: a real
            // gyro bias is a turn-on constant plus drift, and a GM model decays the
            // *estimate* of the constant towards zero when nothing corrects it — 5 % of a
            // 1°/s bias in a 20 s GPS outage, which was most of the outage error
            // (flight1_outage at 79.99 s: −0.95/1.15/0.36° → −0.12/0.45/−0.30°; `report
            // --bias-model gauss-markov`).
            bias_model: Config::thesis().bias_model.random_walk_equivalent(),
            ..Config::thesis()
        }
    }
}
