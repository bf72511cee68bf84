//! How EKF2 is configured and fed, shared by the host adapter (`px4_ekf2.rs`) and the M4F
//! bench (`bench-peers`, which includes this file by path): one place for the parameters
//! (docs/peers.md), flags, receiver figures and call order. `no_std`: it uses only `ekf2`.

use ekf2::params::{GnssControl, HeightReference};
use ekf2::types::{AirspeedSample, BaroSample, GnssSample, ImuSample, SystemFlagUpdate};
use ekf2::{Ekf, EkfConfig};

/// Receiver figures EKF2 checks before it uses GNSS (`EKF2_REQ_*`): a healthy 3-D fix.
const PDOP: f32 = 1.2;
const NSATS: u8 = 14;
const FIX_3D: u8 = 3;

/// `EKF2_ARSP_THR`, m/s: PX4's fixed-wing default (`rc.fw_defaults`; the parameter's own
/// default, 0, turns airspeed fusion off, the C++ struct's 2 m/s is neither).
pub const ARSP_THR: f32 = 8.0;

/// PX4's parameter-file defaults where the C++ struct's initialisers differ (PX4
/// `src/modules/ekf2/params_accel_bias.yaml`, `params_wind.yaml`, `params_barometer.yaml`,
/// `module.yaml`): what a PX4 build ships with. `EKF2_ACC_B_NOISE`, m/s³ (struct: 1e-2; the
/// matched configuration hands the spec's instead).
pub const ACC_B_NOISE: f32 = 3e-3;
/// `EKF2_WIND_NSD`, m/s²/√Hz (struct: 1e-2).
pub const WIND_NSD: f32 = 5e-2;
/// `EKF2_BARO_NOISE`, m (struct: 2.0).
pub const BARO_NOISE: f32 = 3.5;
/// `EKF2_HGT_REF`: GNSS (struct: barometer).
pub const HGT_REF: HeightReference = HeightReference::Gnss;

/// PX4's fixed-wing land detector thresholds (`LNDFW_VEL_XY_MAX`, `LNDFW_AIRSPD_MAX`), m/s:
/// above either the vehicle is flying.
const FLYING_GROUND_SPEED: f32 = 5.0;
const FLYING_AIRSPEED: f32 = 6.0;

/// The sensor figures of a matched comparison, in EKF2's units (docs/peers.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// `EKF2_GYR_NOISE`, rad/s (σ of a rate sample at the filter period).
    pub gyro: f32,
    /// `EKF2_ACC_NOISE`, m/s².
    pub accel: f32,
    /// `EKF2_GYR_B_NOISE`, rad/s² (bias random walk at the filter period).
    pub gyro_bias: f32,
    /// `EKF2_GBIAS_INIT`, rad/s.
    pub gyro_bias_init: f32,
    /// `EKF2_ACC_B_NOISE`, m/s³ (accelerometer bias random walk at the filter period).
    pub accel_bias: f32,
    /// `EKF2_ABIAS_INIT`, m/s².
    pub accel_bias_init: f32,
    /// `EKF2_GPS_V_NOISE`, m/s.
    pub gps_vel: f32,
    /// `EKF2_EAS_NOISE`, m/s.
    pub eas: f32,
}

/// `EKF2_PREDICT_US`, µs: PX4's default prediction period. EKF2 constrains each IMU
/// sample's interval to ½–2× its period and integrates gravity over the constrained
/// interval, while the delta velocity covers the whole one.
pub const PREDICT_US: i32 = 10_000;
/// The largest `EKF2_PREDICT_US` PX4's parameter takes, µs.
pub const PREDICT_US_MAX: i32 = 20_000;

/// What changes EKF2's set-up from one log to another.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// `EKF2_DELAY_MAX`, ms: the observation buffers must hold the log's oldest fix.
    pub delay_max_ms: f32,
    /// `EKF2_PREDICT_US`, µs: [`PREDICT_US`], or the IMU's period where that is longer (a
    /// 50 Hz log), so that no sample's interval exceeds twice it.
    pub predict_us: i32,
    /// `EKF2_REQ_GPS_H`, µs: GNSS health time before first use (PX4: 10 s).
    pub gps_health_us: u32,
    /// Sensor figures (matched configuration), or PX4's defaults (`None`).
    pub noise: Option<Noise>,
}

impl Params {
    /// A log that starts in the air with fixes up to 0.3 s old, at PX4's noise defaults: the
    /// bench's flight. 1 s of GNSS health stands in for the checks that would have passed on
    /// the ground before take-off.
    pub const IN_AIR: Params = Params {
        delay_max_ms: 300.0,
        predict_us: PREDICT_US,
        gps_health_us: 1_000_000,
        noise: None,
    };
}

impl Default for Params {
    fn default() -> Self {
        Params::IN_AIR
    }
}

/// EKF2 with [`Params::IN_AIR`] (the bench), or `None` if the C++ side cannot allocate it.
pub fn new() -> Option<Ekf<'static>> {
    with(&Params::IN_AIR)
}

/// EKF2 with the comparison's parameters, or `None` if the C++ side cannot allocate it.
pub fn with(params: &Params) -> Option<Ekf<'static>> {
    let cfg = EkfConfig {
        delay_max_ms: params.delay_max_ms,
        predict_interval_us: params.predict_us,
        ..EkfConfig::default()
    };
    let mut ekf = Ekf::with_config(cfg).ok()?;
    {
        let mut p = ekf.params_mut();
        p.set_gps_control(GnssControl::HPOS | GnssControl::VPOS | GnssControl::VEL);
        p.set_gps_vel_noise(0.3);
        p.set_accel_bias_noise(ACC_B_NOISE);
        p.set_wind_nsd(WIND_NSD);
        p.set_baro_noise(BARO_NOISE);
        p.set_hgt_ref(HGT_REF);
        p.set_airspeed_delay_ms(0.0);
        p.set_airspeed_fusion_threshold_m_s(ARSP_THR);
        p.set_sideslip_fusion_enabled(true);
        // rc.fw_defaults' receiver requirements.
        p.set_required_eph_m(10.0);
        p.set_required_epv_m(10.0);
        p.set_required_h_drift_m_s(0.5);
        p.set_required_v_drift_m_s(1.0);
        if let Some(n) = params.noise {
            p.set_gyro_noise(n.gyro);
            p.set_accel_noise(n.accel);
            p.set_gyro_bias_noise(n.gyro_bias);
            p.set_gyro_bias_init(n.gyro_bias_init);
            p.set_accel_bias_noise(n.accel_bias);
            p.set_accel_bias_init(n.accel_bias_init);
            p.set_gps_vel_noise(n.gps_vel);
            p.set_eas_noise(n.eas);
        }
    }
    ekf.update_parameters();
    ekf.set_min_required_gps_health_time(params.gps_health_us);
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
/// with what arrived with it, then EKF2's update. `in_air` is the land detector's latch,
/// kept by the caller from one sample to the next.
#[allow(clippy::too_many_arguments)]
pub fn step(
    ekf: &mut Ekf<'static>,
    in_air: &mut bool,
    t_us: u64,
    d_angle: [f32; 3],
    d_vel: [f32; 3],
    dt: f32,
    fix: Option<Fix>,
    baro_alt: Option<f32>,
    airspeed: Option<f32>,
) {
    ekf.set_imu_data(&ImuSample::new(t_us, d_angle, d_vel, dt, dt));
    // PX4's land detector, latched: flying once fast over the ground or through the air.
    // (Squared: `no_std` has no `f32::sqrt`.)
    let ground_speed_sq = fix.as_ref().map(|f| f.vel[0] * f.vel[0] + f.vel[1] * f.vel[1]);
    *in_air |= ground_speed_sq.is_some_and(|v2| v2 > FLYING_GROUND_SPEED * FLYING_GROUND_SPEED)
        || airspeed.is_some_and(|v| v > FLYING_AIRSPEED);
    // The vehicle-status flags on every sample, as PX4's ekf2 module republishes them: EKF2
    // starts fake-position fusion at once if it does not know it flies, and airspeed and
    // sideslip fusion wait for that to stop.
    let mut flags = SystemFlagUpdate::new(t_us);
    flags.in_air = *in_air;
    flags.is_fixed_wing = true;
    ekf.set_system_flag_data(&flags);
    if let Some(f) = fix {
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
