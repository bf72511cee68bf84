//! Alignment of the quaternion filter: the attitude from one fix interval's specific
//! forces (any attitude), the heading from the course, and the heading resets the aid
//! sources ask for.

use super::{course, heading_accel, quat, QuatAhrs, UNKNOWN_HEADING_VAR};
use crate::config::GRAVITY;
use crate::health::AxisStatus;
use crate::math::Vec3;
use crate::measure::gps_delta::GpsDelta;
use super::dv_window::WindowMean;

/// Intervals in a row the alignment skips because their specific forces disagree in length:
/// then it aligns anyway (a sensor's scale may be off by more than the tolerance).
const MAX_ALIGN_SKIPS: u16 = 5;
/// How far apart, as a fraction, the lengths of an interval's body-frame and gyro-rotated
/// mean specific forces may be for the body to count as still against it ([`steady`]).
const STEADY_TOLERANCE: f32 = 0.03;
/// The span of fixes a turn's course is taken over while aligning, s: a 10 Hz interval's
/// acceleration carries `√2·σ_v/0.1 s` of noise (0.7 m/s², 6° on a 30° turn at σ_v 0.05).
const TURN_SPAN: f32 = 0.5;
/// The fixes' velocity noise a turn's course assumes at most, m/s: while aligning nothing
/// has learnt the receiver's noise yet, and receivers report 5–10× their noise or nothing.
const TURN_VEL_SIGMA_MAX: f32 = 0.1;
/// Airspeed change and gusts along the track over a turn's span that its course allows
/// for, m/s² (they turn the acceleration off the perpendicular).
const TURN_ALONG_SIGMA: f32 = 0.5;
/// The yaw variance of an alignment on a course the slip may be off (lateral specific
/// force beyond the limit, or banked beyond it), rad² ((15°)² on top of the crab angle).
const SLIPPING_COURSE_VAR: f32 = 0.0685;

/// Heading variance above which the course is taken up to the aligning bank limit, rad²
/// ((5°)²). Switched on in a steady turn, the attitude about the specific force and the
/// roll-gyro bias that keeps it there leave every GPS-acceleration residual unchanged until
/// the bank changes; the course sees the heading part of that rotation. While the heading
/// is this uncertain, that is worth more than the α error a bank turns sideways (the
/// robustness suite, seeds 1, 4, 5, 6: runs lost 76 → 48; 3° lost 50, 10° 63; the tuning
/// table unchanged).
const WIDE_BANK_VAR: f32 = 0.007_615;

/// The interval's specific force from the GPS, `ā − g`, NED m/s² (level, `−g`, where the
/// fixes carry no vertical velocity).
fn gps_specific_force(d: &GpsDelta) -> Vec3 {
    let a = d.accel_ned;
    [a[0], a[1], if d.vd_valid { a[2] - GRAVITY } else { -GRAVITY }]
}

/// The air-velocity direction of a turn ([`course::turn_direction`]), NED `[N, E]`, where
/// the horizontal acceleration `a` (NED, m/s²) is a manoeuvre ([`heading_accel::manoeuvre`])
/// across the ground velocity `v` (m/s); `None` elsewhere. Inlined: out of line it cost
/// 188 bytes of M4F flash, which has little left.
#[inline(always)]
fn turn_of(a: Vec3, v: Vec3) -> Option<[f32; 2]> {
    if !heading_accel::manoeuvre(a[0] * a[0] + a[1] * a[1]) {
        return None;
    }
    course::turn_direction(a, v)
}

/// Whether the body held still against the specific force over the window: the mean of
/// its body-frame samples has the length of the mean of the same samples turned into NED by
/// the gyro, within [`STEADY_TOLERANCE`]. Through a roll the body-frame mean is the vector
/// of no one attitude (a T-6 switched on in an aileron roll at 2 Hz, 80–100° turned per
/// interval, was aligned 57° off), while the gyro's relative rotations are good before any
/// alignment.
fn steady(w: &WindowMean) -> bool {
    let (b, n) = (crate::math::norm3(w.f_body), crate::math::norm3(w.f_ned));
    libm::fabsf(b - n) <= STEADY_TOLERANCE * n
}

impl QuatAhrs {
    /// Control policy of the alignment, while the tilt is unaligned: in a turn it waits for
    /// fixes 0.5 s apart; the course and the turn give the heading where usable (or, flying,
    /// with a wider σ), then the specific forces the tilt. Cold and not inlined: it runs only
    /// until aligned, and inlined it changed the update's hot path.
    #[cold]
    #[inline(never)]
    pub(super) fn control_alignment(&mut self, d: &GpsDelta, w: &WindowMean, vel_var: [f32; 2]) {
        if self.quat.learn_vel_noise && d.vd_valid {
            let lengths = crate::math::norm3(gps_specific_force(d)) - crate::math::norm3(w.f_ned);
            self.vel_noise.observe_lengths(lengths, d.dt);
        }
        if self.wait_for_turn(d) {
            return;
        }
        if !(steady(w) && self.lengths_agree(d, w, vel_var)) && self.gate_streak < MAX_ALIGN_SKIPS {
            self.gate_streak += 1;
            return;
        }
        let v_air = self.air_velocity(d.vel);
        let (r, min_speed) = (self.ekf.dcm(), self.cfg.min_ground_speed_yaw);
        let sin_max = self.course_sin_bank();
        let course_ok = course::usable(r, v_air, w.f_body[1], &self.quat, min_speed, sin_max);
        let flying = v_air[0] * v_air[0] + v_air[1] * v_air[1] >= min_speed * min_speed;
        self.align(d, w, vel_var, course_ok, flying);
    }

    /// Whether to wait for a longer span of the turn before aligning: one short interval's
    /// course is the noise of two velocities over it.
    fn wait_for_turn(&mut self, d: &GpsDelta) -> bool {
        if turn_of(d.accel_ned, d.mean_vel).is_none() {
            self.turn_span = None;
            return false;
        }
        let (_, span) = self.turn_span.get_or_insert((d.prev_vel, 0.0));
        *span += d.dt;
        *span < TURN_SPAN
    }

    /// Whether the interval's IMU and GPS specific forces have the same length, within 10 %
    /// (scale factors) and 3σ of the GPS noise: the alignment takes them for one vector in
    /// two frames. A fast roll under a receiver latency, or a jolt, breaks that, and the
    /// rotation between them is then no attitude.
    fn lengths_agree(&self, d: &GpsDelta, w: &WindowMean, vel_var: [f32; 2]) -> bool {
        let ni = crate::math::norm3(w.f_body);
        let ng = crate::math::norm3(gps_specific_force(d));
        let sg = crate::math::sqrt((vel_var[0] + vel_var[1]) / (d.dt * d.dt));
        libm::fabsf(ni - ng) <= 0.1 * ng + 3.0 * sg
    }

    /// Aligns the attitude with the interval's specific forces: the shortest rotation
    /// that takes the IMU's NED specific force onto the GPS one (any attitude: nothing
    /// assumes upright flight), after turning the heading onto the course when usable. In
    /// a turn the heading also comes from the turn itself ([`Self::turn_heading`]), which
    /// no wind crabs; the two are weighted by their variances.
    ///
    /// In flight the course gives the heading first even where it is not `course_ok`
    /// (slipping, steeply banked: a wider σ), because the specific force is only matched
    /// as a vector: in a turn its horizontal part, rotated by a wrong heading, would be
    /// read as tilt. The tilt's variance takes the heading's share, `(|f_h|/|f|)²·σ_ψ²`.
    fn align(&mut self, d: &GpsDelta, w: &WindowMean, vel_var: [f32; 2], course_ok: bool, flying: bool) {
        let heading_known = course_ok || flying;
        let flow = course::flow(&self.dcm_at_epoch(), d.vel[2], self.wind.airspeed(), self.flow_model());
        let yaw_var = match (course_ok, flying) {
            (true, _) => self.crab_var(d.vel, flow.var),
            (false, true) => self.crab_var(d.vel, flow.var) + SLIPPING_COURSE_VAR,
            _ => UNKNOWN_HEADING_VAR,
        };
        // A new attitude: the heading error the wind took in is no longer this one's.
        self.wind.decouple_heading(self.ekf.covariance()[2][2]);
        let yaw_var = if heading_known {
            let (y, _, _) = course::residual(&flow, d.vel, 0.0, 0.0, &self.quat);
            let (y, var) = match self.turn_heading(d, w, vel_var, &flow) {
                // Two independent looks at one angle, weighted by their variances.
                Some((yt, vt)) => (y + crate::math::wrap_pi(yt - y) * yaw_var / (yaw_var + vt), yaw_var * vt / (yaw_var + vt)),
                None => (y, yaw_var),
            };
            self.ekf.set_heading(y, 1.0);
            var
        } else {
            yaw_var
        };
        let r = *self.ekf.dcm();
        let f_imu = quat::rotate(&r, w.f_body);
        let f_gps = gps_specific_force(d);
        let q = quat::mul(&quat::between(f_imu, f_gps), &self.ekf.quaternion());
        let s = 3.0 * crate::math::PI / 180.0;
        let fh2 = f_gps[0] * f_gps[0] + f_gps[1] * f_gps[1];
        let f2 = crate::math::max(fh2 + f_gps[2] * f_gps[2], 1.0);
        let tilt_var = s * s + crate::math::min(fh2 / f2, 1.0) * yaw_var;
        self.ekf.reset_attitude(q, [tilt_var, tilt_var, yaw_var]);
        self.tilt_aligned = true;
        self.yaw_aligned = heading_known;
        self.trust_streak = 0;
        self.latency.restart();
        self.vel_noise.restart();
        self.consistency.reset();
        self.heading_accel.reset(); // the attitude was reset: the sums describe another heading
        self.gate_streak = 0;
        self.turn_span = None;
        self.last_update.axes[0].status = AxisStatus::Initialised;
        self.last_update.axes[1].status = AxisStatus::Initialised;
    }

    /// The heading residual from a turn ([`course::turn_direction`]: the air velocity is
    /// across the ground acceleration, whatever the wind) and its variance, rad and rad²,
    /// or `None` outside a turn (see [`Self::turn_heading_over`]).
    fn turn_heading(&self, d: &GpsDelta, w: &WindowMean, vel_var: [f32; 2], flow: &course::Flow) -> Option<(f32, f32)> {
        let (v0, span) = self.turn_span?;
        self.turn_heading_over(v0, span, d.vel, w, vel_var, flow)
    }

    /// The heading residual from the turn between the fixes `v0` (m/s, `span` s before)
    /// and `v1`, rad, and its variance, rad². `flow` is the air-velocity direction at the
    /// newest fix (NED); the turn gives the course at the span's middle, carried on by the
    /// turn rate over half the span. The variance: the acceleration's noise across it, an
    /// airspeed change or gust along the track (`TURN_ALONG_SIGMA`), a quarter of the
    /// carried turn, the α offset a bank turns sideways, the slip floor, and the turn over
    /// a receiver latency the tracker has not yet learnt. Out of line: the alignment and
    /// the course share one copy (M4F flash).
    #[inline(never)]
    pub(super) fn turn_heading_over(
        &self,
        v0: Vec3,
        span: f32,
        v1: Vec3,
        w: &WindowMean,
        vel_var: [f32; 2],
        flow: &course::Flow,
    ) -> Option<(f32, f32)> {
        let a: Vec3 = core::array::from_fn(|i| (v1[i] - v0[i]) / span);
        let mean: Vec3 = core::array::from_fn(|i| 0.5 * (v1[i] + v0[i]));
        let u = turn_of(a, mean)?;
        let a2 = a[0] * a[0] + a[1] * a[1];
        let psi_dot = self.heading_rate(w);
        let turned = psi_dot * 0.5 * span;
        // The angle from the flow's course to the turn's: one atan2 of cross and dot.
        let f = flow.dir;
        let off = crate::math::atan2(f[0] * u[1] - f[1] * u[0], f[0] * u[0] + f[1] * u[1]);
        let y = crate::math::wrap_pi(off + turned);
        let vv = crate::math::min(vel_var[0] + vel_var[1], 2.0 * TURN_VEL_SIGMA_MAX * TURN_VEL_SIGMA_MAX);
        let noise = vv / (span * span) + TURN_ALONG_SIGMA * TURN_ALONG_SIGMA;
        let cs = self.quat.course_sigma;
        let late = psi_dot * psi_dot * self.latency.untracked_var();
        Some((y, noise / a2 + 0.0625 * turned * turned + flow.var + cs * cs + late))
    }

    /// The turn rate about the vertical over the window, rad/s: in a coordinated turn the
    /// rate vector is vertical and `ω·f = −ψ̇·g` whatever the bank (a roll rate, across f,
    /// does not count). Out of line: two callers (M4F flash).
    #[inline(never)]
    pub(super) fn heading_rate(&self, w: &WindowMean) -> f32 {
        let (wb, f) = (self.body_rates(), w.f_body);
        -(wb[0] * f[0] + wb[1] * f[1] + wb[2] * f[2]) / GRAVITY
    }

    /// Lets the heading and the wind fitted with it go (heading σ 1 rad), counted in
    /// `Health::gate_resets[2]`: the updates say both are off together. The direct
    /// solution finds the heading again in the next manoeuvre.
    pub(super) fn let_heading_go(&mut self) {
        self.health.gate_resets[2] = self.health.gate_resets[2].wrapping_add(1);
        self.set_heading(0.0, UNKNOWN_HEADING_VAR);
        self.wind.reset();
    }

    /// Turns the heading by `angle` (rad, about NED down) with variance `var` (rad²); the
    /// direct solution's sums no longer describe the new heading.
    pub(super) fn set_heading(&mut self, angle: f32, var: f32) {
        self.wind.decouple_heading(self.ekf.covariance()[2][2]);
        self.ekf.set_heading(angle, var);
        self.heading_accel.reset();
        self.vel_noise.restart();
    }

    /// An implausible gyro-bias estimate (|b| beyond `bias_plausible_sigmas` turn-on σ) is
    /// not a bias: the updates have put into it an attitude error no state holds, and the
    /// attitude that bias kept is no better. The biases go back to their prior and the
    /// attitude is aligned again from the next interval, flagged doubtful and counted in
    /// `Health::gate_resets[1]`.
    pub(super) fn check_bias(&mut self) {
        let b = self.ekf.bias();
        if b[0] * b[0] + b[1] * b[1] + b[2] * b[2] <= self.lim.bias2 {
            return;
        }
        self.health.gate_resets[1] = self.health.gate_resets[1].wrapping_add(1);
        let s = self.cfg.init_sigma_bias;
        self.ekf.reset_bias(s * s);
        self.tilt_aligned = false;
        self.gate_streak = 0;
        self.flags.set(crate::health::Flags::UNRELIABLE, true);
        self.trust_streak = 0;
    }

    /// The variance of the course as a heading while the wind is unknown: the crab
    /// angle `crab_wind` could cause at the ground velocity `v` (m/s), the slip floor, and
    /// the flow's own `flow_var` (rad², [`course::Flow::var`]: vertical air, or the angle of
    /// attack where the body x-axis stands in for the flow).
    pub(super) fn crab_var(&self, v: Vec3, flow_var: f32) -> f32 {
        let speed = crate::math::max(crate::math::hypot(v[0], v[1]), 1.0);
        let s = crate::math::min(self.quat.crab_wind / speed, 1.0);
        s * s + self.quat.course_sigma * self.quat.course_sigma + flow_var
    }

    /// The sine of the bank limit for a course: the aligning limit (`course_align_max_bank`)
    /// while the heading is not yet aligned (a loiter may never level its wings; the crab
    /// allowance covers the α offset) or its σ is above [`WIDE_BANK_VAR`]'s 5°, else
    /// `course_max_bank`.
    pub(super) fn course_sin_bank(&self) -> f32 {
        if self.heading_var_above(WIDE_BANK_VAR) {
            self.lim.sin_align_bank
        } else {
            self.lim.sin_bank
        }
    }

    /// Whether the heading is unaligned or too uncertain for linear updates
    /// ([`heading_accel::COARSE_VAR`]): then it is solved directly, not fused.
    pub(super) fn heading_coarse(&self) -> bool {
        self.heading_var_above(heading_accel::COARSE_VAR)
    }

    /// Whether the heading is unaligned or its variance is above `var`, rad².
    fn heading_var_above(&self, var: f32) -> bool {
        !self.yaw_aligned || self.ekf.covariance()[2][2] > var
    }
}
