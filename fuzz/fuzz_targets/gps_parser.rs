//! Coverage-guided fuzzing of the GPS byte parser: any byte stream must not panic,
//! every fix that comes out must be usable and plausible, and the byte and slice
//! APIs must agree. Seed the corpus with real captures for depth:
//! `cargo +nightly fuzz run gps_parser corpus/gps_parser ../../shared/data/gnss`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use wing_ahrs::gps::{plausible, GpsParser};

fuzz_target!(|data: &[u8]| {
    let mut p = GpsParser::new();
    let mut fixes = 0u32;
    for (i, &b) in data.iter().enumerate() {
        if let Some(f) = p.push(b, i as u64) {
            assert!(f.usable() && plausible(&f), "{f:?}");
            // Stamped with the byte that completed it, or (an NMEA epoch flushed
            // by a newer one) with an earlier byte.
            assert!(f.t_us <= i as u64);
            fixes += 1;
        }
    }
    assert_eq!(p.counters().fixes, fixes);
    let mut q = GpsParser::new();
    let mut n = 0u32;
    q.push_slice(data, 0, |_| n += 1);
    assert_eq!(n, fixes);
    assert_eq!(p.counters(), q.counters());
});
