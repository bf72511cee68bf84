//! Host side of the HIL sensor-record protocol (`docs/hil-protocol.md`); the
//! firmware's decoder is `src/bin/wing-ahrs-fw/hil.rs`.

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF), as the firmware computes it.
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc = 0xFFFFu16;
    for &b in bytes {
        crc ^= (b as u16) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
        }
    }
    crc
}

fn frame(kind: u8, payload: &[u8]) -> Vec<u8> {
    let mut f = vec![0xA5, 0x5A, kind, payload.len() as u8];
    f.extend_from_slice(payload);
    let crc = crc16(&f[2..]);
    f.extend_from_slice(&crc.to_le_bytes());
    f
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
    let mut p = Vec::with_capacity(41);
    p.extend_from_slice(&t_us.to_le_bytes());
    for v in gyro.iter().chain(&accel) {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&airspeed.unwrap_or(0.0).to_le_bytes());
    p.extend_from_slice(&gps_count.to_le_bytes());
    p.push(airspeed.is_some() as u8);
    frame(1, &p)
}

/// Telemetry configuration record.
pub fn config(attitude_hz: u16, raw_imu_hz: u16, per_sample: bool) -> Vec<u8> {
    let mut p = Vec::with_capacity(5);
    p.extend_from_slice(&attitude_hz.to_le_bytes());
    p.extend_from_slice(&raw_imu_hz.to_le_bytes());
    p.push(per_sample as u8);
    frame(2, &p)
}

/// End-of-flight record: the firmware sends its final report and exits QEMU.
pub fn stop() -> Vec<u8> {
    frame(3, &[])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_matches_the_standard_check_value() {
        // CRC-16/CCITT-FALSE check value for "123456789".
        assert_eq!(crc16(b"123456789"), 0x29B1);
    }

    #[test]
    fn imu_record_layout() {
        let r = imu(0x0102030405060708, [1.0, 2.0, 3.0], [4.0, 5.0, 6.0], Some(20.0), 7);
        assert_eq!(r.len(), 4 + 41 + 2);
        assert_eq!(&r[..4], &[0xA5, 0x5A, 1, 41]);
        assert_eq!(&r[4..12], &0x0102030405060708u64.to_le_bytes());
        assert_eq!(r[4 + 40], 1);
        let crc = u16::from_le_bytes([r[45], r[46]]);
        assert_eq!(crc, crc16(&r[2..45]));
    }
}
