//! How the navigation filters (ours, fusion-nav, PX4 EKF2) are set up for one log, in one of
//! two configurations (issue 33; every parameter is listed in docs/peers.md):
//!
//! - [`Tuning::Defaults`]: each as shipped — ours `Config::default()`, EKF2 at PX4's
//!   fixed-wing parameter defaults, fusion-nav at `Config::default()`;
//! - [`Tuning::Matched`]: each given the same sensor figures, from one [`SensorFigures`]:
//!   IMU noise densities, gyro and accelerometer bias stability and turn-on spread, GNSS
//!   velocity noise, airspeed noise and the receiver latency.
//!
//! What is read off the log in both (facts a user knows about their own flight, not
//! tuning): the IMU period, the receiver latency (arrival minus epoch of each fix), and
//! whether the log starts in the air.

use super::px4_ekf2_feed as feed;
use crate::log::FlightLog;
use crate::sim::sensors::SensorParams;

/// Which configuration of the comparison.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Tuning {
    /// Every estimator as shipped.
    Defaults,
    /// Every navigation filter given the same sensor figures.
    Matched,
}

impl Tuning {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Tuning::Defaults => "defaults",
            Tuning::Matched => "matched",
        }
    }
}

/// One sensor specification in SI units, from which every filter's figures are derived.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFigures {
    /// Where it comes from (tables).
    pub name: &'static str,
    /// Gyro white-noise density, rad/√s.
    pub gyro_noise_density: f64,
    /// Accelerometer white-noise density, m/s²/√Hz.
    pub accel_noise_density: f64,
    /// Gyro bias instability as a random-walk density, rad/s/√s (a Gauss–Markov model's
    /// `σ·√(2/τ)`, the same short-term drift).
    pub gyro_bias_walk: f64,
    /// Gyro turn-on bias, 1-σ per axis, rad/s.
    pub gyro_bias_init: f64,
    /// Accelerometer bias instability as a random-walk density, m/s²/√s (the Gauss–Markov
    /// model's `σ·√(2/τ)`; 0 for a sensor without one, as thesis Table 5.1's).
    pub accel_bias_walk: f64,
    /// Accelerometer turn-on bias, 1-σ per axis, m/s².
    pub accel_bias_init: f64,
    /// The accelerometer bias on any one flight, 1-σ per axis, m/s²: the turn-on spread and
    /// the in-run (Gauss–Markov) σ together, `√(init² + σ_gm²)`.
    pub accel_bias_sigma: f64,
    /// How well the accelerometer's axes are known against the body's, 1-σ per axis, rad:
    /// the package misalignment and the triad's own axis misalignment together (a body-fixed
    /// tilt of the measured specific force).
    pub mounting_sigma: f64,
    /// GNSS velocity noise, 1-σ, m/s.
    pub gnss_vel_noise: f64,
    /// Airspeed noise, 1-σ, m/s.
    pub airspeed_noise: f64,
}

/// The random-walk density a first-order Gauss–Markov process of steady-state σ and
/// correlation time τ (s) starts with, `σ·√(2/τ)` per √s (0 without a τ).
fn gauss_markov_walk(sigma: f64, tau: f64) -> f64 {
    if tau > 0.0 {
        sigma * (2.0 / tau).sqrt()
    } else {
        0.0
    }
}

impl SensorFigures {
    /// The figures of the simulator's sensor model `p` (`name`: the preset it came from).
    pub fn of(name: &'static str, p: &SensorParams) -> Self {
        let d = std::f64::consts::PI / 180.0;
        let sqrt_rate = p.imu.rate_hz.sqrt();
        let gm_walk = gauss_markov_walk(
            p.imu.gyro_bias_gm_sigma_deg_h * d / 3600.0,
            p.imu.gyro_bias_gm_tau_s,
        );
        let rw = p.imu.gyro_bias_rw_deg_s_per_sqrt_s * d;
        let accel_walk =
            gauss_markov_walk(p.imu.accel_bias_gm_sigma_m_s2, p.imu.accel_bias_gm_tau_s);
        SensorFigures {
            name,
            gyro_noise_density: p.imu.gyro_noise_deg_s * d / sqrt_rate,
            accel_noise_density: p.imu.accel_noise_m_s2 / sqrt_rate,
            gyro_bias_walk: (gm_walk * gm_walk + rw * rw).sqrt(),
            gyro_bias_init: p.imu.gyro_turn_on_bias_deg_s * d,
            accel_bias_walk: accel_walk,
            accel_bias_init: p.imu.accel_turn_on_bias_m_s2,
            accel_bias_sigma: p.imu.accel_turn_on_bias_m_s2.hypot(p.imu.accel_bias_gm_sigma_m_s2),
            mounting_sigma: p.imu.package_misalignment_deg.hypot(p.imu.accel_axis_misalignment_deg)
                * d,
            gnss_vel_noise: p.gps.vel_noise_ne_m_s.max(p.gps.vel_noise_d_m_s),
            airspeed_noise: p.airspeed.noise_m_s,
        }
    }
    /// Thesis Table 5.1: the simulator's default and `sim-harness jsbsim`'s.
    pub fn thesis() -> Self {
        Self::of("thesis", &SensorParams::thesis())
    }
    /// The `realistic` preset (a typical MEMS IMU and u-blox receiver).
    pub fn realistic() -> Self {
        Self::of("realistic", &SensorParams::realistic())
    }
}

/// Above these a log's first fix (ground speed) or airspeed sample says it starts in the air,
/// m/s (PX4's fixed-wing land detector, `LNDFW_VEL_XY_MAX`, `LNDFW_AIRSPD_MAX`).
const FLYING_GROUND_SPEED: f64 = 5.0;
const FLYING_AIRSPEED: f64 = 6.0;

/// Everything an adapter needs to know about the log and the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Nominal IMU period, s.
    pub dt: f64,
    /// The configuration.
    pub tuning: Tuning,
    /// The sensor figures `Matched` hands every filter.
    pub figures: SensorFigures,
    /// Median receiver latency of the log (arrival minus epoch), s.
    pub latency: f64,
    /// Largest receiver latency of the log, s.
    pub max_latency: f64,
    /// Whether the log starts in the air (no still window to start from).
    pub in_air_start: bool,
    /// The log's `gps_t` is not the effective epoch (see [`Setup::for_log`]): the navigation
    /// peers stamp each fix's epoch at its row's time minus [`Setup::latency`], measured.
    pub epochs_from_latency: bool,
}

impl Setup {
    /// As shipped, for a log starting in the air with up to 0.3 s of latency (tests, bench).
    pub fn nominal(dt: f64) -> Self {
        Setup {
            dt,
            tuning: Tuning::Defaults,
            figures: SensorFigures::thesis(),
            latency: 0.0,
            max_latency: 0.3,
            in_air_start: true,
            epochs_from_latency: false,
        }
    }

    /// The set-up for `log`, with period `dt`.
    ///
    /// The receiver latency handed to the navigation peers is the log's arrival minus epoch
    /// (`t − gps_t`, median) — unless the latency measured from the data (`latency::estimate`
    /// on the log's own sensors: GPS against accelerometer acceleration, magnitudes only, no
    /// attitude from truth or the reference) differs from it by more than two IMU periods.
    /// That happens where a log gives arrival times only (an ArduPilot DataFlash `GPS`
    /// message, a PX4 sdlog2 log: `gps_t` = `t`) or where the receiver smooths its velocity
    /// (the `realistic` receiver's 0.1 s lag): ours learns that effective latency online from
    /// the fixes, and the peers have no such tracker, so they are handed each fix's epoch as
    /// its arrival minus the measured latency.
    pub fn for_log(log: &FlightLog, dt: f64, tuning: Tuning, figures: SensorFigures) -> Self {
        let mut lat: Vec<f64> =
            log.rows.iter().filter_map(|r| r.gps.map(|g| (r.t - g.t).max(0.0))).collect();
        lat.sort_by(f64::total_cmp);
        let first_fix = log.rows.iter().find_map(|r| r.gps);
        let first_va = log.rows.iter().take(10).find_map(|r| r.airspeed);
        let in_air_start = first_fix
            .is_some_and(|g| g.vel[0].hypot(g.vel[1]) > FLYING_GROUND_SPEED)
            || first_va.is_some_and(|v| v > FLYING_AIRSPEED);
        let logged = lat.get(lat.len() / 2).copied().unwrap_or(0.0);
        let measured = (!lat.is_empty())
            .then(|| {
                let mut own = log.clone();
                for r in &mut own.rows {
                    r.truth = None;
                    r.reference = None;
                }
                crate::latency::estimate(&own, crate::latency::MAX_S)
            })
            .flatten()
            .map(|e| e.latency_s)
            .filter(|m| (m - logged).abs() > 2.0 * dt);
        let (latency, max_latency) = match measured {
            // Epochs restamped at arrival − latency: the rows still fall on the IMU grid.
            Some(l) => (l, l + dt),
            None => (logged, lat.last().copied().unwrap_or(0.0)),
        };
        Setup {
            dt,
            tuning,
            figures,
            latency,
            max_latency,
            in_air_start,
            epochs_from_latency: measured.is_some(),
        }
    }

    /// The GNSS feed of the navigation peers for this log (epochs restamped where the log
    /// has arrival times only).
    pub fn gnss_feed(&self) -> super::gnss_feed::GnssFeed {
        super::gnss_feed::GnssFeed::with_latency(self.epochs_from_latency.then_some(self.latency))
    }

    /// EKF2's parameters for this log: `EKF2_DELAY_MAX` holds the oldest fix plus two IMU
    /// periods (never under PX4's 110 ms); `EKF2_PREDICT_US` is PX4's 10 ms, or the IMU's
    /// period where that is longer (up to the parameter's 20 ms; PX4: "should ideally be an
    /// integer multiple of the IMU time delta"): EKF2 clamps each interval to twice its
    /// period and adds gravity over the clamped part only, so at 10 ms a jittered 50 Hz log's
    /// intervals over 20 ms gave it a spurious climb; `EKF2_REQ_GPS_H` is 1 s for a start in
    /// the air (standing in for checks that would have passed on the ground), PX4's 10 s
    /// otherwise.
    pub fn ekf2(&self) -> feed::Params {
        let f = &self.figures;
        let predict_us =
            ((self.dt * 1e6).round() as i32).clamp(feed::PREDICT_US, feed::PREDICT_US_MAX);
        // EKF2 predicts on IMU data accumulated to its period.
        let root_dt = (f64::from(predict_us) / 1e6).sqrt();
        feed::Params {
            delay_max_ms: (1e3 * (self.max_latency + 2.0 * self.dt)).ceil().max(110.0) as f32,
            predict_us,
            gps_health_us: if self.in_air_start { 1_000_000 } else { 10_000_000 },
            noise: (self.tuning == Tuning::Matched).then(|| feed::Noise {
                gyro: (f.gyro_noise_density / root_dt) as f32,
                accel: (f.accel_noise_density / root_dt) as f32,
                gyro_bias: (f.gyro_bias_walk / root_dt) as f32,
                gyro_bias_init: f.gyro_bias_init as f32,
                accel_bias: (f.accel_bias_walk / root_dt) as f32,
                accel_bias_init: f.accel_bias_init as f32,
                gps_vel: f.gnss_vel_noise as f32,
                eas: f.airspeed_noise as f32,
            }),
        }
    }
}
