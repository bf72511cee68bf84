//! Aid source: the heading from the course of the air-relative velocity, for what
//! the GPS acceleration cannot see — the initial heading, and the heading on long
//! straight legs. Control policy and fusion.
//!
//! The air-relative course `χ_a = atan2(v_E − w_E, v_N − w_N)` equals the course of the
//! air-velocity direction when the flight is coordinated (β ≈ 0): the direction across the
//! body y-axis at the GPS's flight-path angle ([`slip_free`]), which needs no angle of
//! attack. Before the wind is known, the course differs from the heading by up to the crab
//! angle: it only aligns the heading, with that allowance as its variance.

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
#[cfg(any(test, feature = "internals"))]
pub fn course_of(x: &Vec3) -> (f32, AttRow) {
    (crate::math::atan2(x[1], x[0]), course_jacobian(x))
}

/// The Jacobian of [`course_of`] alone (no `atan2`).
fn course_jacobian(x: &Vec3) -> AttRow {
    let (xn, xe, xd) = (x[0], x[1], x[2]);
    let h2 = crate::math::max(xn * xn + xe * xe, 1e-6);
    [-xn * xd / h2, -xe * xd / h2, 1.0]
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

/// Vertical air motion a course allows for, m/s (thermals, gusts): in a bank it turns
/// the no-slip air-velocity direction sideways ([`slip_free`]).
const VERTICAL_AIR_SIGMA: f32 = 0.5;
/// Tilt variance (roll + pitch, rad²) below which the no-slip flow is taken: 2·(4°)².
const TILT_SETTLED_VAR: f32 = 0.009_75;
/// The angle of attack allowed for where the flow is taken along the body x-axis, rad.
const ALPHA_ALLOWANCE: f32 = 0.15;
/// `sin²` of the bank below which [`slip_free`] gives way to the body x-axis ((sin 5°)²): its
/// `α·sin φ` is under 0.5° there, and the wind aid saves a square root on straight legs.
const MIN_SIN2_BANK: f32 = 0.007_6;
/// `cos²` of the bank beyond which [`slip_free`] gives way to the body x-axis ((cos 45°)²).
const MIN_COS2_BANK: f32 = 0.5;
/// `sin²` of the climb or dive beyond which [`slip_free`] gives way ((sin 30°)²).
const MAX_SIN2_PATH: f32 = 0.25;

/// The air-velocity direction of coordinated flight, for the course ([`flow`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flow {
    /// The horizontal part of its unit vector, NED `[N, E]`.
    pub dir: [f32; 2],
    /// The Jacobian of its course w.r.t. the NED attitude error.
    pub h: AttRow,
    /// The variance of its course from vertical air motion, rad².
    pub var: f32,
}

/// The air-velocity direction with no slip, the horizontal part of its unit vector (NED
/// `[N, E]`): in the body's x–z plane, at the down component `s = v_D/V_a` the GPS gives
/// (`vd` the down velocity, `va` the airspeed, m/s; still vertical air). No angle of attack enters (a bank turns an
/// assumed α sideways, `α·sin φ`: 3° at 6° and 30°); the body y-axis `y` alone fixes it:
/// `cos μ·ĥ + sin μ·(y × ĥ)`, `ĥ = [y_E, −y_N, 0]/|y_h|` the horizontal unit vector across
/// `y` (on the body x-axis' side; upright shown), `sin μ = −s/|y_h|`. Its course is `atan2(y_E, y_N) − 90°`
/// plus a climb term `atan(tan μ·y_D)`. `None` banked beyond 45° or climbing or diving beyond
/// 30°, where its tilt coupling (`tan φ`) outgrows the α it removes: there the caller takes
/// the body x-axis. Hand-written: one range-limited square root and no trigonometry (the
/// wind aid calls it at every fix).
pub fn slip_free(r: &Mat3, vd: f32, va: f32) -> Option<[f32; 2]> {
    slip_free_terms(r, vd, va).map(|t| slip_free_dir(r, t))
}

/// [`slip_free`]'s direction from its terms `(|y_h|², s)`.
#[inline(always)]
fn slip_free_dir(r: &Mat3, (hy2, s): (f32, f32)) -> [f32; 2] {
    let y: Vec3 = [r[0][1], r[1][1], r[2][1]];
    // |y_h|·cos μ; the horizontal part is `(|y_h| cos μ·[y_E, −y_N] − s·y_D·[y_N, y_E])/|y_h|²`
    // upright. Inverted (`z_D = R₂₂ < 0`) `ĥ` turns round, and with it the sign of `sin μ`
    // and of `y × ĥ`: only the first term changes sign.
    let q = crate::math::sqrt(hy2 - s * s);
    let q = if r[2][2] < 0.0 { -q } else { q };
    let (sy, k) = (s * y[2], 1.0 / hy2);
    [(q * y[1] - sy * y[0]) * k, (-q * y[0] - sy * y[1]) * k]
}

/// `|y_h|²` and `s` where [`slip_free`] applies, `None` where it gives way.
fn slip_free_terms(r: &Mat3, vd: f32, va: f32) -> Option<(f32, f32)> {
    let hy2 = r[0][1] * r[0][1] + r[1][1] * r[1][1];
    let s = vd / crate::math::max(va, 1.0);
    let yd2 = r[2][1] * r[2][1];
    (yd2 >= MIN_SIN2_BANK && hy2 >= MIN_COS2_BANK && s * s <= MAX_SIN2_PATH).then_some((hy2, s))
}

/// Which air-velocity direction the course and wind aids take ([`flow`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlowModel {
    /// The body x-axis, with the α allowance: while the tilt is unsettled the body y-axis
    /// the no-slip flow hangs on is itself tens of degrees off.
    BodyAxis,
    /// The no-slip flow ([`slip_free`]), its course Jacobian the body x-axis' (heading
    /// only): while the heading is coarse its innovation is tens of degrees, and put through
    /// the y-axis Jacobian (`tan φ` of it into the tilt) it turns tilt and gyro biases off.
    SlipFree,
    /// The no-slip flow with its own Jacobian (the tilt coupling).
    SlipFreeCoupled,
}

/// The air-velocity direction for the course at the down velocity `vd` and airspeed `va`
/// (m/s; [`slip_free`] where `model` and the attitude allow, else the body x-axis), with the Jacobian of its course ([`course_of`]'s for the
/// body y-axis where [`FlowModel::SlipFreeCoupled`]; the climb term's is second order; else
/// for the x-axis) and its variance ([`flow_var`]).
pub fn flow(r: &Mat3, vd: f32, va: f32, model: FlowModel) -> Flow {
    let terms = model_terms(r, vd, va, model);
    let var = terms_var(r, va, terms);
    let x = [r[0][0], r[1][0], r[2][0]];
    match terms {
        Some(t) if model == FlowModel::SlipFreeCoupled => {
            Flow { dir: slip_free_dir(r, t), h: course_jacobian(&[r[0][1], r[1][1], r[2][1]]), var }
        }
        Some(t) => Flow { dir: slip_free_dir(r, t), h: course_jacobian(&x), var },
        None => Flow { dir: [x[0], x[1]], h: course_jacobian(&x), var },
    }
}

/// [`flow`]'s direction alone (no Jacobian, no variance: the wind aid's, every fix).
#[inline(always)]
pub fn flow_dir(r: &Mat3, vd: f32, va: f32, model: FlowModel) -> [f32; 2] {
    model_terms(r, vd, va, model).map_or([r[0][0], r[1][0]], |t| slip_free_dir(r, t))
}

/// The variance of the flow's course ([`flow`]) at the attitude `r`, down air velocity
/// `vd` and airspeed `va` (m/s), rad²: where [`slip_free`] applies, the vertical air's,
/// `(σ_w·tan φ/V_a)²`; elsewhere the angle of attack's a bank turns sideways, `(α·sin φ)²`
/// at [`ALPHA_ALLOWANCE`].
pub fn flow_var(r: &Mat3, vd: f32, va: f32, model: FlowModel) -> f32 {
    terms_var(r, va, model_terms(r, vd, va, model))
}

/// [`slip_free`]'s terms where `model` takes it and the attitude allows.
#[inline(always)]
fn model_terms(r: &Mat3, vd: f32, va: f32, model: FlowModel) -> Option<(f32, f32)> {
    if model == FlowModel::BodyAxis {
        None
    } else {
        slip_free_terms(r, vd, va)
    }
}

/// [`flow_var`] from the terms of the flow taken (`None`: the body x-axis).
#[inline(always)]
fn terms_var(r: &Mat3, va: f32, terms: Option<(f32, f32)>) -> f32 {
    let yd2 = r[2][1] * r[2][1];
    match terms {
        Some((hy2, _)) => VERTICAL_AIR_SIGMA * VERTICAL_AIR_SIGMA / crate::math::max(va * va, 1.0) * (yd2 / hy2),
        None => ALPHA_ALLOWANCE * ALPHA_ALLOWANCE * yd2,
    }
}

/// The course residual `χ_a − χ̂` (rad, wrapped), `χ̂` the course of `flow` ([`flow`]),
/// and its variance: the course noise of velocity variance `vel_var` (m/s)², the wind's
/// `wind_var` (m/s)², the flow's own and the slip floor.
pub fn residual(flow: &Flow, v_air: Vec3, vel_var: f32, wind_var: f32, cfg: &QuatConfig) -> (f32, AttRow, f32) {
    let psi = crate::math::atan2(flow.dir[1], flow.dir[0]);
    let chi = crate::math::atan2(v_air[1], v_air[0]);
    let speed2 = crate::math::max(v_air[0] * v_air[0] + v_air[1] * v_air[1], 1e-3);
    let var = (vel_var + wind_var) / speed2 + cfg.course_sigma * cfg.course_sigma + flow.var;
    (wrap_pi(chi - psi), flow.h, var)
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
    /// The air-velocity direction the aids take now ([`FlowModel`]): the body x-axis until
    /// the tilt has settled ([`TILT_SETTLED_VAR`]), the no-slip flow after, with its tilt
    /// coupling once the heading is no longer coarse.
    pub(super) fn flow_model(&self) -> FlowModel {
        if !self.tilt_settled() {
            FlowModel::BodyAxis
        } else if self.heading_coarse() {
            FlowModel::SlipFree
        } else {
            FlowModel::SlipFreeCoupled
        }
    }

    /// Whether the tilt is aligned and its variance below [`TILT_SETTLED_VAR`].
    #[inline(always)]
    pub(super) fn tilt_settled(&self) -> bool {
        let c = self.ekf.covariance();
        self.tilt_aligned && c[0][0] + c[1][1] <= TILT_SETTLED_VAR
    }

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
            let f = flow(&self.epoch_dcm(epoch), d.vel[2], self.wind.airspeed(), self.flow_model());
            let (y, _, _) = residual(&f, d.vel, vel_var, 0.0, q);
            let var = self.crab_var(d.vel, f.var);
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
        let flow = flow(&self.epoch_dcm(epoch), d.vel[2], self.wind.airspeed(), self.flow_model());
        let turn = if known {
            None
        } else {
            self.turn_heading_over(d.prev_vel, d.dt, d.vel, w, [vel_var, vel_var], &flow)
        };
        let crab = if known { 0.0 } else { self.crab_var(d.vel, flow.var) };
        let (v, wind_and_gusts, whole, turn_y) = if known {
            (v_air, wind_var + self.wind.gust_var(), None, None)
        } else if let Some((yt, vt)) = turn.filter(|t| t.1 < crab) {
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

    /// Body → NED for roll, pitch, yaw (rad).
    fn dcm(roll: f32, pitch: f32, yaw: f32) -> Mat3 {
        let e = crate::rotation::Euler { roll, pitch, yaw };
        super::super::quat::to_dcm(&super::super::quat::from_euler(&e))
    }

    /// `Rot(δθ)·r`: the attitude turned by the small NED rotation `dt` (rad).
    fn turned(r: &Mat3, dt: Vec3) -> Mat3 {
        let t = super::super::quat::to_dcm(&super::super::quat::from_rotation_vector(dt));
        core::array::from_fn(|i| core::array::from_fn(|j| (0..3).map(|k| t[i][k] * r[k][j]).sum()))
    }

    /// Forward model: a body at any attitude from 5° to 44° of bank (and inverted), flying with
    /// an angle of attack from −5° to 15° and no slip, climbing or diving up to 25°: the air
    /// velocity is `R·V[cos α, 0, sin α]`, and its horizontal direction is what the no-slip
    /// flow gives from the down velocity and the airspeed alone, within 1e-4 — while the body
    /// x-axis is off by up to `α·sin φ`. Nearer level it gives way to the body x-axis.
    #[test]
    fn the_no_slip_flow_is_the_air_velocity_whatever_the_angle_of_attack() {
        let deg = core::f32::consts::PI / 180.0;
        let (mut n, mut worst_x) = (0, 0.0f32);
        for roll in [-44.0f32, -30.0, -10.0, 0.0, 20.0, 44.0, 150.0, 180.0, -160.0] {
            for pitch in [-20.0f32, -5.0, 0.0, 10.0, 25.0] {
                for yaw in [-170.0f32, -60.0, 0.0, 35.0, 120.0] {
                    for alpha in [-5.0f32, 0.0, 6.0, 15.0] {
                        let r = dcm(roll * deg, pitch * deg, yaw * deg);
                        let (sa, ca) = (libm::sinf(alpha * deg), libm::cosf(alpha * deg));
                        let va = 23.0;
                        let v: Vec3 = core::array::from_fn(|i| va * (r[i][0] * ca + r[i][2] * sa));
                        let Some(dir) = slip_free(&r, v[2], va) else {
                            let level = r[2][1] * r[2][1] < MIN_SIN2_BANK;
                            assert!(level || v[2] * v[2] > 0.25 * va * va, "roll {roll} pitch {pitch} α {alpha}: gave way");
                            continue;
                        };
                        n += 1;
                        for i in 0..2 {
                            assert!((dir[i] - v[i] / va).abs() < 1e-4, "roll {roll} pitch {pitch} yaw {yaw} α {alpha}: {dir:?} vs {v:?}");
                        }
                        let off = wrap_pi(libm::atan2f(r[1][0], r[0][0]) - libm::atan2f(v[1], v[0]));
                        worst_x = worst_x.max(off.abs());
                    }
                }
            }
        }
        assert!(n > 500, "{n} attitudes");
        assert!(worst_x > 5.0 * deg, "the body x-axis should miss the flow in a bank: {worst_x}");
        // Knife edge: it gives way.
        assert!(slip_free(&dcm(60.0 * deg, 0.0, 0.0), 0.0, 20.0).is_none());
    }

    /// The flow's course Jacobian against central finite differences of its course, at
    /// banks to 45° and a level flight path (the climb term's derivative is left out):
    /// within 2e-3 per component; and `course_of`'s for the body x-axis the same way, so
    /// both share one convention for the attitude error.
    #[test]
    fn the_flow_jacobian_matches_finite_differences() {
        let deg = core::f32::consts::PI / 180.0;
        for (roll, pitch, yaw) in [(8.0f32, 3.0f32, 10.0f32), (30.0, 6.0, -100.0), (-42.0, 8.0, 170.0), (20.0, -4.0, 45.0)] {
            let r = dcm(roll * deg, pitch * deg, yaw * deg);
            let f = flow(&r, 0.0, 20.0, FlowModel::SlipFreeCoupled);
            let x_axis = |r: &Mat3| [r[0][0], r[1][0], r[2][0]];
            let (_, hx) = course_of(&x_axis(&r));
            let e = 1e-3;
            for k in 0..3 {
                let mut d = [0.0; 3];
                d[k] = e;
                let course = |r: &Mat3| {
                    let dir = slip_free(r, 0.0, 20.0).unwrap();
                    libm::atan2f(dir[1], dir[0])
                };
                let (rp, rm) = (turned(&r, d), turned(&r, [-d[0], -d[1], -d[2]]));
                let fd = wrap_pi(course(&rp) - course(&rm)) / (2.0 * e);
                assert!((fd - f.h[k]).abs() < 2e-3, "{roll} {pitch} {yaw}, axis {k}: {fd} vs {}", f.h[k]);
                let fdx = wrap_pi(course_of(&x_axis(&rp)).0 - course_of(&x_axis(&rm)).0) / (2.0 * e);
                assert!((fdx - hx[k]).abs() < 2e-3, "x-axis {roll} {pitch} {yaw}, axis {k}: {fdx} vs {}", hx[k]);
            }
        }
    }
}
