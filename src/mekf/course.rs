//! Aid source: the heading from the course of the air-relative velocity, for what
//! the GPS acceleration cannot see — the initial heading, and the heading on long
//! straight legs. Control policy and fusion.
//!
//! The air-relative course `χ_a = atan2(v_E − w_E, v_N − w_N)` equals the course of
//! the air-velocity direction (the body x-axis pitched by the learnt α, [`super::aoa`])
//! when the flight is coordinated (β ≈ 0); a bank turns the α offset sideways. Before the wind is known, the course differs from the
//! heading by up to the crab angle: it only aligns the heading, with that allowance
//! as its variance.

use super::filter::{AttRow, Fused, Mekf};
use crate::config::QuatConfig;
use super::dv_window::WindowMean;
use super::latency::EpochDcm;
use crate::health::{AxisStatus, AxisUpdate, Flags};
use crate::math::{wrap_pi, Mat3, Vec3};
use crate::measure::gps_delta::GpsDelta;

/// The heading of the body x-axis, rad (NED, from north), and its Jacobian w.r.t. the
/// NED attitude error: `∂ψ/∂δθ = [−x_N x_D, −x_E x_D, h²]/h²`, `h² = x_N² + x_E²`.
#[cfg(any(test, feature = "internals"))]
pub fn heading(r_bn: &Mat3) -> (f32, AttRow) {
    course_of(&[r_bn[0][0], r_bn[1][0], r_bn[2][0]])
}

/// The course of a body-fixed direction `x` given in NED, rad, and its Jacobian (as
/// [`heading`], which is this for the body x-axis).
pub fn course_of(x: &Vec3) -> (f32, AttRow) {
    let (xn, xe, xd) = (x[0], x[1], x[2]);
    let h2 = crate::math::max(xn * xn + xe * xe, 1e-6);
    let psi = crate::math::atan2(xe, xn);
    (psi, [-xn * xd / h2, -xe * xd / h2, 1.0])
}

/// Whether the attitude and flight allow a course measurement of the heading:
/// bank and pitch within `sin_max` (the sine of the limit), enough air-relative speed,
/// no slip.
pub fn usable(
    r_bn: &Mat3,
    v_air: Vec3,
    lateral_f: f32,
    cfg: &QuatConfig,
    min_speed: f32,
    sin_max: f32,
) -> bool {
    let sin_bank = r_bn[2][1]; // sin φ cos θ: the body y-axis' down component
    let sin_pitch = -r_bn[2][0];
    let speed2 = v_air[0] * v_air[0] + v_air[1] * v_air[1];
    let upright = r_bn[2][2] > 0.0; // cos φ cos θ: not inverted
    upright
        && libm::fabsf(sin_bank) <= sin_max
        && libm::fabsf(sin_pitch) <= sin_max
        && speed2 >= min_speed * min_speed
        && lateral_f * lateral_f <= cfg.course_max_lateral * cfg.course_max_lateral
}

/// The course residual `χ_a − χ̂` (rad, wrapped), `χ̂` the course of the air-velocity
/// direction `flow_axis` (NED), and its variance: the course noise of velocity variance
/// `vel_var` (m/s)², the wind's `wind_var` (m/s)² and the slip floor.
pub fn residual(
    flow_axis: &Vec3,
    v_air: Vec3,
    vel_var: f32,
    wind_var: f32,
    cfg: &QuatConfig,
) -> (f32, AttRow, f32) {
    let (psi, h) = course_of(flow_axis);
    let chi = crate::math::atan2(v_air[1], v_air[0]);
    let speed2 = crate::math::max(v_air[0] * v_air[0] + v_air[1] * v_air[1], 1e-3);
    let var = (vel_var + wind_var) / speed2 + cfg.course_sigma * cfg.course_sigma;
    (wrap_pi(chi - psi), h, var)
}

/// The direction of the air velocity in a turn, NED `[N, E]` (not unit length): with a
/// steady airspeed and wind, the ground acceleration `a` (NED, m/s²) is the air velocity's
/// centripetal one, perpendicular to it whatever the wind, and the ground velocity `v`
/// (m/s) tells on which side (its crab off the air velocity is below 90° while the wind
/// is below the airspeed). `None` unless `a` is mostly across `v` (at least 45° off it: a
/// speed change along the track is no turn). Its course is `atan2(E, N)`; callers compare
/// it with a heading by one `atan2` of the cross and dot products.
pub fn turn_direction(a: Vec3, v: Vec3) -> Option<[f32; 2]> {
    let cross = v[0] * a[1] - v[1] * a[0];
    let (a2, v2) = (a[0] * a[0] + a[1] * a[1], v[0] * v[0] + v[1] * v[1]);
    if 2.0 * cross * cross < a2 * v2 {
        return None;
    }
    // Turning right (cross > 0) the air velocity is `a` turned −90°, left +90°.
    let s = if cross > 0.0 { 1.0 } else { -1.0 };
    Some([s * a[1], -s * a[0]])
}

/// Fuses the course as a heading measurement.
pub fn fuse(ekf: &mut Mekf, y: f32, h: AttRow, var: f32, cfg: &QuatConfig) -> Fused {
    ekf.fuse([y], &[h], [var], cfg.gate_chi2_heading)
}

/// A course update this far beyond its σ² (NIS, a 2σ residual) doubts the heading;
/// `QuatConfig::course_doubt_after` of them in a row reset it and the wind.
const COURSE_DOUBT_NIS: f32 = 4.0;

impl super::QuatAhrs {
    /// The course: aligns the heading while it is unknown, then aids it at most every
    /// `course_interval` while the wind is known well enough.
    pub(super) fn control_course(
        &mut self,
        t_us: u64,
        d: &GpsDelta,
        w: &WindowMean,
        vel_var: f32,
        epoch: &mut EpochDcm,
    ) {
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
        if !usable(r, v_air, w.f_body[1], q, min_speed, self.course_sin_bank()) {
            self.health.yaw_skipped_sideslip = self.health.yaw_skipped_sideslip.wrapping_add(1);
            return;
        }
        if !self.yaw_aligned {
            let (y, _, _) = residual(&self.flow_axis(w, &self.epoch_dcm(epoch)), d.vel, vel_var, 0.0, q);
            let var = self.crab_var(d.vel);
            self.set_heading(y, var);
            self.yaw_aligned = true;
            self.last_update.axes[2].status = AxisStatus::Initialised;
            return;
        }
        self.last_course_t = Some(t_us);
        // With the wind known: the air-relative course. Without: the ground course, with
        // the crab angle an unknown wind could cause as its error.
        let vw = self.wind.reported_variance(0.0);
        let wind_var = vw[0] + vw[1];
        let known = wind_var <= q.wind_max_sigma * q.wind_max_sigma;
        // Known: the air velocity, its variance with the wind's and the gusts'. Unknown: in a
        // turn, the air course the turn gives with its variance; elsewhere the ground velocity
        // with the crab allowance as the whole variance.
        let flow = self.flow_axis(w, &self.epoch_dcm(epoch));
        let turn = if known {
            None
        } else {
            self.turn_heading_over(d.prev_vel, d.dt, d.vel, w, [vel_var, vel_var], &flow)
        };
        let (v, wind_and_gusts, whole, turn_y) = if known {
            (v_air, wind_var + self.wind.gust_var(), None, None)
        } else if let Some((yt, vt)) = turn.filter(|t| t.1 < self.crab_var(d.vel)) {
            // Most of its variance is the same on every fix of one turn (`α·sin φ`, the
            // slip, an untracked latency's turn): fused again and again it would be taken
            // for known. It only aids a heading less known than one fix's course.
            if self.ekf.covariance()[2][2] < vt {
                return;
            }
            (d.vel, 0.0, Some(vt), Some(yt))
        } else {
            // The crab allowance only bounds a drifting heading: once the GPS acceleration
            // knows the heading far better, a course could only pull it off.
            let crab = self.crab_var(d.vel);
            if self.ekf.covariance()[2][2] < 0.1 * crab {
                return;
            }
            (d.vel, 0.0, Some(crab), None)
        };
        let (y, h, mut var) = residual(&flow, v, vel_var, wind_and_gusts, q);
        if known {
            // The wind was learnt with the attitude's heading, and a share of that heading's
            // error (the coupling) is in it: the course can confirm the heading no better
            // than that share of its variance. Not a white error: each fix's course carries
            // the same one, so it enters as variance, with the heading's σ at this update
            // standing for the σ the wind was learnt with.
            let coupling = self.wind.heading_coupling(v);
            var += coupling * coupling * self.ekf.covariance()[2][2];
        }
        let (y, var) = (turn_y.unwrap_or(y), whole.unwrap_or(var));
        let res = fuse(&mut self.ekf, y, h, var, q);
        let doubtful = res.nis > COURSE_DOUBT_NIS;
        self.course_doubt = if doubtful { self.course_doubt.saturating_add(1) } else { 0 };
        if self.course_doubt >= q.course_doubt_after && q.course_doubt_after > 0 {
            self.course_doubt = 0;
            self.let_heading_go();
            return;
        }
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ground velocity of a circle flown at airspeed `va` (m/s) and heading `psi` (rad) in
    /// the wind `w` (m/s, NED): the forward model the turn's course inverts.
    fn ground(va: f32, psi: f32, w: [f32; 2]) -> Vec3 {
        [va * libm::cosf(psi) + w[0], va * libm::sinf(psi) + w[1], 0.0]
    }

    /// In any wind below the airspeed, either way round, the chord of two fixes 0.5 s
    /// apart gives the heading at their middle; the ground course is off by the crab.
    #[test]
    fn a_turn_gives_the_heading_whatever_the_wind() {
        let (va, span) = (22.0, 0.5);
        let mut worst_crab = 0.0f32;
        for rate in [-0.35f32, -0.12, 0.12, 0.35] {
            for k in 0..12 {
                let wdir = k as f32 * 0.52;
                let w = [12.0 * libm::cosf(wdir), 12.0 * libm::sinf(wdir)];
                let psi0 = 0.3 * k as f32 - 1.0;
                let (v0, v1) = (ground(va, psi0, w), ground(va, psi0 + rate * span, w));
                let a: Vec3 = core::array::from_fn(|i| (v1[i] - v0[i]) / span);
                let mean: Vec3 = core::array::from_fn(|i| 0.5 * (v0[i] + v1[i]));
                let u = turn_direction(a, mean).expect("a turn");
                let chi = libm::atan2f(u[1], u[0]);
                let mid = psi0 + 0.5 * rate * span;
                assert!(wrap_pi(chi - mid).abs() < 1e-4, "rate {rate} wind {wdir}: {chi} vs {mid}");
                let ground_course = libm::atan2f(mean[1], mean[0]);
                worst_crab = worst_crab.max(wrap_pi(ground_course - mid).abs());
            }
        }
        assert!(worst_crab > 0.4, "the wind should crab the ground course: {worst_crab}");
    }

    /// A speed change along the track is no turn.
    #[test]
    fn a_straight_acceleration_is_no_turn() {
        assert!(turn_direction([3.0, 0.5, 0.0], [20.0, 1.0, 0.0]).is_none());
        assert!(turn_direction([-4.0, 0.0, 0.0], [20.0, 0.0, 0.0]).is_none());
        assert!(turn_direction([1.0, 4.0, 0.0], [20.0, 0.0, 0.0]).is_some());
    }
}
