//! Property-based robustness of the facade (proptest): whatever sequence of
//! samples and fixes arrives — NaN/Inf/huge values, zero, negative or huge Δt,
//! repeated timestamps, nonsense fixes — the state and covariance stay finite,
//! P stays symmetric positive definite, and nothing panics.

mod common;
use common::{is_pd, is_symmetric};
use proptest::prelude::*;
use wing_ahrs::{Ahrs, Config, FixType, GpsFix, Model};

#[derive(Debug, Clone)]
enum Event {
    Imu { dt_us: i64, gyro: [f32; 3], accel: [f32; 3] },
    Gps { dt_us: i64, vel_ne: [f32; 2], vel_d: Option<f32>, ok: bool, itow: Option<u32> },
    Air { va: f32 },
}

fn wild_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        6 => -20.0f32..20.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(1e30f32),
        1 => Just(-1e30f32),
        1 => proptest::num::f32::ANY,
    ]
}

fn wild_dt() -> impl Strategy<Value = i64> {
    prop_oneof![
        6 => Just(10_000i64),
        2 => 1i64..50_000,
        1 => Just(0i64),
        1 => -50_000i64..0,
        1 => Just(10_000_000_000i64),
        1 => 0i64..5_000_000,
    ]
}

fn event() -> impl Strategy<Value = Event> {
    prop_oneof![
        8 => (wild_dt(), proptest::array::uniform3(wild_f32()), proptest::array::uniform3(wild_f32()))
            .prop_map(|(dt_us, gyro, accel)| Event::Imu { dt_us, gyro, accel }),
        2 => (wild_dt(), proptest::array::uniform2(wild_f32()), proptest::option::of(wild_f32()), any::<bool>(), proptest::option::of(any::<u32>()))
            .prop_map(|(dt_us, vel_ne, vel_d, ok, itow)| Event::Gps { dt_us, vel_ne, vel_d, ok, itow }),
        1 => wild_f32().prop_map(|va| Event::Air { va }),
    ]
}

fn check(ahrs: &Ahrs) -> Result<(), TestCaseError> {
    prop_assert!(ahrs.state().iter().all(|v| v.is_finite()), "state {:?}", ahrs.state());
    let p = &ahrs.covariance();
    prop_assert!(p.iter().flatten().all(|v| v.is_finite()), "P not finite");
    prop_assert!(is_symmetric(p), "P not symmetric");
    prop_assert!(is_pd(p), "P not PD: {:?}", p);
    let e = ahrs.attitude();
    prop_assert!(
        e.roll.abs() <= std::f32::consts::PI
            && e.yaw.abs() <= std::f32::consts::PI
            && e.pitch.abs() <= std::f32::consts::FRAC_PI_2 + 1e-4,
        "attitude {:?}",
        e
    );
    Ok(())
}

fn run(model: Model, events: &[Event]) -> Result<(), TestCaseError> {
    let mut cfg = Config::euler().with_model(model);
    cfg.euler_mut().unwrap().init_from_measurement = events.len() % 2 == 0;
    let mut ahrs = Ahrs::try_new(cfg).expect("a valid configuration");
    let mut t: i64 = 1_000_000;
    for ev in events {
        match *ev {
            Event::Imu { dt_us, gyro, accel } => {
                t = (t + dt_us).max(0);
                ahrs.on_imu(t as u64, gyro, accel);
            }
            Event::Gps { dt_us, vel_ne, vel_d, ok, itow } => {
                let ft = (t + dt_us).max(0) as u64;
                ahrs.on_gps(&GpsFix {
                    t_us: ft,
                    itow_ms: itow,
                    fix_type: FixType::Fix3D,
                    fix_ok: ok,
                    vel_ne,
                    vel_d,
                    ..Default::default()
                });
            }
            Event::Air { va } => {
                ahrs.on_airspeed(t.max(0) as u64, va);
            }
        }
        check(&ahrs)?;
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn ekf1_survives_any_input(events in proptest::collection::vec(event(), 1..400)) {
        run(Model::Ekf1(Default::default()), &events)?;
    }

    #[test]
    fn ekf2_survives_any_input(events in proptest::collection::vec(event(), 1..400)) {
        run(Model::Ekf2(Default::default()), &events)?;
    }
}

/// Plausible but hostile flight: violent rates and accelerations, velocity jumps.
fn plausible_event() -> impl Strategy<Value = Event> {
    prop_oneof![
        10 => (proptest::array::uniform3(-10.0f32..10.0), proptest::array::uniform3(-60.0f32..60.0))
            .prop_map(|(gyro, accel)| Event::Imu { dt_us: 10_000, gyro, accel }),
        1 => proptest::array::uniform3(-60.0f32..60.0)
            .prop_map(|v| Event::Gps { dt_us: 0, vel_ne: [v[0], v[1]], vel_d: Some(v[2]), ok: true, itow: None }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]
    #[test]
    fn stays_consistent_under_violent_but_valid_motion(events in proptest::collection::vec(plausible_event(), 1..1500)) {
        run(Model::Ekf1(Default::default()), &events)?;
    }
}
