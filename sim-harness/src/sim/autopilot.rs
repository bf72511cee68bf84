//! Successive-loop-closure autopilot (Beard & McLain ch. 6): roll (aileron),
//! course → roll, sideslip (rudder), pitch (elevator), altitude → pitch and
//! airspeed (throttle). Gains come from the book's design rules evaluated on the
//! airframe's coefficients at the trim airspeed, so both presets fly with no
//! hand tuning. It reads the true state: it flies the aircraft, it is not under test.

use super::aircraft::{Airframe, Controls, RHO};
use super::dynamics::G;
use super::rotation::wrap_pi;
use super::trim::Trim;

/// What the script asks for at one instant (already rate-limited by the script).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Targets {
    pub lateral: Lateral,
    pub longitudinal: Longitudinal,
    /// m/s
    pub airspeed: f64,
    /// Sideslip the rudder holds, rad (0 = coordinated).
    pub sideslip: f64,
    /// Sideslip loop on (rudder closes on β) or off (rudder open loop).
    pub coordinated: bool,
    /// Open-loop additions, rad (doublets, crossed controls).
    pub rudder_offset: f64,
    pub aileron_offset: f64,
    pub elevator_offset: f64,
    /// Bank limit used by the course loop, rad.
    pub bank_limit: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Lateral {
    /// Roll angle, rad.
    Bank(f64),
    /// Course over ground, rad.
    Course(f64),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Longitudinal {
    /// Altitude reference, m, and its rate (feed-forward), m/s.
    Altitude { h: f64, hdot: f64 },
    /// Pitch angle, rad.
    Pitch(f64),
}

/// The aircraft state the loops read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Feedback {
    pub roll: f64,
    pub pitch: f64,
    pub p: f64,
    pub q: f64,
    pub r: f64,
    pub course: f64,
    pub ground_speed: f64,
    pub altitude: f64,
    pub va: f64,
    pub beta: f64,
}

/// Loop gains (Beard & McLain §6.3 notation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gains {
    pub kp_phi: f64,
    pub kd_phi: f64,
    pub ki_phi: f64,
    pub kp_chi: f64,
    pub ki_chi: f64,
    pub kp_beta: f64,
    pub ki_beta: f64,
    pub kp_theta: f64,
    pub kd_theta: f64,
    pub kp_h: f64,
    pub ki_h: f64,
    pub kp_v: f64,
    pub ki_v: f64,
}

impl Gains {
    /// Design at the trim; `roll_error_max` (rad) sets the roll loop's stiffness
    /// (smaller = stiffer, for aggressive flight).
    pub fn design(af: &Airframe, trim: &Trim, roll_error_max: f64) -> Self {
        let va = trim.va;
        let gm = af.gammas();
        let c_p_p = gm[3] * af.C_ell_p + gm[4] * af.C_n_p;
        let c_p_da = gm[3] * af.C_ell_delta_a + gm[4] * af.C_n_delta_a;
        let qsb = 0.5 * RHO * va * va * af.S * af.b;
        let a_phi1 = -qsb * c_p_p * af.b / (2.0 * va);
        let a_phi2 = qsb * c_p_da;
        let zeta = 0.9;
        let kp_phi = (af.max_aileron * 0.6 / roll_error_max) * a_phi2.signum();
        let wn_phi = (a_phi2.abs() * kp_phi.abs()).sqrt();
        let kd_phi = (2.0 * zeta * wn_phi - a_phi1).max(0.0) / a_phi2;
        let ki_phi = 0.3 * kp_phi; // steady turns need it: the kd·p term biases the bank (p = −ψ̇ sin θ ≠ 0)
                                   // Course: bandwidth well below roll (W_χ = 8).
        let wn_chi = wn_phi / 8.0;
        let kp_chi = 2.0 * zeta * wn_chi * va / G;
        let ki_chi = wn_chi * wn_chi * va / G;
        // Pitch.
        let qsc = 0.5 * RHO * va * va * af.S * af.c / af.Jy;
        let a_th1 = -qsc * af.C_m_q * af.c / (2.0 * va);
        let a_th2 = -qsc * af.C_m_alpha;
        let a_th3 = qsc * af.C_m_delta_e;
        let kp_theta = (af.max_elevator * 0.5 / 10f64.to_radians()) * a_th3.signum();
        let wn_th = (a_th2 + kp_theta.abs() * a_th3.abs()).sqrt();
        let kd_theta = (2.0 * 0.7 * wn_th - a_th1).max(0.0) / a_th3;
        let k_dc = kp_theta * a_th3 / (a_th2 + kp_theta * a_th3);
        // Altitude: W_h = 20 below pitch.
        let wn_h = wn_th / 20.0;
        let kp_h = 2.0 * 0.9 * wn_h / (k_dc * va);
        let ki_h = wn_h * wn_h / (k_dc * va);
        // Airspeed with throttle.
        let a_v1 = RHO * va * af.S / af.mass * af.c_d(trim.alpha)
            + RHO * af.S_prop * af.C_prop * va / af.mass;
        let a_v2 = RHO * af.S_prop * af.C_prop * af.k_motor * af.k_motor * trim.controls.throttle
            / af.mass;
        let wn_v = 0.8;
        let kp_v = ((2.0 * 0.9 * wn_v - a_v1) / a_v2).max(0.02);
        let ki_v = wn_v * wn_v / a_v2;
        // Sideslip: the rudder acts through the yaw moment (β̇ ≈ −r), so δr = sign(C_nδr)·k·β.
        let s = af.C_n_delta_r.signum();
        Gains {
            kp_phi,
            kd_phi,
            ki_phi,
            kp_chi,
            ki_chi,
            kp_beta: 2.0 * s,
            ki_beta: 2.0 * s,
            kp_theta,
            kd_theta,
            kp_h,
            ki_h,
            kp_v,
            ki_v,
        }
    }
}

/// Autopilot with its integrators and servo states.
#[derive(Debug, Clone)]
pub struct Autopilot {
    pub gains: Gains,
    trim: Trim,
    af: Airframe,
    i_phi: f64,
    i_chi: f64,
    i_beta: f64,
    i_h: f64,
    i_v: f64,
    /// Servo outputs (first-order lag).
    pub out: Controls,
}

impl Autopilot {
    pub fn new(af: &Airframe, trim: &Trim, roll_error_max: f64) -> Self {
        Autopilot {
            gains: Gains::design(af, trim, roll_error_max),
            trim: *trim,
            af: af.clone(),
            i_phi: 0.0,
            i_chi: 0.0,
            i_beta: 0.0,
            i_h: 0.0,
            i_v: 0.0,
            out: trim.controls,
        }
    }

    /// Runs the loops for `dt` seconds and returns the servo positions.
    pub fn step(&mut self, t: &Targets, fb: &Feedback, dt: f64) -> Controls {
        let g = self.gains;
        let af = &self.af;
        // Lateral.
        let phi_c = match t.lateral {
            Lateral::Bank(phi) => {
                self.i_chi = 0.0;
                phi
            }
            Lateral::Course(chi) => {
                let e = wrap_pi(chi - fb.course);
                let raw = g.kp_chi * e + g.ki_chi * self.i_chi;
                if raw.abs() < t.bank_limit {
                    self.i_chi += e * dt;
                }
                raw.clamp(-t.bank_limit, t.bank_limit)
            }
        };
        let e_phi = phi_c - fb.roll;
        let da_raw = g.kp_phi * e_phi - g.kd_phi * fb.p + g.ki_phi * self.i_phi + t.aileron_offset;
        if da_raw.abs() < af.max_aileron {
            self.i_phi += e_phi * dt;
        }
        let da = da_raw.clamp(-af.max_aileron, af.max_aileron);
        let dr = if af.has_rudder() {
            let mut r = t.rudder_offset;
            if t.coordinated {
                let e_b = fb.beta - t.sideslip;
                let raw = g.kp_beta * e_b + g.ki_beta * self.i_beta;
                if raw.abs() < af.max_rudder {
                    self.i_beta += e_b * dt;
                }
                r += raw;
            }
            r.clamp(-af.max_rudder, af.max_rudder)
        } else {
            0.0
        };
        // Longitudinal.
        let theta_c = match t.longitudinal {
            Longitudinal::Pitch(th) => {
                self.i_h = 0.0;
                th
            }
            Longitudinal::Altitude { h, hdot } => {
                let e = h - fb.altitude;
                let ff = self.trim.alpha + (hdot / fb.va.max(1.0)).clamp(-0.5, 0.5);
                let raw = ff + g.kp_h * e + g.ki_h * self.i_h;
                let lim = 30f64.to_radians();
                if raw.abs() < lim {
                    self.i_h += e * dt;
                }
                raw.clamp(-lim, lim)
            }
        };
        let de = (self.trim.controls.elevator + g.kp_theta * (theta_c - fb.pitch)
            - g.kd_theta * fb.q
            + t.elevator_offset)
            .clamp(-af.max_elevator, af.max_elevator);
        let e_v = t.airspeed - fb.va;
        let th_raw = self.trim.controls.throttle + g.kp_v * e_v + g.ki_v * self.i_v;
        if (0.0..=1.0).contains(&th_raw) {
            self.i_v += e_v * dt;
        }
        let th = th_raw.clamp(0.0, 1.0);
        // Servos: first-order lag, exact for the step.
        let k = 1.0 - (-dt / af.servo_tau).exp();
        self.out.elevator += k * (de - self.out.elevator);
        self.out.aileron += k * (da - self.out.aileron);
        self.out.rudder += k * (dr - self.out.rudder);
        self.out.throttle += k * (th - self.out.throttle);
        self.out
    }
}
