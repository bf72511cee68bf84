//! Aid source of the Euler filter's EKF2: roll and pitch from the airspeed, its rate
//! and the flight-path angle (thesis chapter 4), per fix or over a window of fixes
//! (`measure::air_window`).

use super::EulerAhrs;
use crate::config::{Ekf2Config, GRAVITY};
use crate::math::Vec3;
use crate::measure::airspeed::{self, AirData};
use crate::measure::gps_delta::GpsDelta;
use crate::measure::RollPitch;

/// Airspeed samples older than this are not used by EKF2, µs.
const AIRSPEED_MAX_AGE_US: u64 = 500_000;

impl EulerAhrs {
    /// EKF2 roll/pitch from airspeed.
    pub(super) fn airspeed_roll_pitch(
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
    pub(super) fn airspeed_roll_pitch_windowed(
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
}
