//! Mounting rotation, level calibration refusals and the clipping counters of the facade,
//! against forward models of a board at rest (the simulator tests the flights:
//! `sim-harness/tests/sim_mounting.rs`).

use wing_ahrs::mounting::{angles_of, BoardRotation, LevelCalibration, LevelError};
use wing_ahrs::rotation::{r_bn, Euler};
use wing_ahrs::{Ahrs, Config, Flags, GRAVITY};

const DEG: f32 = core::f32::consts::PI / 180.0;

/// The specific force of an airframe at rest and level, seen by a board mounted at `o`.
fn board_gravity(o: [f32; 3]) -> [f32; 3] {
    let r = r_bn(&Euler { roll: o[0], pitch: o[1], yaw: o[2] });
    core::array::from_fn(|i| -GRAVITY * r[i][2])
}

/// A deterministic zero-mean ±`amp` "noise" per sample k and axis i (no RNG needed; every
/// run of 10 samples has mean 0).
fn wiggle(k: u32, i: usize, amp: f32) -> f32 {
    let p = ((k * 7 + i as u32 * 3) % 10) as f32 / 9.0;
    amp * (2.0 * p - 1.0)
}

#[test]
fn board_rotation_inverts_the_mounting_and_its_angles_round_trip() {
    let o = [3.0 * DEG, -5.0 * DEG, 20.0 * DEG];
    let rot = BoardRotation::new(o);
    let body = [0.3, -1.2, -9.5];
    let r = rot.matrix();
    let board: [f32; 3] = core::array::from_fn(|i| (0..3).map(|k| r[i][k] * body[k]).sum());
    let back = rot.rotate_to_body(board);
    for i in 0..3 {
        assert!((back[i] - body[i]).abs() < 1e-5, "{back:?} vs {body:?}");
    }
    let a = angles_of(r);
    for i in 0..3 {
        assert!((a[i] - o[i]).abs() < 1e-5, "{a:?} vs {o:?}");
    }
    assert!(BoardRotation::new([0.0; 3]).is_identity() && !rot.is_identity());
}

#[test]
fn level_calibration_measures_roll_and_pitch_and_refuses_what_is_not_rest() {
    let o = [4.0 * DEG, -2.5 * DEG, 30.0 * DEG];
    let f = board_gravity(o);
    let mut cal = LevelCalibration::default();
    for k in 0..300 {
        let a = core::array::from_fn(|i| f[i] + wiggle(k, i, 0.05));
        cal.push([0.01 + wiggle(k, 0, 0.001), -0.02, 0.005], a);
    }
    let (roll, pitch) = cal.offsets().unwrap();
    assert!((roll - o[0]).abs() < 0.02 * DEG && (pitch - o[1]).abs() < 0.02 * DEG);

    let run = |gyro: &dyn Fn(u32) -> [f32; 3], accel: &dyn Fn(u32) -> [f32; 3], n: u32| {
        let mut c = LevelCalibration::default();
        (0..n).for_each(|k| c.push(gyro(k), accel(k)));
        c.offsets()
    };
    let still = |_| [0.0; 3];
    let level = |_| f;
    assert!(matches!(
        run(&still, &level, 50),
        Err(LevelError::TooFewSamples { samples: 50, needed: 200 })
    ));
    // A hand moving the board: 3°/s swings.
    let swing = |k: u32| [wiggle(k, 0, 3.0 * DEG), 0.0, 0.0];
    assert!(matches!(run(&swing, &level, 300), Err(LevelError::Rotating { .. })));
    // A slow steady turn at 10°/s.
    let turn = |_| [0.0, 0.0, 10.0 * DEG];
    assert!(matches!(run(&turn, &level, 300), Err(LevelError::Rotating { .. })));
    let shaken = |k: u32| core::array::from_fn(|i| f[i] + wiggle(k, i, 1.5));
    assert!(matches!(run(&still, &shaken, 300), Err(LevelError::Moving { .. })));
    let heavy = |_| f.map(|x| 1.2 * x);
    match run(&still, &heavy, 300) {
        Err(LevelError::NotOneG { magnitude }) => assert!((magnitude - 1.2 * GRAVITY).abs() < 1e-3),
        other => panic!("{other:?}"),
    }
    let nan = |k: u32| if k == 7 { [f32::NAN; 3] } else { f };
    assert!(matches!(run(&still, &nan, 300), Err(LevelError::NonFiniteSamples { count: 1 })));
}

/// Feeds `secs` of a level airframe at rest through a board mounted at `o`.
fn rest(ahrs: &mut Ahrs, o: [f32; 3], secs: u32) {
    let f = board_gravity(o);
    for k in 1..=secs * 100 {
        ahrs.on_imu(k as u64 * 10_000, [0.0; 3], f);
    }
}

#[test]
fn configured_mounting_levels_the_airframe_not_the_board() {
    let o = [3.0 * DEG, 5.0 * DEG, 0.0];
    let mut raw = Ahrs::try_new(Config::default()).expect("a valid configuration");
    rest(&mut raw, o, 1);
    let e = raw.attitude();
    assert!((e.roll - o[0]).abs() < 0.01 * DEG && (e.pitch - o[1]).abs() < 0.01 * DEG);

    let mut cfg = Config::default();
    cfg.mounting.offsets = o;
    let mut fixed = Ahrs::try_new(cfg).expect("a valid configuration");
    rest(&mut fixed, o, 1);
    let e = fixed.attitude();
    assert!(e.roll.abs() < 0.01 * DEG && e.pitch.abs() < 0.01 * DEG, "{e:?}");
    assert_eq!(fixed.mounting().applied, o);
    assert_eq!(fixed.mounting().estimated, None);

    // calibrate_level from the raw samples: restarts with the measured roll/pitch.
    let mut ahrs = Ahrs::try_new(Config::default()).expect("a valid configuration");
    let mut cal = LevelCalibration::default();
    let f = board_gravity(o);
    for _ in 0..300 {
        cal.push([0.0; 3], f);
    }
    let applied = ahrs.calibrate_level(&cal).unwrap();
    assert!((applied[0] - o[0]).abs() < 1e-4 && (applied[1] - o[1]).abs() < 1e-4);
    assert_eq!(ahrs.config().mounting.offsets, applied);
    rest(&mut ahrs, o, 1);
    let e = ahrs.attitude();
    assert!(e.roll.abs() < 0.01 * DEG && e.pitch.abs() < 0.01 * DEG, "{e:?}");
    // A refused calibration changes nothing.
    let before = ahrs.mounting();
    assert!(ahrs.calibrate_level(&LevelCalibration::default()).is_err());
    assert_eq!(ahrs.mounting(), before);
}

#[test]
fn clipped_samples_are_integrated_counted_and_flagged_per_gps_interval() {
    let cfg = Config::default();
    let mut ahrs = Ahrs::try_new(cfg).expect("a valid configuration");
    let f = [0.0, 0.0, -GRAVITY];
    let t = core::cell::Cell::new(0u64);
    let imu = |a: &mut Ahrs, g: [f32; 3], f: [f32; 3]| {
        t.set(t.get() + 10_000);
        a.on_imu(t.get(), g, f)
    };
    assert!(imu(&mut ahrs, [0.0; 3], f));
    // 98 % of full scale is not clipping; 99.5 % of it is (either sensor).
    assert!(imu(&mut ahrs, [0.98 * cfg.gyro_clip, 0.0, 0.0], f));
    assert_eq!(ahrs.health().imu_clipped, 0);
    assert!(imu(&mut ahrs, [0.0, -0.995 * cfg.gyro_clip, 0.0], f));
    assert!(imu(&mut ahrs, [0.0; 3], [0.0, 0.0, -0.995 * cfg.accel_clip]));
    let h = ahrs.health();
    assert_eq!((h.imu_clipped, h.imu_samples), (2, 4), "integrated and counted");
    assert!(ahrs.flags().has(Flags::IMU_CLIPPED));
    assert_eq!(ahrs.imu_clipped_since_fix(), 2);
    // Beyond the rejection range: rejected, not counted as clipped.
    assert!(!imu(&mut ahrs, [1.01 * cfg.gyro_range, 0.0, 0.0], f));
    assert_eq!(ahrs.health().imu_clipped, 2);

    let fix = |t_us| wing_ahrs::GpsFix {
        t_us,
        vel_ne: [0.0; 2],
        vel_d: Some(0.0),
        fix_type: wing_ahrs::FixType::Fix3D,
        fix_ok: true,
        ..Default::default()
    };
    ahrs.on_gps(&fix(t.get()));
    assert_eq!((ahrs.imu_clipped_since_fix(), ahrs.imu_clipped_last_interval()), (0, 2));
    assert!(ahrs.flags().has(Flags::IMU_CLIPPED), "still set for the interval just closed");
    imu(&mut ahrs, [0.0; 3], f);
    ahrs.on_gps(&fix(t.get()));
    assert_eq!(ahrs.imu_clipped_last_interval(), 0);
    assert!(!ahrs.flags().has(Flags::IMU_CLIPPED), "cleared after a clean interval");
}
