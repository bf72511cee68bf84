//! Host side of the HIL sensor-record protocol (`docs/hil-protocol.md`): the core's codec
//! (`wing_ahrs::hil_record`, the one the firmware decodes with), as byte vectors.

use wing_ahrs::hil_record::{self, ImuRecord, Record, TelemetryConfig};
use wing_ahrs::Sample;

/// The frame of one record.
pub fn frame(rec: &Record) -> Vec<u8> {
    let mut f = [0u8; hil_record::MAX_FRAME];
    let n = hil_record::encode(rec, &mut f).expect("MAX_FRAME holds every record");
    f[..n].to_vec()
}

/// IMU record: sample time (µs), gyro (rad/s), specific force (m/s²), optional
/// airspeed (m/s), and the cumulative number of GPS fixes sent so far.
pub fn imu(
    t_us: u64,
    gyro: [f32; 3],
    accel: [f32; 3],
    airspeed: Option<f32>,
    gps_count: u32,
) -> Vec<u8> {
    frame(&Record::Imu(ImuRecord { sample: Sample { t_us, gyro, accel, airspeed }, gps_count }))
}

/// Telemetry configuration record.
pub fn config(attitude_hz: u16, raw_imu_hz: u16, per_sample: bool) -> Vec<u8> {
    frame(&Record::Config(TelemetryConfig { attitude_hz, raw_imu_hz, per_sample }))
}

/// End-of-flight record: the firmware sends its final report and exits QEMU.
pub fn stop() -> Vec<u8> {
    frame(&Record::Stop)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imu_record_decodes_to_what_was_sent() {
        let r = imu(0x0102030405060708, [1.0, 2.0, 3.0], [4.0, 5.0, 6.0], Some(20.0), 7);
        assert_eq!(r.len(), 4 + 41 + 2);
        let Some(Record::Imu(d)) = hil_record::decode_frame(&r) else { panic!("not decoded") };
        assert_eq!(d.sample.t_us, 0x0102030405060708);
        assert_eq!(d.sample.airspeed, Some(20.0));
        assert_eq!(d.gps_count, 7);
        assert_eq!(hil_record::decode_frame(&stop()), Some(Record::Stop));
    }
}
