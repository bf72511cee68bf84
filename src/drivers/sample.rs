//! What every IMU driver returns: raw counts as read, and the SI sample in body FRD.

use super::axes::AxisMap;

/// One burst read as the chip reports it: sensor frame, raw counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RawSample {
    /// Accelerometer X, Y, Z, LSB (sensor frame).
    pub accel: [i16; 3],
    /// Die temperature, LSB.
    pub temp: i16,
    /// Gyro X, Y, Z, LSB (sensor frame).
    pub gyro: [i16; 3],
}

impl RawSample {
    /// True when any axis sits at a rail (the value is clipped, not measured).
    pub fn saturated(&self) -> bool {
        let rail = |v: i16| v == i16::MAX || v == i16::MIN;
        self.accel.iter().chain(self.gyro.iter()).any(|&v| rail(v))
    }

    /// Scales counts (rad/s and m/s² per LSB) and rotates sensor → body FRD.
    pub(crate) fn to_si(
        self,
        axes: &AxisMap,
        gyro_per_lsb: f32,
        accel_per_lsb: f32,
        temp_c: f32,
    ) -> ImuSample {
        ImuSample {
            gyro: axes.apply(self.gyro.map(|v| v as f32 * gyro_per_lsb)),
            accel: axes.apply(self.accel.map(|v| v as f32 * accel_per_lsb)),
            temp_c,
            saturated: self.saturated(),
        }
    }
}

/// A converted sample, ready for [`crate::Ahrs::on_imu`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImuSample {
    /// Angular rate, rad/s, body FRD.
    pub gyro: [f32; 3],
    /// Specific force, m/s², body FRD (level and still: (0, 0, −g)).
    pub accel: [f32; 3],
    /// Die temperature, °C.
    pub temp_c: f32,
    /// Some axis was at its rail (see [`RawSample::saturated`]).
    pub saturated: bool,
}
