//! The firmware's 1 Hz health counters reach the ground station: a simulated flight with an
//! airframe-vibration episode through QEMU sends `VIB` (`Health::vibration`) and `IMU_CLIP`
//! (`Health::imu_clipped`) as NAMED_VALUE_INT, equal to the host replay's counts of the
//! same samples, and the vibration count covers the episode.
mod qemu_common;

use sim_harness::hil::{self, GpsWire, Options};
use sim_harness::{replay, sim};

#[test]
fn qemu_vibration_and_clipping_counters_match_the_host() {
    let Some(fw) = qemu_common::setup("qemu_vibration_and_clipping_counters_match_the_host") else {
        return;
    };
    // flight1, 30 s, 3 m/s² RMS of vibration from 10 to 25 s (30× the thesis IMU's noise).
    let path = std::env::temp_dir().join(format!("wing-qemu-vib-{}.toml", std::process::id()));
    let body = "base = \"flight1\"\nname = \"flight1_vibration\"\n[[vibration]]\nstart_s = 10.0\nend_s = 25.0\naccel_m_s2 = 3.0\ngyro_deg_s = 1.0\n";
    std::fs::write(&path, body).unwrap();
    let sc = sim::load_scenario(path.to_str().unwrap()).unwrap().with_duration(30.0);
    std::fs::remove_file(&path).ok();
    let log = sim::run(&sc, 3).unwrap().log;
    let items = hil::plan(&log, GpsWire::Ubx);
    let out = hil::run(&log, &items, &Options::hil(fw)).expect("HIL run");
    let host = replay::run(&log, wing_ahrs::Config::default(), |_, _| {}).health();
    let n = |k: &str| out.named.get(k).copied();
    println!(
        "firmware VIB {:?} IMU_CLIP {:?}; host vibration {} imu_clipped {}",
        n("VIB"),
        n("IMU_CLIP"),
        host.vibration,
        host.imu_clipped
    );
    // 15 s of 10 Hz fixes: ~150 intervals flagged.
    assert!(host.vibration >= 140, "host flagged only {} intervals", host.vibration);
    assert_eq!(n("VIB"), Some(host.vibration as i64));
    assert_eq!(n("IMU_CLIP"), Some(host.imu_clipped as i64));
}
