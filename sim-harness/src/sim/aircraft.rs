//! Airframe parameters and the aerodynamic / propulsion force model.
//!
//! Source: R. W. Beard and T. W. McLain, *Small Unmanned Aircraft: Theory and
//! Practice*, Princeton University Press, 2012 — ch. 4 (forces and moments,
//! eqs 4.6–4.19: nonlinear lift with the σ(α) stall blend, parabolic drag, the
//! simple propeller model) and appendix E (Aerosonde and Zagi parameters). The
//! thesis flew the Aerosonde of the AeroSim library. For the `aggressive`
//! scenario (the thesis' 1.4 m Easystar at 12–18 m/s) see [`Airframe::easystar_scaled`].
//!
//! Forces are in body FRD axes, N; moments in N·m; control deflections in rad,
//! throttle in [0, 1].

use serde::{Deserialize, Serialize};

/// Air density used by both presets, kg/m³ (Beard & McLain app. E).
pub const RHO: f64 = 1.2682;

/// Physical and aerodynamic parameters of one airframe (Beard & McLain notation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct Airframe {
    pub name: String,
    /// kg
    pub mass: f64,
    /// kg·m²
    pub Jx: f64,
    pub Jy: f64,
    pub Jz: f64,
    pub Jxz: f64,
    /// wing area m², span m, mean chord m
    pub S: f64,
    pub b: f64,
    pub c: f64,
    /// propeller disc area m², motor constant (m/s per unit throttle)
    pub S_prop: f64,
    pub k_motor: f64,
    pub C_prop: f64,
    /// Oswald efficiency
    pub e: f64,
    /// stall blend sharpness and angle, rad
    pub M: f64,
    pub alpha0: f64,
    pub C_L_0: f64,
    pub C_L_alpha: f64,
    pub C_L_q: f64,
    pub C_L_delta_e: f64,
    pub C_D_p: f64,
    pub C_D_q: f64,
    pub C_D_delta_e: f64,
    pub C_m_0: f64,
    pub C_m_alpha: f64,
    pub C_m_q: f64,
    pub C_m_delta_e: f64,
    pub C_Y_0: f64,
    pub C_Y_beta: f64,
    pub C_Y_p: f64,
    pub C_Y_r: f64,
    pub C_Y_delta_a: f64,
    pub C_Y_delta_r: f64,
    pub C_ell_0: f64,
    pub C_ell_beta: f64,
    pub C_ell_p: f64,
    pub C_ell_r: f64,
    pub C_ell_delta_a: f64,
    pub C_ell_delta_r: f64,
    pub C_n_0: f64,
    pub C_n_beta: f64,
    pub C_n_p: f64,
    pub C_n_r: f64,
    pub C_n_delta_a: f64,
    pub C_n_delta_r: f64,
    /// Deflection limits, rad (not in the book's tables: typical ±30° / ±45°).
    pub max_elevator: f64,
    pub max_aileron: f64,
    pub max_rudder: f64,
    /// Control-surface servo time constant, s.
    pub servo_tau: f64,
}

impl Airframe {
    /// The Aerosonde UAV (Beard & McLain app. E.2; the thesis' simulated airframe).
    pub fn aerosonde() -> Self {
        Airframe {
            name: "aerosonde".into(),
            mass: 13.5,
            Jx: 0.8244,
            Jy: 1.135,
            Jz: 1.759,
            Jxz: 0.1204,
            S: 0.55,
            b: 2.8956,
            c: 0.18994,
            S_prop: 0.2027,
            k_motor: 80.0,
            C_prop: 1.0,
            e: 0.9,
            M: 50.0,
            alpha0: 0.4712,
            C_L_0: 0.28,
            C_L_alpha: 3.45,
            C_L_q: 0.0,
            C_L_delta_e: -0.36,
            C_D_p: 0.0437,
            C_D_q: 0.0,
            C_D_delta_e: 0.0,
            C_m_0: -0.02338,
            C_m_alpha: -0.38,
            C_m_q: -3.6,
            C_m_delta_e: -0.5,
            C_Y_0: 0.0,
            C_Y_beta: -0.98,
            C_Y_p: 0.0,
            C_Y_r: 0.0,
            C_Y_delta_a: 0.0,
            C_Y_delta_r: -0.17,
            C_ell_0: 0.0,
            C_ell_beta: -0.12,
            C_ell_p: -0.26,
            C_ell_r: 0.14,
            C_ell_delta_a: 0.08,
            C_ell_delta_r: 0.105,
            C_n_0: 0.0,
            C_n_beta: 0.25,
            C_n_p: 0.022,
            C_n_r: -0.35,
            C_n_delta_a: 0.06,
            C_n_delta_r: -0.032,
            max_elevator: 30f64.to_radians(),
            max_aileron: 30f64.to_radians(),
            max_rudder: 30f64.to_radians(),
            servo_tau: 0.03,
        }
    }

    /// The Zagi flying wing (Beard & McLain app. E.1): elevons, no rudder.
    pub fn zagi() -> Self {
        Airframe {
            name: "zagi".into(),
            mass: 1.56,
            Jx: 0.1147,
            Jy: 0.0576,
            Jz: 0.1712,
            Jxz: 0.0015,
            S: 0.2589,
            b: 1.4224,
            c: 0.3302,
            S_prop: 0.0314,
            k_motor: 20.0,
            C_prop: 1.0,
            e: 0.9,
            M: 50.0,
            alpha0: 0.4712,
            C_L_0: 0.09167,
            C_L_alpha: 3.5016,
            C_L_q: 2.8932,
            C_L_delta_e: 0.2724,
            C_D_p: 0.0254,
            C_D_q: 0.0,
            C_D_delta_e: 0.3045,
            C_m_0: -0.02338,
            C_m_alpha: -0.5675,
            C_m_q: -1.399,
            C_m_delta_e: -0.3254,
            C_Y_0: 0.0,
            C_Y_beta: -0.07359,
            C_Y_p: 0.0,
            C_Y_r: 0.0,
            C_Y_delta_a: 0.0,
            C_Y_delta_r: 0.0,
            C_ell_0: 0.0,
            C_ell_beta: -0.02854,
            C_ell_p: -0.3209,
            C_ell_r: 0.03066,
            C_ell_delta_a: 0.1682,
            C_ell_delta_r: 0.0,
            C_n_0: 0.0,
            C_n_beta: -0.0004,
            C_n_p: -0.01297,
            C_n_r: -0.00434,
            C_n_delta_a: -0.00328,
            C_n_delta_r: 0.0,
            max_elevator: 30f64.to_radians(),
            max_aileron: 30f64.to_radians(),
            max_rudder: 0.0,
            servo_tau: 0.02,
        }
    }

    /// An Easystar-sized airframe (1.37 m span, 0.25 m², 0.9 kg flying weight)
    /// with the Aerosonde's non-dimensional coefficients and inertias scaled by
    /// m·b² — NOT a published Easystar model. The book's small Zagi is directionally
    /// unstable without a rudder (C_nβ < 0) and tumbles in sustained 50° reversals,
    /// so the `aggressive` scenario flies this instead.
    pub fn easystar_scaled() -> Self {
        let a = Self::aerosonde();
        let (mass, b) = (0.9, 1.37);
        let k = (mass / a.mass) * (b / a.b).powi(2);
        Airframe {
            name: "easystar_scaled".into(),
            mass,
            Jx: a.Jx * k,
            Jy: a.Jy * k,
            Jz: a.Jz * k,
            Jxz: a.Jxz * k,
            S: 0.25,
            b,
            c: 0.19,
            S_prop: 0.02,
            k_motor: 25.0,
            servo_tau: 0.02,
            ..a
        }
    }

    /// A preset by name: `aerosonde`, `easystar_scaled` or `zagi`.
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "aerosonde" => Some(Self::aerosonde()),
            "easystar_scaled" => Some(Self::easystar_scaled()),
            "zagi" => Some(Self::zagi()),
            _ => None,
        }
    }

    pub fn has_rudder(&self) -> bool {
        self.max_rudder > 0.0 && self.C_n_delta_r != 0.0
    }

    /// Aspect ratio b²/S.
    pub fn aspect_ratio(&self) -> f64 {
        self.b * self.b / self.S
    }

    /// Inertia products Γ1..Γ8 of Beard & McLain eq 3.13 (index 0 = Γ).
    pub fn gammas(&self) -> [f64; 9] {
        let g = self.Jx * self.Jz - self.Jxz * self.Jxz;
        [
            g,
            self.Jxz * (self.Jx - self.Jy + self.Jz) / g,
            (self.Jz * (self.Jz - self.Jy) + self.Jxz * self.Jxz) / g,
            self.Jz / g,
            self.Jxz / g,
            (self.Jz - self.Jx) / self.Jy,
            self.Jxz / self.Jy,
            ((self.Jx - self.Jy) * self.Jx + self.Jxz * self.Jxz) / g,
            self.Jx / g,
        ]
    }

    /// Lift coefficient with the σ(α) blend to a flat plate past stall (eq 4.9).
    pub fn c_l(&self, alpha: f64) -> f64 {
        let a = (-self.M * (alpha - self.alpha0)).exp();
        let b = (self.M * (alpha + self.alpha0)).exp();
        let sigma = (1.0 + a + b) / ((1.0 + a) * (1.0 + b));
        (1.0 - sigma) * (self.C_L_0 + self.C_L_alpha * alpha)
            + sigma * 2.0 * alpha.signum() * alpha.sin().powi(2) * alpha.cos()
    }

    /// Drag coefficient: parasitic plus induced (eq 4.11).
    pub fn c_d(&self, alpha: f64) -> f64 {
        let cl = self.C_L_0 + self.C_L_alpha * alpha;
        self.C_D_p + cl * cl / (std::f64::consts::PI * self.e * self.aspect_ratio())
    }
}

/// Control inputs.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Controls {
    /// rad
    pub elevator: f64,
    pub aileron: f64,
    pub rudder: f64,
    /// [0, 1]
    pub throttle: f64,
}

/// Air-relative flow angles and speed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AirData {
    /// true airspeed, m/s
    pub va: f64,
    /// angle of attack, rad
    pub alpha: f64,
    /// sideslip, rad
    pub beta: f64,
}

impl AirData {
    /// From the air-relative velocity in body axes, m/s.
    pub fn from_body(v_air: [f64; 3]) -> Self {
        let va = (v_air[0] * v_air[0] + v_air[1] * v_air[1] + v_air[2] * v_air[2]).sqrt();
        if va < 1e-6 {
            return AirData::default();
        }
        AirData {
            va,
            alpha: v_air[2].atan2(v_air[0]),
            beta: (v_air[1] / va).clamp(-1.0, 1.0).asin(),
        }
    }
}

/// Aerodynamic + propulsive force (body, N, gravity excluded) and moment (body, N·m)
/// for body rates `w` (rad/s).
pub fn forces_moments(
    af: &Airframe,
    air: &AirData,
    w: [f64; 3],
    u: &Controls,
) -> ([f64; 3], [f64; 3]) {
    let [p, q, r] = w;
    let va = air.va.max(1e-3);
    let qbar_s = 0.5 * RHO * va * va * af.S;
    let (sa, ca) = air.alpha.sin_cos();
    let lift = qbar_s
        * (af.c_l(air.alpha) + af.C_L_q * af.c / (2.0 * va) * q + af.C_L_delta_e * u.elevator);
    let drag = qbar_s
        * (af.c_d(air.alpha) + af.C_D_q * af.c / (2.0 * va) * q + af.C_D_delta_e * u.elevator);
    let bb = af.b / (2.0 * va);
    let fy = qbar_s
        * (af.C_Y_0
            + af.C_Y_beta * air.beta
            + af.C_Y_p * bb * p
            + af.C_Y_r * bb * r
            + af.C_Y_delta_a * u.aileron
            + af.C_Y_delta_r * u.rudder);
    let thrust = 0.5 * RHO * af.S_prop * af.C_prop * ((af.k_motor * u.throttle).powi(2) - va * va);
    let fx = -ca * drag + sa * lift + thrust;
    let fz = -sa * drag - ca * lift;
    let l = qbar_s
        * af.b
        * (af.C_ell_0
            + af.C_ell_beta * air.beta
            + af.C_ell_p * bb * p
            + af.C_ell_r * bb * r
            + af.C_ell_delta_a * u.aileron
            + af.C_ell_delta_r * u.rudder);
    let m = qbar_s
        * af.c
        * (af.C_m_0
            + af.C_m_alpha * air.alpha
            + af.C_m_q * af.c / (2.0 * va) * q
            + af.C_m_delta_e * u.elevator);
    let n = qbar_s
        * af.b
        * (af.C_n_0
            + af.C_n_beta * air.beta
            + af.C_n_p * bb * p
            + af.C_n_r * bb * r
            + af.C_n_delta_a * u.aileron
            + af.C_n_delta_r * u.rudder);
    ([fx, fy, fz], [l, m, n])
}
