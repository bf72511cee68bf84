//! What a constant accelerometer bias does to the heading, against what the reported σ
//! says of it. The filter has no accelerometer-bias states; it adds consider terms for
//! the bias to the covariance it reports (`accel_bias_sigma`: the heading share in turns,
//! `unmodelled::HeadingBias`, and the heading drift it leaves in the gyro biases). Those
//! terms are forward models; this measures the effect itself on the simulator.
//!
//! Each seed flies a scenario twice with the same noise, without an accelerometer bias
//! and with a turn-on bias of σ_b per axis (drawn from the same random stream, scaled), so
//! the heading difference between the two runs is the bias' effect alone. The term is the
//! biased run's reported heading variance told σ_b minus the same run's told 0: the
//! estimates are the same (checked), only the report differs.

use crate::montecarlo::rotation_error_ned;
use crate::{replay, sim};
use anyhow::{ensure, Result};
use wing_ahrs::{Config, Filter};

/// Sums over the samples of one kind: effect² (rad²), the term's variance (rad²), count.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sums {
    pub effect_sq: f64,
    pub term_var: f64,
    pub n: usize,
}

impl Sums {
    fn add(&mut self, effect: f64, var: f64) {
        self.effect_sq += effect * effect;
        self.term_var += var;
        self.n += 1;
    }

    /// Mean square effect over mean term variance: 1 where the term is as large as the
    /// effect, below 1 where it is conservative.
    pub fn ratio(&self) -> f64 {
        self.effect_sq / self.term_var
    }

    /// RMS effect and RMS term σ, rad.
    pub fn rms(&self) -> (f64, f64) {
        let n = self.n.max(1) as f64;
        ((self.effect_sq / n).sqrt(), (self.term_var / n).max(0.0).sqrt())
    }
}

/// The measurement over a scenario's seeds, from `FROM_S` into the flight.
#[derive(Debug, Clone, Default)]
pub struct Share {
    /// Per whole second from `FROM_S`.
    pub per_second: Vec<Sums>,
    /// Banked beyond 15° (truth), where the GPS acceleration measures the heading.
    pub banked: Sums,
    /// Within 15° of level, where the heading drifts on what the biases took in.
    pub level: Sums,
}

/// Samples before this (s) are the alignment's.
pub const FROM_S: f64 = 20.0;

/// One IMU row of a replay.
struct Sample {
    t: f64,
    /// NED down component of the rotation error, rad.
    heading_err: f64,
    /// Reported heading variance, rad².
    heading_var: f64,
    /// The truth banked beyond 15°.
    banked: bool,
}

/// Each IMU row from `FROM_S`, for a filter told an accelerometer bias σ `sigma_b` (m/s²)
/// and no mounting error.
fn heading(out: &sim::SimOutput, sigma_b: f32) -> Vec<Sample> {
    let mut cfg = Config::default();
    if let Filter::Quaternion(q) = &mut cfg.filter {
        q.accel_bias_sigma = sigma_b;
        q.mounting_sigma = 0.0;
    }
    let mut rows = Vec::new();
    replay::run(&out.log, cfg, |row, ahrs| {
        if row.t < FROM_S {
            return;
        }
        let (Some(tr), Some(p)) = (row.truth, ahrs.error_covariance()) else { return };
        let e = ahrs.attitude();
        rows.push(Sample {
            t: row.t,
            heading_err: rotation_error_ned([e.roll, e.pitch, e.yaw].map(f64::from), tr)[2],
            heading_var: p[2][2] as f64,
            banked: tr[0].abs() > 15f64.to_radians(),
        });
    });
    rows
}

/// Flies `scenario` (its own sensors, the accelerometer bias replaced) for seeds
/// `1..=seeds` with and without a turn-on bias of `sigma_b` m/s² per axis.
pub fn measure(scenario: &str, seeds: u64, sigma_b: f64) -> Result<Share> {
    let base = sim::load_scenario(scenario)?;
    let mut share = Share::default();
    for seed in 1..=seeds {
        let mut sc = base.clone();
        sc.sensors.imu.accel_turn_on_bias_m_s2 = 0.0;
        let clean = heading(&sim::run(&sc, seed)?, sigma_b as f32);
        sc.sensors.imu.accel_turn_on_bias_m_s2 = sigma_b;
        let out = sim::run(&sc, seed)?;
        let (told, untold) = (heading(&out, sigma_b as f32), heading(&out, 0.0));
        ensure!(
            told.iter().zip(&untold).all(|(a, b)| a.heading_err == b.heading_err),
            "seed {seed}: the estimate changed with accel_bias_sigma, so the reports' difference is not the term alone"
        );
        for ((c, b), u) in clean.iter().zip(&told).zip(&untold) {
            let effect = crate::metrics::wrap(b.heading_err - c.heading_err);
            let var = b.heading_var - u.heading_var;
            let k = (c.t - FROM_S) as usize;
            if share.per_second.len() <= k {
                share.per_second.resize(k + 1, Sums::default());
            }
            share.per_second[k].add(effect, var);
            if c.banked { &mut share.banked } else { &mut share.level }.add(effect, var);
        }
    }
    Ok(share)
}
