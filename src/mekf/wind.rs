//! Aid source: the horizontal wind, from the ground velocity and the attitude — with
//! an airspeed sensor, or from the turn circles of the ground velocity without one.
//!
//! A linear three-state Kalman filter, `[w_N, w_E, V_a]` (m/s), outside the attitude
//! filter: `v_ground,h = V_a·u_h + w`, with `u_h` the horizontal part of the body
//! x-axis in NED (α and β are not known: their effect is in R). `V_a` is carried
//! between fixes by the specific force along x, `V̇_a = f_x + g·R₂₀` (gravity's
//! component on body x). Without an airspeed sensor the wind is observable once the
//! heading has changed (a turn); until then its σ stays large and the course aid
//! does not use it.
//!
//! Gusts and turbulence move the air between fixes by more than a random walk the
//! size of still air's allows. Their variance is measured, not tuned: the smoothed
//! excess of the cross-track innovation's square over its predicted variance. It is
//! added to this filter's R (the wind estimate is the mean wind) and to the course
//! aid's R (one fix's air-relative course is off by the gust of that moment).

use super::dv_window::WindowMean;
use super::latency::EpochDcm;
use super::UNKNOWN_HEADING_VAR;
use crate::config::GRAVITY;
use crate::math::{max, min, Mat3, Vec3};
use crate::measure::gps_delta::GpsDelta;

/// Smoothing time of the gust variance, s (a few turbulence scales at airspeed).
const GUST_TAU: f32 = 20.0;
/// Ceiling of the gust variance, (m/s)².
const GUST_MAX_VAR: f32 = 25.0;

/// The wind filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind {
    x: Vec3,
    p: Mat3,
    started: bool,
    /// Cross-track ground-velocity variance the model does not explain, (m/s)²: gusts
    /// and turbulence, which move the air between fixes (smoothed over `GUST_TAU`).
    gust_var: f32,
    /// How the estimate's error moves with the heading error it was fed, `∂e/∂δψ`
    /// (m/s per rad, `[w_N, w_E, V_a]`): each fix takes its air velocity's direction from
    /// the attitude's heading, and that error is common to every fix, not white, so
    /// averaging fixes does not remove it ([`Wind::heading_coupling`]).
    heading_sens: Vec3,
}

/// Tuning of the wind filter (from [`crate::config::QuatConfig`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindNoise {
    /// Wind random walk, m/s/√s.
    pub wind_walk: f32,
    /// Airspeed random walk beyond the specific-force prediction, m/s/√s.
    pub airspeed_walk: f32,
    /// Initial wind σ, m/s.
    pub init_sigma: f32,
    /// Flow-angle allowance (α, β, the nose-to-velocity offset), rad.
    pub flow_angle_sigma: f32,
}

/// Fix intervals shorter than this (s) run the wind filter every other fix.
const WIND_MIN_INTERVAL: f32 = 0.15;

impl Default for Wind {
    fn default() -> Self {
        Wind { x: [0.0; 3], p: [[0.0; 3]; 3], started: false, gust_var: 0.0, heading_sens: [0.0; 3] }
    }
}

impl Wind {
    /// Wind estimate `[w_N, w_E, 0]`, m/s NED (the air mass' velocity).
    pub fn wind(&self) -> Vec3 {
        [self.x[0], self.x[1], 0.0]
    }

    /// 1-σ of `[w_N, w_E]` as reported, m/s (∞ before the first fix): the filter's own, with
    /// the share of the heading's error (variance `heading_var`, rad²) that the estimate took
    /// in, `|∂e/∂δψ|·σ_ψ` per axis, which P, fed that error as white, has averaged away.
    pub fn reported_sigma(&self, heading_var: f32) -> [f32; 2] {
        self.reported_variance(heading_var).map(crate::math::sqrt)
    }

    /// The variances of [`Wind::reported_sigma`], (m/s)² (∞ before the first fix): the
    /// course weighs the wind by these, with no square root on the GPS-update path.
    pub fn reported_variance(&self, heading_var: f32) -> [f32; 2] {
        if !self.started {
            return [f32::INFINITY; 2];
        }
        let s = self.heading_sens;
        [self.p[0][0] + s[0] * s[0] * heading_var, self.p[1][1] + s[1] * s[1] * heading_var]
    }

    /// The estimated airspeed, m/s (0 before the first fix).
    pub fn airspeed(&self) -> f32 {
        self.x[2]
    }

    /// Whether the estimate has started.
    pub fn started(&self) -> bool {
        self.started
    }

    /// Forgets the estimate.
    pub fn reset(&mut self) {
        *self = Wind::default();
    }

    /// Carries the airspeed over `dt` s with the mean body-x specific force `fx` (m/s²)
    /// and gravity's body-x component `gx` (m/s²).
    pub fn predict(&mut self, dt: f32, fx: f32, gx: f32, n: &WindNoise) {
        if !self.started {
            return;
        }
        self.x[2] = max(self.x[2] + (fx + gx) * dt, 0.0);
        self.p[0][0] += n.wind_walk * n.wind_walk * dt;
        self.p[1][1] += n.wind_walk * n.wind_walk * dt;
        self.p[2][2] += n.airspeed_walk * n.airspeed_walk * dt;
    }

    /// Fuses a ground velocity `v` (m/s NED, variance `vel_var` per axis) with the air
    /// velocity's direction `x_axis` in NED (the body x-axis pitched by α) and its
    /// heading variance `heading_var` (rad²).
    pub fn fuse_ground_velocity(
        &mut self,
        v: Vec3,
        vel_var: f32,
        x_axis: Vec3,
        heading_var: f32,
        dt: f32,
        n: &WindNoise,
    ) {
        let u = [x_axis[0], x_axis[1]];
        if !self.started {
            let va = crate::math::hypot(v[0], v[1]);
            let s2 = n.init_sigma * n.init_sigma;
            self.x = [0.0, 0.0, va];
            self.p = [[s2, 0.0, 0.0], [0.0, s2, 0.0], [0.0, 0.0, s2]];
            self.started = true;
            return;
        }
        let va = self.x[2];
        let r = vel_var + va * va * (heading_var + n.flow_angle_sigma * n.flow_angle_sigma);
        self.match_gusts(v, u, r, dt);
        let r = r + self.gust_var;
        // A heading error δψ turns u by `[−u_E, u_N]·δψ`: row k's residual carries `m_k·δψ`.
        let m = [-va * u[1], va * u[0]];
        for k in 0..2 {
            // Sequential scalar updates: row k of H = [e_k, u_k], the airspeed as the previous
            // row left it.
            let pred = self.x[k] + self.x[2] * u[k];
            self.scalar(v[k] - pred, k, u[k], r, m[k]);
        }
    }

    /// The course error of the air velocity `v_air` (m/s NED) per rad of the heading error
    /// this wind was learnt with, `∂χ/∂w·∂e/∂δψ`: 0 for a wind learnt independently of the
    /// heading (a full circle), −1 for one that holds the whole heading error (its course
    /// then only repeats the heading it was given).
    pub fn heading_coupling(&self, v_air: Vec3) -> f32 {
        let speed2 = max(v_air[0] * v_air[0] + v_air[1] * v_air[1], 1e-3);
        let s = self.heading_sens;
        (v_air[0] * s[1] - v_air[1] * s[0]) / speed2
    }

    /// The heading was set anew (variance `heading_var` rad² before): the error the
    /// estimate took from the old heading is no longer tied to the new one, so it moves
    /// into the covariance. Out of line: rare (a heading reset), and two callers.
    #[inline(never)]
    pub fn decouple_heading(&mut self, heading_var: f32) {
        let s = self.heading_sens;
        for i in 0..3 {
            for j in 0..3 {
                self.p[i][j] += s[i] * s[j] * heading_var;
            }
        }
        self.heading_sens = [0.0; 3];
    }

    /// Variance of the gusts, (m/s)²: what the air-relative velocity of one fix may differ
    /// from the mean wind by.
    pub fn gust_var(&self) -> f32 {
        self.gust_var
    }

    /// The cross-track innovation's square beyond its predicted variance, smoothed over
    /// `GUST_TAU` and weighted by the interval `dt` (s) it closes. Cross-track only: the
    /// along-track part is mostly the airspeed model's error.
    fn match_gusts(&mut self, v: Vec3, u: [f32; 2], r: f32, dt: f32) {
        let c = [-u[1], u[0]];
        let y0 = v[0] - (self.x[0] + self.x[2] * u[0]);
        let y1 = v[1] - (self.x[1] + self.x[2] * u[1]);
        let y = c[0] * y0 + c[1] * y1;
        let p = &self.p;
        let s = c[0] * c[0] * p[0][0] + 2.0 * c[0] * c[1] * p[0][1] + c[1] * c[1] * p[1][1] + r;
        let sample = (y * y - s).clamp(0.0, GUST_MAX_VAR);
        if sample.is_finite() && dt > 0.0 {
            self.gust_var += min(dt / GUST_TAU, 1.0) * (sample - self.gust_var);
        }
    }

    /// Fuses a measured true airspeed `va` (m/s) of variance `var`.
    pub fn fuse_airspeed(&mut self, va: f32, var: f32) {
        if self.started {
            self.scalar(va - self.x[2], 2, 0.0, var, 0.0);
        }
    }

    /// One scalar update of the row `H = e_a + c·e_2` (a ground-velocity row `e_k + u_k·e_Va`;
    /// the airspeed `e_Va`, c = 0), written out: the zeros of a general row would still cost
    /// their multiplies (IEEE `x·0` is not 0 for every x, so they are not folded away), on
    /// the M4F's GPS-update sample. `m` is the residual's sensitivity to the heading error
    /// (m/s per rad): the error `e` moves by `−k·y`, so `∂e/∂δψ ← ∂e/∂δψ − k·(H·∂e/∂δψ + m)`.
    /// P's upper triangle is updated and mirrored.
    #[inline(always)]
    fn scalar(&mut self, y: f32, a: usize, c: f32, r: f32, m: f32) {
        let p = &mut self.p;
        let ph: Vec3 = core::array::from_fn(|i| p[i][a] + c * p[i][2]);
        let s = ph[a] + c * ph[2] + r;
        if !(s > 0.0) || !y.is_finite() {
            return;
        }
        let k: Vec3 = core::array::from_fn(|i| ph[i] / s);
        let hs = self.heading_sens[a] + c * self.heading_sens[2] + m;
        for i in 0..3 {
            self.x[i] += k[i] * y;
            self.heading_sens[i] -= k[i] * hs;
            for j in i..3 {
                let v = p[i][j] - k[i] * ph[j];
                p[i][j] = v;
                p[j][i] = v;
            }
            p[i][i] = max(p[i][i], 1e-6);
        }
    }
}

impl super::QuatAhrs {
    /// Ground velocity minus the wind estimate (the ground velocity before it starts).
    pub(super) fn air_velocity(&self, v: Vec3) -> Vec3 {
        let w = if self.wind.started() { self.wind.wind() } else { [0.0; 3] };
        [v[0] - w[0], v[1] - w[1], v[2]]
    }

    /// The wind filter: carried every interval; fused only while the heading was seen by
    /// the GPS acceleration within `wind_heading_memory` (in straight flight crosswind and
    /// heading error look alike, and a wind fitted to a drifted heading would hold it).
    pub(super) fn control_wind(
        &mut self,
        t_us: u64,
        d: &GpsDelta,
        w: &WindowMean,
        vel_var: f32,
        epoch: &mut EpochDcm,
    ) {
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
            self.learn_alpha(d, w, dt, epoch);
        }
        let memory = self.lim.wind_memory_us;
        let recent = self.heading_seen_t.is_some_and(|t| t_us.saturating_sub(t) <= memory);
        if !recent && self.wind.started() {
            return;
        }
        let r = self.epoch_dcm(epoch);
        let flow_axis = if self.quat.learn_alpha {
            self.flow_axis(w, &r)
        } else {
            let u = super::course::flow_dir(&r, d.vel[2], self.wind.airspeed(), self.flow_model());
            [u[0], u[1], 0.0]
        };
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
}

#[cfg(test)]
mod tests {
    use super::*;

    const N: WindNoise =
        WindNoise { wind_walk: 0.03, airspeed_walk: 0.05, init_sigma: 10.0, flow_angle_sigma: 0.02 };

    /// Flies 400 s of 0.2 s intervals circling at 20 m/s in a 3 m/s wind from the north
    /// plus white cross-track gusts of `gust` m/s (a seeded LCG), returns the filter.
    fn circle(gust: f32) -> Wind {
        let (mut w, mut seed) = (Wind::default(), 12345u32);
        for k in 0..2000 {
            let psi = k as f32 * 0.01;
            let u = [libm::cosf(psi), libm::sinf(psi), 0.0];
            // Sum of 12 uniforms: unit variance, zero mean.
            let g: f32 = (0..12)
                .map(|_| {
                    seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
                    (seed >> 8) as f32 / (1u32 << 24) as f32
                })
                .sum::<f32>()
                - 6.0;
            let c = [-u[1], u[0]];
            let v = [20.0 * u[0] - 3.0 + gust * g * c[0], 20.0 * u[1] + gust * g * c[1], 0.0];
            w.predict(0.2, 0.0, 0.0, &N);
            w.fuse_ground_velocity(v, 0.01, u, 1e-6, 0.2, &N);
        }
        w
    }

    /// Flies `n` intervals of 0.2 s circling at 20 m/s, turning `step` rad per interval, in a
    /// 6 m/s wind from the east, the air velocity's direction fed `offset` rad off the true
    /// heading. The
    /// filter starts at the truth (its prior σ kept), so every residual is the offset's:
    /// the gains' own dependence on the heading then moves the estimate only to second order.
    fn arc(n: usize, step: f32, offset: f32) -> Wind {
        let mut w = Wind::default();
        w.fuse_ground_velocity([20.0, 0.0, 0.0], 0.01, [1.0, 0.0, 0.0], 0.003, 0.2, &N);
        w.x = [0.0, -6.0, 20.0];
        for k in 0..n {
            let psi = 0.3 + k as f32 * step;
            let v = [20.0 * libm::cosf(psi), 20.0 * libm::sinf(psi) - 6.0, 0.0];
            let fed = psi - offset;
            w.predict(0.2, 0.0, 0.0, &N);
            w.fuse_ground_velocity(v, 0.01, [libm::cosf(fed), libm::sinf(fed), 0.0], 0.003, 0.2, &N);
        }
        w
    }

    /// The heading sensitivity is the estimate's own derivative: two filters fed the same
    /// fixes, one with the heading 0.05° off, differ by it (finite difference). Over a
    /// quarter turn the wind holds most of the heading error, so a course from it would
    /// repeat the heading it was given (coupling near −1). Circling at 14 °/s the filter's
    /// memory (~16 s) spans more than half a circle, and the turn separates the wind from
    /// the heading (coupling near 0); at 3 °/s it spans 46° of the turn, and stays coupled.
    #[test]
    fn the_wind_knows_how_much_of_the_heading_error_it_holds() {
        let eps = 0.05f32.to_radians();
        for (n, step, coupling) in
            [(160usize, 0.01f32, -1.0f32..-0.6), (400, 0.05, -0.1..0.1), (1900, 0.01, -0.6..-0.2)]
        {
            let (a, b) = (arc(n, step, 0.0), arc(n, step, eps));
            for i in 0..3 {
                // δψ = true − fed: filter b was fed ψ − ε, so its error is e + s·ε and its
                // estimate x̂ − s·ε.
                let fd = (a.x[i] - b.x[i]) / eps;
                let s = a.heading_sens[i];
                assert!((fd - s).abs() <= 0.01 * s.abs().max(1.0), "{n} fixes, state {i}: {fd} vs {s}");
            }
            let psi = 0.3 + n as f32 * step;
            let v_air = [20.0 * libm::cosf(psi), 20.0 * libm::sinf(psi), 0.0];
            let c = a.heading_coupling(v_air);
            assert!(coupling.contains(&c), "{n} fixes of {step} rad: coupling {c}");
        }
    }

    /// A heading 1σ off (the variance the filter is fed): after a quarter turn the wind is
    /// off by the share it took in. The filter's own σ says that error cannot be; the
    /// reported σ, with the coupled share, covers it.
    #[test]
    fn the_reported_sigma_covers_the_heading_error_the_wind_took_in() {
        let heading_var = 0.003f32;
        let w = arc(160, 0.01, crate::math::sqrt(heading_var));
        let own = w.reported_sigma(0.0);
        let reported = w.reported_sigma(heading_var);
        let err = [w.x[0] - 0.0, w.x[1] + 6.0];
        let z_own = libm::hypotf(err[0] / own[0], err[1] / own[1]);
        let z_rep = libm::hypotf(err[0] / reported[0], err[1] / reported[1]);
        assert!(z_own > 3.0, "own σ {own:?} against the error {err:?}");
        assert!(z_rep < 2.0, "reported σ {reported:?} against the error {err:?}");
    }

    #[test]
    fn the_gust_variance_is_measured_from_the_innovations() {
        let calm = circle(0.0);
        let gusty = circle(1.5);
        // Calm: only the model's own noise (flow-angle allowance) — nothing left over.
        assert!(calm.gust_var() < 0.05, "calm: {}", calm.gust_var());
        // 1.5 m/s gusts: variance 2.25 (m/s)², within the smoothing's scatter.
        assert!((gusty.gust_var() - 2.25).abs() < 0.7, "gusty: {}", gusty.gust_var());
        // The mean wind is still found through the gusts.
        let e = gusty.wind();
        assert!((e[0] + 3.0).abs() < 0.5 && e[1].abs() < 0.5, "wind {e:?}");
    }
}
