//! Nonlinear 6-DoF rigid-body equations of motion (Beard & McLain eqs 3.14–3.17
//! with the attitude as a quaternion, so aggressive attitudes never hit the
//! Euler singularity), flat non-rotating Earth, constant gravity, classic RK4.

use super::aircraft::{forces_moments, AirData, Airframe, Controls};
use super::rotation::{self as rot, V3};

/// Standard gravity, m/s² (docs/design.md, conventions).
pub const G: f64 = 9.80665;

/// Rigid-body state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Position NED, m (down is negative altitude).
    pub pos: V3,
    /// Inertial (ground-relative) velocity in body axes, m/s.
    pub vel_b: V3,
    /// Attitude quaternion, body → NED, scalar first.
    pub quat: [f64; 4],
    /// Body rates p, q, r, rad/s.
    pub omega: V3,
}

/// What the air around the aircraft does during one step: steady wind in NED and
/// the gust (turbulence) in body axes, both m/s (Beard & McLain §4.4 split).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WindInput {
    pub steady_ned: V3,
    pub gust_body: V3,
}

/// Everything derived from a state at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Derived {
    pub air: AirData,
    /// Non-gravitational force / mass in body axes: the specific force an ideal
    /// accelerometer at the CG reads, m/s².
    pub specific_force: V3,
    pub moment: V3,
    /// Inertial velocity NED, m/s.
    pub vel_ned: V3,
    /// Wind NED (steady + gust), m/s.
    pub wind_ned: V3,
}

impl State {
    /// Level state with the given attitude, body velocity and position.
    pub fn new(pos: V3, vel_b: V3, euler: V3) -> Self {
        State {
            pos,
            vel_b,
            quat: rot::quat_from_euler(euler[0], euler[1], euler[2]),
            omega: [0.0; 3],
        }
    }

    pub fn euler(&self) -> V3 {
        rot::euler_from_quat(self.quat)
    }

    pub fn vel_ned(&self) -> V3 {
        rot::mul_mv(&rot::r_nb_quat(self.quat), self.vel_b)
    }

    /// Air data, specific force and moments at this state.
    pub fn derive(&self, af: &Airframe, u: &Controls, wind: &WindInput) -> Derived {
        let r_nb = rot::r_nb_quat(self.quat);
        let wind_b = rot::add(rot::mul_mtv(&r_nb, wind.steady_ned), wind.gust_body);
        let air = AirData::from_body(rot::sub(self.vel_b, wind_b));
        let (f, m) = forces_moments(af, &air, self.omega, u);
        Derived {
            air,
            specific_force: rot::scale(f, 1.0 / af.mass),
            moment: m,
            vel_ned: rot::mul_mv(&r_nb, self.vel_b),
            wind_ned: rot::mul_mv(&r_nb, wind_b),
        }
    }
}

type X = [f64; 13];

fn pack(s: &State) -> X {
    let mut x = [0.0; 13];
    x[0..3].copy_from_slice(&s.pos);
    x[3..6].copy_from_slice(&s.vel_b);
    x[6..10].copy_from_slice(&s.quat);
    x[10..13].copy_from_slice(&s.omega);
    x
}

fn unpack(x: &X) -> State {
    State {
        pos: [x[0], x[1], x[2]],
        vel_b: [x[3], x[4], x[5]],
        quat: [x[6], x[7], x[8], x[9]],
        omega: [x[10], x[11], x[12]],
    }
}

fn deriv(af: &Airframe, gam: &[f64; 9], x: &X, u: &Controls, wind: &WindInput) -> X {
    let s = unpack(x);
    let d = s.derive(af, u, wind);
    let r_nb = rot::r_nb_quat(s.quat);
    // Gravity in body axes, added to the specific force.
    let g_b = rot::mul_mtv(&r_nb, [0.0, 0.0, G]);
    let a = rot::add(d.specific_force, g_b);
    let [p, q, r] = s.omega;
    // v̇_B = F/m − ω × v_B
    let vdot = rot::sub(a, rot::cross(s.omega, s.vel_b));
    let edot = rot::quat_rate(s.quat, s.omega);
    let [l, m, n] = d.moment;
    let pdot = gam[1] * p * q - gam[2] * q * r + gam[3] * l + gam[4] * n;
    let qdot = gam[5] * p * r - gam[6] * (p * p - r * r) + m / af.Jy;
    let rdot = gam[7] * p * q - gam[1] * q * r + gam[4] * l + gam[8] * n;
    let mut dx = [0.0; 13];
    dx[0..3].copy_from_slice(&d.vel_ned);
    dx[3..6].copy_from_slice(&vdot);
    dx[6..10].copy_from_slice(&edot);
    dx[10..13].copy_from_slice(&[pdot, qdot, rdot]);
    dx
}

fn lerp_controls(a: &Controls, b: &Controls, f: f64) -> Controls {
    let l = |x: f64, y: f64| x + f * (y - x);
    Controls {
        elevator: l(a.elevator, b.elevator),
        aileron: l(a.aileron, b.aileron),
        rudder: l(a.rudder, b.rudder),
        throttle: l(a.throttle, b.throttle),
    }
}

fn lerp_wind(a: &WindInput, b: &WindInput, f: f64) -> WindInput {
    let l = |x: V3, y: V3| {
        [x[0] + f * (y[0] - x[0]), x[1] + f * (y[1] - x[1]), x[2] + f * (y[2] - x[2])]
    };
    WindInput { steady_ned: l(a.steady_ned, b.steady_ned), gust_body: l(a.gust_body, b.gust_body) }
}

/// One classic RK4 step of length `dt` (s). Servo positions and wind move
/// linearly from `u.0`/`wind.0` at the start to `u.1`/`wind.1` at the end, so the
/// forces — and the accelerometer truth — stay continuous in time.
/// The quaternion is renormalised afterwards.
pub fn rk4_step(
    af: &Airframe,
    s: &State,
    u: (&Controls, &Controls),
    wind: (&WindInput, &WindInput),
    dt: f64,
) -> State {
    let gam = af.gammas();
    let (um, wm) = (lerp_controls(u.0, u.1, 0.5), lerp_wind(wind.0, wind.1, 0.5));
    let x0 = pack(s);
    let axpy = |a: &X, k: &X, h: f64| {
        let mut y = *a;
        for i in 0..13 {
            y[i] += h * k[i];
        }
        y
    };
    let k1 = deriv(af, &gam, &x0, u.0, wind.0);
    let k2 = deriv(af, &gam, &axpy(&x0, &k1, dt / 2.0), &um, &wm);
    let k3 = deriv(af, &gam, &axpy(&x0, &k2, dt / 2.0), &um, &wm);
    let k4 = deriv(af, &gam, &axpy(&x0, &k3, dt), u.1, wind.1);
    let mut x = x0;
    for i in 0..13 {
        x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    let mut s1 = unpack(&x);
    s1.quat = rot::normalize_quat(s1.quat);
    s1
}
