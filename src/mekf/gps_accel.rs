//! Aid source: the GPS-derived acceleration against the accelerometer, as a 3-D
//! vector in NED (EKF1 in the quaternion filter). Control policy and fusion.
//!
//! Between two fixes the receiver's velocity difference is the mean inertial
//! acceleration, `ā = (v₁ − v₀)/Δt`; the IMU gives the mean specific force in NED,
//! `f̄ = Σ R̂ f Δt / T` ([`super::dv_window`]). The two agree when the attitude is
//! right: `ā − g = R·f̄_body`. Both sides are ground-referenced, so a steady wind
//! does not bias it, and with the error `R = exp([δθ×])R̂` the residual is
//! `y = (ā − g) − f̄ ≈ −[f̄×]·δθ`: it observes the tilt always (gravity) and the
//! heading whenever the aircraft accelerates horizontally (turns, speed changes).
//!
//! Control policy: fused every fix interval once the attitude is aligned; the heading
//! takes part only where the interval sees it; a gated update widens the attitude's
//! variance, three in a row flag it unreliable (`Flags::UNRELIABLE`), and
//! `gate_max_consecutive` reset the heading, then the alignment. Status:
//! `UpdateRecord::axes` (NED, m/s²).

use super::dv_window::WindowMean;
use super::filter::{minus_skew, AttRow, Fused, Mekf};
use super::latency::Jerk;
use super::{heading_accel, unmodelled, QuatAhrs};
use crate::config::{QuatConfig, GRAVITY};
use crate::health::{AxisStatus, AxisUpdate, Flags};
use crate::measure::gps_delta::GpsDelta;

/// The residual, Jacobian and noise of one fix interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// `y = (ā − g) − f̄`, NED, m/s².
    pub y: [f32; 3],
    /// `∂y/∂δθ` (`∂y/∂δb` = 0).
    pub h: [AttRow; 3],
    /// Noise variance per NED axis, (m/s²)², the GPS part included.
    pub r: [f32; 3],
    /// The GPS part of `r`, `(σ₀² + σ₁²)/Δt²` (m/s²)²: left out where the fix noise is a state.
    pub r_gps: f32,
}

/// Forms the measurement of fix interval `d` with the IMU window `w`.
/// `vel_var` = the two fixes' velocity variances (m/s)², `gyro_psd` (rad²/s) and
/// `lag` (s, the receiver latency) give the attitude noise accumulated since the window.
/// `att_var` = the attitude error variances (rad², NED axes) for the second-order term.
#[allow(clippy::too_many_arguments)]
pub fn measurement(
    d: &GpsDelta,
    w: &WindowMean,
    r_bn: &crate::math::Mat3,
    vel_var: [f32; 2],
    cfg: &QuatConfig,
    gyro_psd: f32,
    lag: f32,
    att_var: [f32; 3],
) -> Measurement {
    let f = w.f_ned;
    let a = d.accel_ned;
    let mut y = [a[0] - f[0], a[1] - f[1], a[2] - GRAVITY - f[2]];
    let h = minus_skew(f);
    // GPS: (σ₀² + σ₁²)/Δt² per axis. Accelerometer: white noise over the window, plus the
    // window's own scatter (vibration) rotated into NED. Attitude drift since the window:
    // |f|²·σ_g²·(lag + T/2). A floor for what no model covers (lever arm, timing).
    let gps = (vel_var[0] + vel_var[1]) / (d.dt * d.dt);
    let white = cfg.accel_noise_density * cfg.accel_noise_density / w.duration;
    let f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
    let drift = f2 * gyro_psd * (lag + 0.5 * w.duration);
    let floor = cfg.accel_floor * cfg.accel_floor + cfg.accel_floor_rel * cfg.accel_floor_rel * f2;
    // The rotation's second-order term ½ δθ × (δθ × f): while one axis is uncertain (the
    // heading after alignment) and another is not yet small (the tilt), a tilt error
    // tilts f̄ and the first-order model would read GPS noise across it as heading.
    let [p0, p1, p2] = att_var;
    let second = f2 * (p0 * p1 + p0 * p2 + p1 * p2);
    let mut r = [0.0f32; 3];
    for i in 0..3 {
        let vib: f32 = (0..3).map(|j| r_bn[i][j] * r_bn[i][j] * w.sem_sq[j]).sum();
        r[i] = gps + white + vib + drift + floor + second;
    }
    if !d.vd_valid {
        // No measured vertical velocity: the down axis carries no information.
        y[2] = 0.0;
        r[2] = 1e6;
    }
    Measurement { y, h, r, r_gps: gps }
}

/// Whether the interval's horizontal specific force is significantly (3σ) more than
/// tilt error and noise could make: only then does the measurement see the heading.
pub fn sees_heading(m: &Measurement, w: &WindowMean, att_var: [f32; 3]) -> bool {
    let f = w.f_ned;
    let fh2 = f[0] * f[0] + f[1] * f[1];
    let tilt_var = crate::math::max(att_var[0], att_var[1]);
    let noise = GRAVITY * GRAVITY * tilt_var + 0.5 * (m.r[0] + m.r[1]);
    fh2 > 9.0 * noise
}

/// Fuses `m` with the χ² gate of the configuration. `fix_var` = the two fixes'
/// velocity variances when both receivers reported them: their noise is then a state
/// (`Mekf::fuse_with_fix_noise`), else white.
pub fn fuse(
    ekf: &mut Mekf,
    m: &Measurement,
    fix_var: Option<[f32; 2]>,
    dt: f32,
    cfg: &QuatConfig,
) -> Fused {
    match fix_var {
        Some([v0, v1]) => {
            let white = m.r.map(|r| r - m.r_gps);
            let vd = |v: f32| if m.r[2] >= 1e6 { [v, v, 0.0] } else { [v; 3] };
            ekf.fuse_with_fix_noise(m.y, &m.h, white, vd(v0), vd(v1), dt, cfg.gate_chi2)
        }
        None => {
            ekf.forget_fix_noise();
            ekf.fuse(m.y, &m.h, m.r, cfg.gate_chi2)
        }
    }
}

/// Each gated GPS-acceleration update multiplies the attitude variance by this: the
/// residual says the attitude is further off than P claims (σ × 1.41 per gated update).
const GATE_INFLATION: f32 = 2.0;
/// No inflation beyond this attitude variance per axis, rad² ((10°)²): further off, the
/// linear update is no longer a correction, and the re-alignment of
/// `gate_max_consecutive` takes over.
const MAX_INFLATED_VAR: f32 = 0.0305;
/// Consecutive gated updates that make the attitude doubtful (`Flags::UNRELIABLE`), and
/// consecutive accepted ones that clear it again.
const DOUBT_AFTER: u16 = 3;
const TRUST_AFTER: u16 = 10;

/// How the heading takes part in one interval's GPS-acceleration update.
#[derive(Debug, Clone, Copy)]
struct HeadingUse {
    /// The heading is unaligned or too uncertain for the linear update
    /// ([`heading_accel::COARSE_VAR`]): it is solved directly, not fused.
    coarse: bool,
    /// The horizontal specific force is significantly more than tilt error and noise
    /// make of it: the update observes the heading.
    sees: bool,
    /// The noise of one horizontal axis before the heading's share, with the tilt's,
    /// (m/s²)²: what the direct heading solution compares against (0 unless `coarse`).
    h_var: f32,
}

/// Fix rate up to which the latency's share of R counts as white, Hz. Above it, R's
/// latency share grows as `rate/LATENCY_WHITE_HZ` (robustness suite, seeds 1, 4, 5, 6: runs
/// lost 48 → 45, lost with NEES > 8 12 → 9; the tuning table, 10 Hz, unchanged; 5 Hz cost
/// it 1.018×).
const LATENCY_WHITE_HZ: f32 = 10.0;
/// Time over which the gyro biases take in a heading error as a rate, s: while the latency
/// tracker moves, each step δd of it says the last updates read `δd·|ω|` rad of latency
/// error as heading, and the biases' variance grows by `(δd·|ω|/τ)²` (docs/design.md, "The
/// biases while the tracker learns"; figures in CHANGELOG.md).
const BIAS_TAKES_LATENCY_S: f32 = 20.0;
/// `1/τ²` of [`BIAS_TAKES_LATENCY_S`], s⁻².
const BIAS_PER_LATENCY_STEP: f32 = 1.0 / (BIAS_TAKES_LATENCY_S * BIAS_TAKES_LATENCY_S);

impl QuatAhrs {
    /// The two fixes' velocity variances, (m/s)²: each fix's report (or the guess) times the
    /// learnt scale of the reports; or as reported.
    pub(super) fn vel_var(&mut self, d: &GpsDelta) -> [f32; 2] {
        let guess = self.quat.unreported_vel_sigma;
        if self.quat.learn_vel_noise {
            let n = &mut self.vel_noise;
            n.reference(d.speed_acc[1].unwrap_or(guess));
            return d.speed_acc.map(|a| n.variance(a.unwrap_or(guess)));
        }
        d.speed_acc.map(|a| {
            let s = a.unwrap_or(guess);
            s * s
        })
    }

    /// Control policy and fusion of the GPS acceleration for one fix interval (the
    /// attitude aligned): the measurement, the heading's part in it, the gated fusion,
    /// then what an accepted or a gated update means for the filter.
    pub(super) fn control_gps_accel(
        &mut self,
        t_us: u64,
        d: &GpsDelta,
        w: &WindowMean,
        vel_var: [f32; 2],
    ) {
        // Learnt, the noise is white by construction; as reported, only when both are.
        let reported = d.speed_acc[0].is_some() && d.speed_acc[1].is_some();
        let white_known = reported || self.quat.learn_vel_noise;
        let fix_var = (white_known && self.quat.fix_noise_states).then_some(vel_var);
        let (mut m, jerk, att_var) = self.gps_accel_measurement(d, w, vel_var, fix_var.is_some()
            && cfg!(feature = "latency-consider")
            && self.quat.latency_consider);
        let heading = self.heading_use(&mut m, w, att_var);
        let res = fuse(&mut self.ekf, &m, fix_var, d.dt, &self.quat);
        self.consistency.observe(res.nis, if d.vd_valid { 3.0 } else { 2.0 }, d.dt);
        if self.quat.learn_vel_noise {
            self.learn_vel_noise(&m, w, &res, d);
        }
        let status = if res.applied { AxisStatus::Accepted } else { AxisStatus::Gated };
        for i in 0..3 {
            self.last_update.axes[i] = AxisUpdate {
                z: d.accel_ned[i],
                innovation: m.y[i],
                variance: res.s_diag[i],
                status,
            };
        }
        if res.applied {
            self.gps_accel_accepted(t_us, d, w, &m, jerk, heading);
        } else {
            self.gps_accel_gated(heading.coarse);
        }
    }

    /// The measurement of the interval, widened for the latency's uncertainty (with the
    /// fix noise as states, `consider`, its untracked share is carried as a consider
    /// parameter instead); with the interval's jerk and the attitude variances it was
    /// formed with.
    fn gps_accel_measurement(
        &mut self,
        d: &GpsDelta,
        w: &WindowMean,
        vel_var: [f32; 2],
        consider: bool,
    ) -> (Measurement, Option<Jerk>, [f32; 3]) {
        let lag = self.latency.value();
        let p = self.ekf.covariance();
        let att_var = [p[0][0], p[1][1], p[2][2]];
        let gyro_psd = self.noise.gyro_psd;
        let mut m = measurement(d, w, self.ekf.dcm(), vel_var, &self.quat, gyro_psd, lag, att_var);
        let jerk = self.latency.jerk(w.f_ned, w.duration);
        let untracked = self.latency.untracked_var();
        if consider {
            let j = match jerk {
                Some(Jerk { j, .. }) if d.vd_valid => j,
                Some(Jerk { j, .. }) => [j[0], j[1], 0.0],
                None => [0.0; 3],
            };
            self.ekf.consider_latency(untracked, j);
            self.widen_for_latency(&mut m, jerk, 0.0);
        } else {
            self.widen_for_latency(&mut m, jerk, untracked);
        }
        (m, jerk, att_var)
    }

    /// A latency error δd leaves `δd·ȧ` in the GPS-acceleration residual, and in a
    /// steady turn `δd·ω` of heading error looks the same: R gets `(σ_d·ȧ)²` per axis,
    /// σ_d² the configured σ² plus `untracked` s², what the tracker has not yet learnt
    /// ([`super::latency::LatencyTracker::untracked_var`]; 0 where the update carries it
    /// as a consider parameter instead). The error is the same in every
    /// update of a manoeuvre, not white: above [`LATENCY_WHITE_HZ`] the share grows with
    /// the rate, so a second of 20 Hz updates learns no more from it than one of 10 Hz.
    fn widen_for_latency(&self, m: &mut Measurement, jerk: Option<Jerk>, untracked: f32) {
        if let Some(Jerk { j, inv }) = jerk {
            let s2 = (self.quat.latency_sigma * self.quat.latency_sigma + untracked)
                * crate::math::max(1.0, inv * (1.0 / LATENCY_WHITE_HZ));
            for i in 0..3 {
                m.r[i] += s2 * j[i] * j[i];
            }
        }
    }

    /// Whether the update fuses the heading. Where it does not see it, the heading is
    /// noise to the horizontal axes, not a state (else GPS noise across a spurious
    /// horizontal f̄ would be read as heading): its share moves from H into R.
    fn heading_use(&self, m: &mut Measurement, w: &WindowMean, att_var: [f32; 3]) -> HeadingUse {
        let coarse = self.heading_coarse();
        let sees = !coarse && sees_heading(m, w, att_var);
        let h_var = if coarse {
            0.5 * (m.r[0] + m.r[1]) + GRAVITY * GRAVITY * crate::math::max(att_var[0], att_var[1])
        } else {
            0.0
        };
        if !sees {
            let pyaw = att_var[2];
            for i in 0..3 {
                let hd = m.h[i][2];
                m.r[i] += hd * hd * pyaw;
                m.h[i][2] = 0.0;
            }
        }
        HeadingUse { coarse, sees, h_var }
    }

    /// After an accepted update: trust regained, the latency tracked, and the heading:
    /// seen (the accelerometer-bias heading share, the wind's memory), or solved
    /// directly while coarse ([`heading_accel`]).
    fn gps_accel_accepted(
        &mut self,
        t_us: u64,
        d: &GpsDelta,
        w: &WindowMean,
        m: &Measurement,
        jerk: Option<Jerk>,
        heading: HeadingUse,
    ) {
        self.gate_streak = 0;
        self.trust_streak = self.trust_streak.saturating_add(1);
        if self.trust_streak >= TRUST_AFTER {
            self.flags.set(Flags::UNRELIABLE, false);
        }
        let f_var = w.noise_sq[0] + w.noise_sq[1] + w.noise_sq[2];
        if let Some(step) = self.latency.observe(m.y, w.f_ned, f_var, w.duration, d.vd_valid, jerk) {
            self.window.set_delay(self.latency.value());
            // What the latency error made of the heading went partly into the biases, whose
            // P took it as white: they are that much less known.
            self.ekf.widen_biases(step * step * BIAS_PER_LATENCY_STEP);
        }
        if heading.sees {
            let fh2 = w.f_ned[0] * w.f_ned[0] + w.f_ned[1] * w.f_ned[1];
            let r = self.ekf.dcm();
            self.heading_bias.observe(w.f_ned, fh2, r, self.quat.accel_bias_sigma);
            // For the wind, only a manoeuvre (the direct solution's threshold, a 17°
            // bank) counts: turbulence passes the 3σ test too, and a wind fitted to a
            // heading it barely saw would hold it.
            if heading_accel::manoeuvre(fh2) {
                self.heading_seen_t = Some(t_us);
                let w = self.body_rates();
                let rate2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
                let p = self.ekf.covariance();
                self.heading_rate_var = unmodelled::heading_rate_variance(
                    self.quat.heading_rate_sigma,
                    self.unmodelled[0],
                    rate2,
                    p[3][3] + p[4][4] + p[5][5],
                );
            }
        } else if heading.coarse {
            self.control_heading_accel(t_us, d, w, heading.h_var);
        }
    }

    /// After a gated update: the attitude variance grows (the residual says the attitude
    /// is further off than P claims), doubt is flagged, and a persistent run resets.
    fn gps_accel_gated(&mut self, coarse: bool) {
        self.health.gate_rejections[0] = self.health.gate_rejections[0].wrapping_add(1);
        self.gate_streak = self.gate_streak.saturating_add(1);
        let p = self.ekf.covariance();
        // From the second in a row once settled (one gated update is an outlier as often
        // as not), from the first while settling after an alignment or a doubt.
        let settling = self.trust_streak < TRUST_AFTER;
        let due = self.gate_streak >= 2 || settling;
        if due && crate::math::max(p[0][0], p[1][1]) < MAX_INFLATED_VAR {
            self.ekf.inflate_attitude(GATE_INFLATION);
        }
        if self.gate_streak >= DOUBT_AFTER {
            self.flags.set(Flags::UNRELIABLE, true);
            self.trust_streak = 0;
        }
        if self.gate_streak >= self.quat.gate_max_consecutive {
            self.gate_streak = 0;
            self.reset_after_gates(coarse);
        }
    }

    /// `gate_max_consecutive` gated updates in a row. The heading first: on straight legs
    /// only the course vouches for it, through a wind fitted with that same heading, so
    /// both can be wrong together and confident (a crosswind read as no crab); the first
    /// loop then fails every update. Let both go: the direct solution finds the heading
    /// again from the manoeuvre, and the tilt is kept. Still failing with the heading out:
    /// diverged (or a long slip of the sensors), align again from the measurement.
    fn reset_after_gates(&mut self, coarse: bool) {
        if !coarse {
            self.let_heading_go();
            return;
        }
        self.health.gate_resets[0] = self.health.gate_resets[0].wrapping_add(1);
        self.tilt_aligned = false;
    }

    /// Teaches [`super::vel_noise`] this interval's residual (every interval: what the GPS
    /// acceleration must be weighed with includes what a manoeuvre adds to it, and the
    /// clamped log-mean keeps a short one from moving it far).
    fn learn_vel_noise(&mut self, m: &Measurement, w: &WindowMean, res: &Fused, d: &GpsDelta) {
        self.vel_noise.observe(m.y, w.f_ned, res.dtheta, d.dt, d.vd_valid);
    }
}
