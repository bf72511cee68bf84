//! How EKF2 is configured and fed, shared by the host adapter (`px4_ekf2.rs`) and the M4F
//! bench (`bench-peers`, which includes this file by path): one place for the parameters
//! (docs/peers.md), flags, receiver figures and call order. `no_std`: it uses only `ekf2`.

use ekf2::params::GnssControl;
use ekf2::types::{AirspeedSample, BaroSample, GnssSample, ImuSample, SystemFlagUpdate};
use ekf2::{Ekf, EkfConfig};

/// Receiver figures EKF2 checks before it uses GNSS (`EKF2_REQ_*`): a healthy 3-D fix.
const PDOP: f32 = 1.2;
const NSATS: u8 = 14;
const FIX_3D: u8 = 3;

/// EKF2 with the comparison's parameters, or `None` if the C++ side cannot allocate it.
pub fn new() -> Option<Ekf<'static>> {
    let cfg = EkfConfig { delay_max_ms: 300.0, ..EkfConfig::default() };
    let mut ekf = Ekf::with_config(cfg).ok()?;
    {
        let mut p = ekf.params_mut();
        p.set_gps_control(GnssControl::HPOS | GnssControl::VPOS | GnssControl::VEL);
        p.set_gps_vel_noise(0.3);
        p.set_airspeed_delay_ms(0.0);
        p.set_sideslip_fusion_enabled(true);
    }
    ekf.update_parameters();
    Some(ekf)
}

/// One GNSS fix as EKF2 takes it.
pub struct Fix {
    /// The fix epoch, µs (handed over with PPS compensation: EKF2 adds no delay).
    pub time_us: u64,
    /// Latitude, longitude (deg), altitude (m, WGS-84).
    pub lla: [f64; 3],
    /// NED velocity, m/s.
    pub vel: [f32; 3],
    /// Horizontal and vertical position accuracy, m; speed accuracy, m/s.
    pub h_acc: f32,
    pub v_acc: f32,
    pub sacc: f32,
}

/// One IMU sample at `t_us` (delta angle, rad, and delta velocity, m/s, FRD, over `dt` s)
/// with what arrived with it, then EKF2's update.
#[allow(clippy::too_many_arguments)]
pub fn step(
    ekf: &mut Ekf<'static>,
    t_us: u64,
    d_angle: [f32; 3],
    d_vel: [f32; 3],
    dt: f32,
    fix: Option<Fix>,
    baro_alt: Option<f32>,
    airspeed: Option<f32>,
) {
    ekf.set_imu_data(&ImuSample::new(t_us, d_angle, d_vel, dt, dt));
    if let Some(f) = fix {
        // The vehicle-status flags, as PX4's ekf2 module republishes them: a fixed wing
        // in the air. Set directly, they are cleared when the filter initialises.
        let mut flags = SystemFlagUpdate::new(t_us);
        flags.in_air = true;
        flags.is_fixed_wing = true;
        ekf.set_system_flag_data(&flags);
        let g = GnssSample::new(
            f.time_us,
            f.lla[0],
            f.lla[1],
            f.lla[2] as f32,
            f.vel,
            f.h_acc,
            f.v_acc,
            f.sacc,
            PDOP,
            FIX_3D,
            NSATS,
        );
        ekf.set_gps_data_with_pps(&g, true);
    }
    if let Some(b) = baro_alt {
        ekf.set_baro_data(&BaroSample::new(t_us, b));
    }
    if let Some(va) = airspeed {
        ekf.set_airspeed_data(&AirspeedSample::new(t_us, va, 1.0));
    }
    let _ = ekf.update();
}
