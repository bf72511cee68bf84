//! The flight-log CSV contract (docs/formats.md) as in-memory rows.
//! One row per IMU sample; optional channels are `None` when the cell is empty.

/// A GPS fix that became available at a row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsSample {
    /// Epoch of the fix, s (`gps_t`).
    pub t: f64,
    /// NED velocity, m/s (`vn ve vd`).
    pub vel: [f64; 3],
    /// The receiver's speed accuracy, m/s 1-σ (`gps_sacc`, optional: an extra column
    /// the contract's readers may ignore; UBX `sAcc`).
    pub speed_acc: Option<f64>,
    /// The fix's position: latitude, longitude (deg) and height (m, WGS-84) (`lat lon alt`,
    /// optional; the navigation peers synthesise one from the velocities when absent).
    pub lla: Option<[f64; 3]>,
}

/// One IMU sample with whatever else arrived with it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LogRow {
    /// IMU sample time, s.
    pub t: f64,
    /// Gyro, rad/s, body FRD.
    pub gyro: [f64; 3],
    /// Specific force, m/s², body FRD.
    pub accel: [f64; 3],
    /// GPS fix available at this row.
    pub gps: Option<GpsSample>,
    /// True airspeed, m/s.
    pub airspeed: Option<f64>,
    /// Barometric altitude, m (`baro_alt`, optional; any fixed datum).
    pub baro_alt: Option<f64>,
    /// True attitude (roll, pitch, yaw), rad.
    pub truth: Option<[f64; 3]>,
    /// True gyro bias, rad/s.
    pub truth_bias: Option<[f64; 3]>,
    /// Another estimator's attitude, rad.
    pub reference: Option<[f64; 3]>,
    /// True wind (air-mass velocity) NED, m/s (`true_wind_n,e,d`; simulator only).
    pub truth_wind: Option<[f64; 3]>,
}

/// A whole flight log.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FlightLog {
    /// Rows in time order.
    pub rows: Vec<LogRow>,
}
