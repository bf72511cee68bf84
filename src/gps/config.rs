//! Receiver configuration: the UBX messages that set a u-blox receiver to output
//! NAV-PVT at 10 Hz on UART1, for the firmware to send at boot.
//!
//! - u-blox 6/7/8 (protocol ≤ 23): CFG-RATE (100 ms, navRate 1, GPS time),
//!   CFG-MSG (NAV-PVT once per epoch on UART1), then CFG-PRT (UART1 8N1 at the
//!   new baud rate, in UBX+NMEA, out UBX only). CFG-PRT comes last because the
//!   receiver switches baud rate as soon as it applies it.
//! - Generation 9+ (F9/M9/M10): one CFG-VALSET to the RAM layer with the same
//!   settings as configuration keys.
//!
//! Byte layouts follow the u-blox M8 protocol specification (UBX-13003221) §32.10
//! and the F9 interface description (UBX-18010854) §5 / §6.

use super::ubx::frame as ubx_frame;

/// Configuration class.
pub const CLASS_CFG: u8 = 0x06;
/// CFG-PRT id.
pub const ID_PRT: u8 = 0x00;
/// CFG-MSG id.
pub const ID_MSG: u8 = 0x01;
/// CFG-RATE id.
pub const ID_RATE: u8 = 0x08;
/// CFG-VALSET id.
pub const ID_VALSET: u8 = 0x8A;

/// CFG-RATE-MEAS (U2, ms).
pub const KEY_RATE_MEAS: u32 = 0x3021_0001;
/// CFG-RATE-NAV (U2, measurements per solution).
pub const KEY_RATE_NAV: u32 = 0x3021_0002;
/// CFG-MSGOUT-UBX_NAV_PVT_UART1 (U1, per epoch).
pub const KEY_MSGOUT_NAV_PVT_UART1: u32 = 0x2091_0007;
/// CFG-UART1OUTPROT-UBX (L).
pub const KEY_UART1OUTPROT_UBX: u32 = 0x1074_0001;
/// CFG-UART1OUTPROT-NMEA (L).
pub const KEY_UART1OUTPROT_NMEA: u32 = 0x1074_0002;
/// CFG-UART1-BAUDRATE (U4, Bd).
pub const KEY_UART1_BAUDRATE: u32 = 0x4052_0001;

/// Measurement period for 10 Hz, ms.
pub const MEAS_RATE_MS: u16 = 100;
/// Longest output of [`m8_10hz_nav_pvt`] / [`valset_10hz_nav_pvt`], bytes.
pub const CONFIG_MAX: usize = 3 * 8 + 6 + 8 + 20 + 8;

/// CFG-RATE frame: `meas_ms` per measurement, one solution per measurement, GPS time.
pub fn cfg_rate(meas_ms: u16, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; 6];
    p[0..2].copy_from_slice(&meas_ms.to_le_bytes());
    p[2..4].copy_from_slice(&1u16.to_le_bytes()); // navRate
    p[4..6].copy_from_slice(&1u16.to_le_bytes()); // timeRef 1 = GPS
    ubx_frame(CLASS_CFG, ID_RATE, &p, out)
}

/// CFG-MSG frame (8-byte form): output `class/id` once per epoch on UART1 only
/// (port order I2C, UART1, UART2, USB, SPI, reserved).
pub fn cfg_msg_uart1(class: u8, id: u8, rate: u8, out: &mut [u8]) -> Option<usize> {
    let p = [class, id, 0, rate, 0, 0, 0, 0];
    ubx_frame(CLASS_CFG, ID_MSG, &p, out)
}

/// CFG-PRT frame for UART1: 8 data bits, no parity, 1 stop bit at `baud`; input
/// UBX + NMEA, output UBX only.
pub fn cfg_prt_uart1(baud: u32, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; 20];
    p[0] = 1; // portID UART1
    p[4..8].copy_from_slice(&0x0000_08C0u32.to_le_bytes()); // mode: charLen 8 bit, no parity, 1 stop
    p[8..12].copy_from_slice(&baud.to_le_bytes());
    p[12..14].copy_from_slice(&0x0003u16.to_le_bytes()); // inProtoMask UBX | NMEA
    p[14..16].copy_from_slice(&0x0001u16.to_le_bytes()); // outProtoMask UBX
    ubx_frame(CLASS_CFG, ID_PRT, &p, out)
}

/// u-blox M8 and older: CFG-RATE, CFG-MSG (NAV-PVT), CFG-PRT, concatenated.
pub fn m8_10hz_nav_pvt(baud: u32, out: &mut [u8]) -> Option<usize> {
    let mut n = cfg_rate(MEAS_RATE_MS, out)?;
    n += cfg_msg_uart1(super::ubx::CLASS_NAV, super::ubx::ID_PVT, 1, out.get_mut(n..)?)?;
    n += cfg_prt_uart1(baud, out.get_mut(n..)?)?;
    Some(n)
}

/// Generation 9+: one CFG-VALSET (version 0, RAM layer) with rate 100 ms, navRate 1,
/// NAV-PVT on UART1 every epoch, UART1 out UBX only, UART1 at `baud`.
pub fn valset_10hz_nav_pvt(baud: u32, out: &mut [u8]) -> Option<usize> {
    let mut p = [0u8; 4 + 6 + 6 + 5 + 5 + 5 + 8];
    p[0] = 0; // version
    p[1] = 0x01; // layers: RAM
    let mut o = 4;
    let mut kv = |key: u32, val: &[u8]| {
        p[o..o + 4].copy_from_slice(&key.to_le_bytes());
        p[o + 4..o + 4 + val.len()].copy_from_slice(val);
        o += 4 + val.len();
    };
    kv(KEY_RATE_MEAS, &MEAS_RATE_MS.to_le_bytes());
    kv(KEY_RATE_NAV, &1u16.to_le_bytes());
    kv(KEY_MSGOUT_NAV_PVT_UART1, &[1]);
    kv(KEY_UART1OUTPROT_UBX, &[1]);
    kv(KEY_UART1OUTPROT_NMEA, &[0]);
    kv(KEY_UART1_BAUDRATE, &baud.to_le_bytes());
    let len = o;
    ubx_frame(CLASS_CFG, ID_VALSET, &p[..len], out)
}
