//! **Our implementation** of the DCM complementary filter of W. Premerlani and P. Bizard,
//! "Direction Cosine Matrix IMU: Theory" (2009), with the GPS-velocity-difference
//! centripetal compensation used by ArduPilot's `AP_AHRS_DCM` (and PX4's former
//! `ATT_ACC_COMP`): the baseline most autopilots fly. Written here from the paper and
//! ArduPilot's published description — not ArduPilot code; f64 since it is a host baseline.
//!
//! - Kinematics: `R_NB ← R_NB (I + [ω×]Δt)`, ω = gyro + ω_I + ω_P + ω_yaw, then the
//!   paper's renormalisation (orthogonality error shared between rows X and Y, Z = X × Y,
//!   first-order unit-length correction).
//! - Roll/pitch drift: over each GPS interval, the accelerometer rotated into NED is
//!   integrated (`Σ R f Δt`) and compared with the GPS specific force
//!   `Δv/Δt − g_N` of the same interval (ArduPilot's `_ra_sum` vs `GA_e`). Both are
//!   normalised; the error is their cross product in NED, its down component dropped
//!   (yaw is corrected from the course separately), rotated into body axes.
//! - Yaw drift: GPS course above 3 m/s ground speed (no magnetometer), error about NED down.
//! - PI gains are ArduPilot's defaults: AHRS_RP_P = AHRS_YAW_P = 0.2 s⁻¹,
//!   Ki = 0.0087, Ki_yaw = 0.01. Not modelled: spin-rate gain scaling, the start-up fast
//!   gains and the integrator's slew limit (ArduPilot calibrates gyros on the ground; our
//!   logs start with an uncalibrated turn-on bias, so the integrator may move freely,
//!   bounded at 10 °/s).
//! - Without GPS for more than 1 s it falls back to gravity-only levelling every 0.1 s.
//! - Start: roll/pitch levelled from the first accelerometer sample, yaw from the first
//!   usable course (as ArduPilot does without a compass).

use super::{course, wrap, Estimator, StepClock, YawSource, G};
use crate::log::LogRow;

type M3 = [[f64; 3]; 3];
type V3 = [f64; 3];

/// Roll/pitch proportional gain, s⁻¹ (AHRS_RP_P).
pub const KP: f64 = 0.2;
/// Yaw proportional gain, s⁻¹ (AHRS_YAW_P).
pub const KP_YAW: f64 = 0.2;
/// Roll/pitch integral gain, s⁻² (ArduPilot `_ki`).
pub const KI: f64 = 0.0087;
/// Yaw integral gain, s⁻² (ArduPilot `_ki_yaw`).
pub const KI_YAW: f64 = 0.01;
/// Bound on the integrator (gyro-bias correction), rad/s.
const OMEGA_I_MAX: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// GPS intervals longer than this are not differenced, s.
const GPS_MAX_INTERVAL: f64 = 1.0;
/// Gravity-only levelling period when GPS is absent, s.
const NO_GPS_PERIOD: f64 = 0.1;

/// The DCM + GPS baseline.
pub struct DcmGps {
    r: M3,
    omega_i: V3,
    omega_p: V3,
    omega_yaw: V3,
    ra_sum: V3,
    ra_dt: f64,
    last_gps: Option<(f64, V3)>,
    levelled: bool,
    yaw_set: bool,
    clock: StepClock,
}

fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn mul(r: &M3, v: V3) -> V3 {
    [dot(r[0], v), dot(r[1], v), dot(r[2], v)]
}
fn mul_t(r: &M3, v: V3) -> V3 {
    core::array::from_fn(|j| r[0][j] * v[0] + r[1][j] * v[1] + r[2][j] * v[2])
}
fn unit(v: V3) -> Option<V3> {
    let n = dot(v, v).sqrt();
    (n > 1e-9).then(|| scale(v, 1.0 / n))
}

/// `R_NB` (body → NED) of 3-2-1 Euler angles.
pub fn r_nb(roll: f64, pitch: f64, yaw: f64) -> M3 {
    let (sf, cf) = roll.sin_cos();
    let (st, ct) = pitch.sin_cos();
    let (sp, cp) = yaw.sin_cos();
    [
        [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp],
        [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp],
        [-st, sf * ct, cf * ct],
    ]
}

impl DcmGps {
    /// A filter with nominal IMU period `dt`, s; it levels itself on the first sample.
    pub fn new(dt: f64) -> Self {
        DcmGps {
            r: r_nb(0.0, 0.0, 0.0),
            omega_i: [0.0; 3],
            omega_p: [0.0; 3],
            omega_yaw: [0.0; 3],
            ra_sum: [0.0; 3],
            ra_dt: 0.0,
            last_gps: None,
            levelled: false,
            yaw_set: false,
            clock: StepClock::new(dt),
        }
    }

    /// The integrator, i.e. minus the gyro-bias estimate, rad/s.
    pub fn omega_i(&self) -> V3 {
        self.omega_i
    }

    fn euler(&self) -> V3 {
        let r = &self.r;
        [r[2][1].atan2(r[2][2]), (-r[2][0]).clamp(-1.0, 1.0).asin(), r[1][0].atan2(r[0][0])]
    }

    /// The paper's renormalisation (eq 18–21).
    fn renormalise(&mut self) {
        let (x, y) = (self.r[0], self.r[1]);
        let e = dot(x, y);
        let xo = add(x, scale(y, -0.5 * e));
        let yo = add(y, scale(x, -0.5 * e));
        let zo = cross(xo, yo);
        let n = |v: V3| scale(v, 0.5 * (3.0 - dot(v, v)));
        self.r = [n(xo), n(yo), n(zo)];
    }

    /// Roll/pitch correction from the measured (rotated, mean) and reference specific forces in NED.
    fn level(&mut self, ga_b: V3, ga_e: V3, interval: f64) {
        let (Some(b), Some(e)) = (unit(ga_b), unit(ga_e)) else { return };
        let mut err = cross(b, e);
        err[2] = 0.0;
        let err_body = mul_t(&self.r, err);
        self.omega_p = scale(err_body, KP);
        self.integrate(scale(err_body, KI * interval));
    }

    fn integrate(&mut self, d: V3) {
        self.omega_i =
            core::array::from_fn(|i| (self.omega_i[i] + d[i]).clamp(-OMEGA_I_MAX, OMEGA_I_MAX));
    }

    fn on_gps(&mut self, t: f64, vel: V3) {
        let chi = course(vel);
        if let (Some(chi), false) = (chi, self.yaw_set) {
            let [ro, pi, _] = self.euler();
            self.r = r_nb(ro, pi, chi);
            self.yaw_set = true;
        } else if let Some(chi) = chi {
            let e = wrap(chi - self.euler()[2]);
            let err_body = mul_t(&self.r, [0.0, 0.0, e]);
            self.omega_yaw = scale(err_body, KP_YAW);
            if let Some((t0, _)) = self.last_gps {
                self.integrate(scale(err_body, KI_YAW * (t - t0)));
            }
        } else {
            self.omega_yaw = [0.0; 3];
        }
        match self.last_gps {
            Some((t0, v0)) if t > t0 && t - t0 <= GPS_MAX_INTERVAL && self.ra_dt > 0.0 => {
                let dt = t - t0;
                let ga_e =
                    [(vel[0] - v0[0]) / dt, (vel[1] - v0[1]) / dt, (vel[2] - v0[2]) / dt - G];
                let ga_b = scale(self.ra_sum, 1.0 / self.ra_dt);
                self.level(ga_b, ga_e, dt);
            }
            _ => {}
        }
        self.last_gps = Some((t, vel));
        self.ra_sum = [0.0; 3];
        self.ra_dt = 0.0;
    }
}

impl Estimator for DcmGps {
    fn name(&self) -> &str {
        "DCM+GPS (ours, P&B)"
    }
    fn step(&mut self, row: &LogRow) {
        let dt = self.clock.dt(row.t);
        if !self.levelled {
            let f = row.accel;
            let roll = (-f[1]).atan2(-f[2]);
            let pitch = f[0].atan2((f[1] * f[1] + f[2] * f[2]).sqrt());
            self.r = r_nb(roll, pitch, 0.0);
            self.levelled = true;
        } else {
            let w = add(add(row.gyro, self.omega_i), add(self.omega_p, self.omega_yaw));
            let d = scale(w, dt);
            // R ← R (I + [d×])
            let r = self.r;
            // Row i of R·[d×] is r_i·[d×] = r_i × d.
            for (i, row_r) in r.iter().enumerate() {
                self.r[i] = add(*row_r, cross(*row_r, d));
            }
            self.renormalise();
        }
        self.ra_sum = add(self.ra_sum, scale(mul(&self.r, row.accel), dt));
        self.ra_dt += dt;
        if let Some(g) = row.gps {
            self.on_gps(row.t, g.vel);
        } else if self.last_gps.is_none_or(|(t0, _)| row.t - t0 > 1.0)
            && self.ra_dt >= NO_GPS_PERIOD
        {
            // No GPS: assume no net acceleration (gravity-only levelling).
            let ga_b = scale(self.ra_sum, 1.0 / self.ra_dt);
            let interval = self.ra_dt;
            self.level(ga_b, [0.0, 0.0, -G], interval);
            self.omega_yaw = [0.0; 3];
            self.ra_sum = [0.0; 3];
            self.ra_dt = 0.0;
        }
    }
    fn attitude(&self) -> [f64; 3] {
        self.euler()
    }
    fn estimates_bias(&self) -> bool {
        true
    }
    fn uses_gps(&self) -> bool {
        true
    }
    fn yaw_source(&self) -> YawSource {
        YawSource::OwnGps
    }
}
