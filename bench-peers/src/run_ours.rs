//! wing-ahrs, default configuration, fed as `sim-harness replay` feeds it (`Ahrs::step`: the
//! IMU sample with its airspeed, then the row's fix stamped with the row time).

use crate::record::Record;
use wing_ahrs::{Ahrs, Config, FixType, GpsFix, Sample};

pub struct Peer(Ahrs);

impl Peer {
    pub const KEY: &'static str = "ours";
    pub fn new() -> Self {
        Peer(Ahrs::try_new(Config::default()).expect("a valid configuration"))
    }
    pub fn step(&mut self, r: &Record) {
        let sample = Sample {
            t_us: r.t_us,
            gyro: r.gyro,
            accel: r.accel,
            airspeed: (!r.airspeed.is_nan()).then_some(r.airspeed),
        };
        let fix = r.fix.then(|| GpsFix {
            t_us: r.t_us,
            itow_ms: None,
            fix_type: FixType::Fix3D,
            fix_ok: true,
            vel_ne: [r.vel[0], r.vel[1]],
            vel_d: Some(r.vel[2]),
            speed_acc: Some(r.sacc),
            num_sats: 10,
            ..GpsFix::default()
        });
        self.0.step(&sample, fix.as_slice());
    }
    pub fn attitude(&self) -> [f32; 3] {
        let e = self.0.attitude();
        [e.roll, e.pitch, e.yaw]
    }
}
