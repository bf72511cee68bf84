//! One fix interval of the Euler filter: the measurement `z = [φm, θm, ψm]` from the
//! aid sources ([`super::gps_accel`] or [`super::airspeed`], and [`super::course`]),
//! its noise, and the three scalar updates with their gates and recovery.

use super::EulerAhrs;
use crate::config::{AccelAlignment, MeasNoise, Model};
use crate::ekf::fix_noise::Coupling;
use crate::health::{AxisStatus, AxisUpdate, Flags, UpdateRecord};
use crate::math::{wrap_pi, Vec3};
use crate::measure::gps_delta::GpsDelta;
use crate::measure::heading::RollPitchTrig;
use crate::measure::interval::IntervalMean;
use crate::measure::{noise, RollPitch};

/// What one fix interval refers to.
#[derive(Debug, Clone, Copy)]
pub(super) struct IntervalRefs {
    /// The attitude the measurement refers to, rad.
    pub att: Vec3,
    /// The accelerometer paired with it, m/s² (body FRD).
    pub accel: Vec3,
    /// The velocity whose course is the yaw measurement, m/s NED.
    pub vel: Vec3,
    /// Whether `vel` is the mean of the two fixes (else the newest one).
    pub mean_vel: bool,
}

/// The measurement noise of one fix interval.
#[derive(Debug, Clone, Copy)]
pub(super) struct IntervalNoise {
    /// Variance of roll, pitch, yaw, rad² (with `coupling`: the white part only).
    pub var: [f32; 3],
    /// From the sensors: the two fixes' velocity variances (m/s)² and the floor (rad).
    pub sensors: Option<(f32, f32, [f32; 3])>,
    /// The fix noise is carried as states (EKF1, enabled, both fixes reporting).
    pub correlated: bool,
    /// Each axis' dependence on the fix-noise states.
    pub coupling: [Option<Coupling>; 3],
}

impl EulerAhrs {
    /// Forms z and runs the three scalar updates. Not inlined: it runs once per fix, and
    /// kept out of the per-sample path it leaves that path compact (fewer saved registers
    /// and stack per IMU sample).
    #[inline(never)]
    pub(super) fn update(
        &mut self,
        t_us: u64,
        d: &GpsDelta,
        means: Option<IntervalMean>,
        fix_vel: Vec3,
    ) {
        // P is propagated mid-way between fixes, not here (see `PendingCovariance::stagger`):
        // the update uses P as of the last propagation, at most N − 1 samples old.
        self.pending.stagger(self.decimation());
        self.settling = self.settling.saturating_sub(1);
        // P must be positive definite for the gains to mean anything (repaired if not);
        // its factor bounds the fix-noise cross-covariance below.
        let chol = self.ekf.ensure_positive_definite();
        if (self.ekf.flips() ^ self.seen_flips) & 1 != 0 {
            self.fix_noise.flip_pitch();
        }
        self.seen_flips = self.ekf.flips();
        let x = self.ekf.x;
        let refs = self.interval_refs(d, means);
        let slipping = self.slipping(means);
        // sin/cos of the referenced roll and pitch, once for every model below (near the
        // state's: from the predict's carried sin/cos).
        let trig =
            RollPitchTrig::from_sin_cos(self.ekf.roll_pitch_sin_cos(refs.att[0], refs.att[1]));
        let yaw = self.control_course(d, &refs, &trig, slipping);
        let mut noise = self.interval_noise(d, &refs);
        // The roll/pitch the measurement refers to (EKF2 windowed: the window's mean).
        let mut rp_att = [refs.att[0], refs.att[1]];
        let rp: RollPitch = match self.euler.model {
            Model::Ekf1(e1) => {
                self.gps_accel_roll_pitch(&e1, d, means, &refs, &trig, &yaw, &mut noise, &chol)
            }
            Model::Ekf2(e2) if e2.window > 0.0 => {
                let (rp, mean_att, spread_var) =
                    self.airspeed_roll_pitch_windowed(&e2, t_us, fix_vel);
                rp_att = mean_att;
                noise.var[0] += spread_var[0];
                noise.var[1] += spread_var[1];
                rp
            }
            Model::Ekf2(e2) => self.airspeed_roll_pitch(&e2, t_us, d, (refs.att[0], refs.att[1])),
        };
        self.health.solver_clamped = self.health.solver_clamped.wrapping_add(rp.clamped as u32);
        if rp.degenerate {
            self.health.solver_degenerate = self.health.solver_degenerate.wrapping_add(1);
        }
        let z = [rp.roll, rp.pitch, yaw.measurement()];
        let att = [rp_att[0], rp_att[1], refs.att[2]];
        // Written in place (no 72-byte record copy at the end).
        self.last_update = UpdateRecord {
            t_us,
            seq: self.last_update.seq.wrapping_add(1),
            axes: [AxisUpdate::default(); 3],
            course: AxisUpdate::default(),
            alpha_sin_cos: yaw.alpha_sin_cos,
        };
        self.apply_axes(z, att, x, &noise);
        self.after_update(x);
    }

    /// The attitude and accelerometer the measurement refers to, and the velocity whose
    /// course is the yaw measurement (the mean of the two fixes, or the newest one).
    fn interval_refs(&self, d: &GpsDelta, means: Option<IntervalMean>) -> IntervalRefs {
        let now = ([self.ekf.x[0], self.ekf.x[1], self.ekf.x[2]], self.accel);
        let alignment = match self.euler.model {
            Model::Ekf1(e1) => Some(e1.accel_alignment),
            Model::Ekf2(_) => None,
        };
        let (att, accel, vel, mean_vel) = match (alignment, means) {
            (Some(AccelAlignment::IntervalMean), Some(m)) => (m.att, m.accel, d.mean_vel, true),
            (Some(AccelAlignment::Latest), Some(m)) => (m.latest_att, m.latest_accel, d.vel, false),
            _ => (now.0, now.1, d.vel, false),
        };
        IntervalRefs { att, accel, vel, mean_vel }
    }

    /// Measurement variances: fixed (thesis), or from the inputs' noise plus a floor.
    /// EKF2's roll/pitch R is its own (`Ekf2Config::rp_sigma`) whatever the noise model;
    /// EKF1's is `sigma` when fixed, and set by its aid source from the sensors otherwise.
    ///
    /// EKF1 with R from the sensors carries the fix shared with the previous difference
    /// (and the heading shared with the yaw measurement) as states when both fixes report
    /// their speed accuracy. The states carry a posterior mean of the fix noise into the
    /// next measurement, so a wrong σ injects error where the white model only loses
    /// gain: with a guessed σ (NMEA) the white model stays (the PX4 logs, no sAcc, with
    /// arrival-time jitter: their differenced acceleration has lag-1 correlation
    /// +0.3…+0.7, not −½).
    fn interval_noise(&self, d: &GpsDelta, refs: &IntervalRefs) -> IntervalNoise {
        let sq = |x: f32| x * x;
        let ekf2_rp = match self.euler.model {
            Model::Ekf1(_) => None,
            Model::Ekf2(e2) => Some(e2.rp_sigma),
        };
        let (var, sensors, correlated_fix_noise) = match self.euler.meas_noise {
            MeasNoise::FromSensors { vel_sigma, floor, correlated_fix_noise } => {
                let [v0, v1] = d.speed_acc.map(|a| sq(a.unwrap_or(vel_sigma)));
                // The interval-mean velocity is half of each fix.
                let vel_var = if refs.mean_vel { 0.25 * (v0 + v1) } else { v1 };
                let rp = ekf2_rp.unwrap_or([0.0; 2]);
                let yaw = sq(floor[2]) + noise::course_variance(vel_var, refs.vel);
                ([sq(rp[0]), sq(rp[1]), yaw], Some((v0, v1, floor)), correlated_fix_noise)
            }
            MeasNoise::Fixed { sigma } => {
                let rp = ekf2_rp.unwrap_or([sigma[0], sigma[1]]);
                ([sq(rp[0]), sq(rp[1]), sq(sigma[2])], None, false)
            }
        };
        let reported = d.speed_acc[0].is_some() && d.speed_acc[1].is_some();
        let correlated =
            matches!(self.euler.model, Model::Ekf1(_)) && correlated_fix_noise && reported;
        IntervalNoise { var, sensors, correlated, coupling: [None; 3] }
    }

    /// The three scalar updates of `z` measured at attitude `att`, the state before them
    /// `x`. Yaw first when its error is a shared state: the yaw innovation then tells the
    /// heading error (to within the yaw estimate's σ) before roll and pitch use it — the
    /// same posterior in any order, but the roll/pitch gates and NIS see e's posterior,
    /// not the yaw R's sideslip allowance (2°, set for slipping flight).
    fn apply_axes(&mut self, z: [Option<f32>; 3], att: Vec3, x: [f32; 6], noise: &IntervalNoise) {
        let correlated = noise.correlated;
        let order: [usize; 3] = if correlated { [2, 0, 1] } else { [0, 1, 2] };
        for i in order {
            let c = noise.coupling[i];
            let Some(zi) = z[i] else {
                // Not measured: the new fix's noise on this axis stays its prior.
                if let (Some(c), true) = (c, i < 2) {
                    self.fix_noise.forget(i, c.fresh_var);
                }
                continue;
            };
            // Refer the measurement to the current time: the innovation is taken
            // against the attitude it was measured at (`att`), applied to the state now.
            let shift = if i == 1 { x[i] - att[i] } else { wrap_pi(x[i] - att[i]) };
            let a = self.update_axis(i, zi, shift, noise.var[i], c, correlated);
            self.last_update.axes[i] = a;
        }
    }

    /// After the updates: angles wrapped, the state checked (a re-seed re-aligns), the
    /// EKF2 window moved with the state (`x` the state before the updates).
    fn after_update(&mut self, x: [f32; 6]) {
        self.ekf.normalize_angles();
        self.ekf.check_state(self.caps, self.bias_limit);
        self.health.covariance_repairs = self.ekf.repairs();
        if self.ekf.resets() != self.seen_resets {
            self.after_reset();
        }
        self.health.updates = self.health.updates.wrapping_add(1);
        if self.ekf2_windowed() {
            self.air_window.shift_att(wrap_pi(self.ekf.x[0] - x[0]), self.ekf.x[1] - x[1]);
        }
        let all = self.aligned.iter().all(|a| *a);
        self.flags.set(Flags::ALIGNED, all);
    }

    /// Initialises, gates and applies one axis with measurement variance `r` (rad²).
    /// `shift` = x_now − x_at_measurement. `correlated`: the update runs on the filter
    /// augmented by the fix-noise states (`ekf::fix_noise`), `coupling` says how this
    /// axis depends on them (`r` is then the white part only).
    fn update_axis(
        &mut self,
        i: usize,
        z: f32,
        shift: f32,
        r: f32,
        coupling: Option<Coupling>,
        correlated: bool,
    ) -> AxisUpdate {
        let z_now = if i == 1 { z + shift } else { wrap_pi(z + shift) };
        if !self.aligned[i] {
            return self.initialise_axis(i, z, z_now, r, coupling, correlated);
        }
        let gate = self.euler.gate_chi2[i];
        let res = if correlated {
            let c = coupling.unwrap_or_default();
            self.fix_noise.update_axis(&mut self.ekf, i, z_now, r, c, gate)
        } else {
            self.ekf.update_axis(i, z_now, r, gate)
        };
        if res.applied {
            self.gate_streak[i] = 0;
            return AxisUpdate {
                z,
                innovation: res.innovation,
                variance: res.variance,
                status: AxisStatus::Accepted,
            };
        }
        self.gate_streak[i] = self.gate_streak[i].saturating_add(1);
        if self.gate_streak[i] >= self.euler.gate_max_consecutive && res.innovation.is_finite() {
            self.force_axis(i, z_now, r, res.innovation, coupling, correlated);
            return AxisUpdate {
                z,
                innovation: res.innovation,
                variance: res.variance,
                status: AxisStatus::ForcedAfterGate,
            };
        }
        self.health.gate_rejections[i] = self.health.gate_rejections[i].wrapping_add(1);
        AxisUpdate { z, innovation: res.innovation, variance: res.variance, status: AxisStatus::Gated }
    }

    /// An axis not yet aligned is set to the measurement, with its variance.
    fn initialise_axis(
        &mut self,
        i: usize,
        z: f32,
        z_now: f32,
        r: f32,
        coupling: Option<Coupling>,
        correlated: bool,
    ) -> AxisUpdate {
        let nu = wrap_pi(z_now - self.ekf.x[i]);
        let r_init = coupling.map_or(r, |c| c.white_var);
        self.ekf.reset_axis(i, z_now, r_init);
        if correlated {
            self.fix_noise.decorrelate(i);
            if let (Some(c), true) = (coupling, i < 2) {
                self.fix_noise.forget(i, c.fresh_var);
            }
        }
        self.aligned[i] = true;
        self.restart_settling();
        AxisUpdate { z, innovation: nu, variance: r_init, status: AxisStatus::Initialised }
    }

    /// Recovery after `gate_max_consecutive` gated updates: the estimate has left the
    /// measurement for too long; trust it again (the variance widened by the innovation²,
    /// the update forced).
    fn force_axis(
        &mut self,
        i: usize,
        z_now: f32,
        r: f32,
        innovation: f32,
        coupling: Option<Coupling>,
        correlated: bool,
    ) {
        self.ekf.inflate_axis(i, innovation * innovation);
        // The fix noise of this axis was reset by the gated update: the forced one takes
        // the difference as white (its full variance).
        let r_forced = coupling.map_or(r, |c| c.white_var);
        if correlated {
            self.fix_noise.decorrelate(i);
            let c = Coupling::default();
            self.fix_noise.update_axis(&mut self.ekf, i, z_now, r_forced, c, f32::INFINITY);
        } else {
            self.ekf.update_axis(i, z_now, r_forced, f32::INFINITY);
        }
        self.health.gate_resets[i] = self.health.gate_resets[i].wrapping_add(1);
        self.restart_settling();
        self.gate_streak[i] = 0;
    }
}
