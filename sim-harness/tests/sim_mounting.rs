//! IMU mounting and clipping against the simulator's truth: the level calibration
//! recovers a simulated board offset, the configured rotation gives back the attitude
//! accuracy of a board without offset, the in-flight estimate finds pitch/yaw offsets
//! (plus mean α / minus mean β), and clipped samples are counted where the true rates
//! exceed the sensor's full scale.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sim_harness::replay;
use sim_harness::sim::{self, rotation as rot, SimOutput};
use wing_ahrs::mounting::LevelCalibration;
use wing_ahrs::{Ahrs, Config, Flags, InFlightMounting};

const G: f64 = 9.80665;

fn fly(name: &str, offset_deg: [f64; 3], seed: u64) -> SimOutput {
    let mut sc = sim::load_scenario(name).unwrap();
    sc.sensors.imu.mounting_offset_deg = offset_deg;
    sim::run(&sc, seed).unwrap()
}

/// 5 s at rest and level (zero rates, f = −g·z) through the flight's own IMU model.
fn rest_calibration(out: &SimOutput) -> LevelCalibration {
    let mut imu = out.imu.clone();
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    let mut cal = LevelCalibration::default();
    for _ in 0..500 {
        let (g, a) = imu.sample([0.0; 3], [0.0, 0.0, -G], &mut rng);
        cal.push(g.map(|x| x as f32), a.map(|x| x as f32));
    }
    cal
}

/// RMS roll/pitch/yaw error against truth from 20 s, °.
fn rms_error(out: &SimOutput, cfg: Config) -> ([f64; 3], Ahrs) {
    let mut sum = [0.0; 3];
    let mut n = 0usize;
    let ahrs = replay::run(&out.log, cfg, |row, a| {
        if row.t < 20.0 {
            return;
        }
        let e = a.attitude();
        let t = row.truth.unwrap();
        let est = [e.roll as f64, e.pitch as f64, e.yaw as f64];
        for i in 0..3 {
            let d = sim_harness::metrics::wrap(est[i] - t[i]);
            sum[i] += d * d;
        }
        n += 1;
    });
    (sum.map(|s| (s / n as f64).sqrt().to_degrees()), ahrs)
}

#[test]
fn level_calibration_recovers_the_simulated_mounting() {
    for offset in [[3.0, 5.0, 0.0], [-5.0, 3.0, 10.0], [5.0, -5.0, 0.0]] {
        let out = fly("flight1", offset, 1);
        let (roll, pitch) = rest_calibration(&out).offsets().unwrap();
        let err = [roll.to_degrees() as f64 - offset[0], pitch.to_degrees() as f64 - offset[1]];
        println!("thesis IMU, mounting {offset:?}°: level calibration error {err:.4?}°");
        assert!(err.iter().all(|e| e.abs() < 0.2), "{err:?}");
    }
    // Realistic IMU (accelerometer bias 0.1 m/s² σ, scale, cross-axis, 0.3° package draw):
    // the calibration measures the accelerometer's own gravity direction — the forward
    // model M_a·(−g·z) + b — which the bias tilts away from the mounting by ≈ b/g.
    let mut sc = sim::load_scenario("flight1").unwrap().with_spec(sim::SensorSpec::Realistic);
    sc.sensors.imu.mounting_offset_deg = [3.0, 5.0, 0.0];
    let out = sim::run(&sc, 2).unwrap();
    let (roll, pitch) = rest_calibration(&out).offsets().unwrap();
    let f = rot::add(rot::mul_mv(&out.imu.accel_matrix, [0.0, 0.0, -G]), out.imu.accel_bias());
    let want = [(-f[1]).atan2(-f[2]), f[0].atan2(f[1].hypot(f[2]))];
    let vs_model = [roll as f64 - want[0], pitch as f64 - want[1]].map(f64::to_degrees);
    let pkg = out.imu.package_angles;
    let vs_mount = [roll as f64 - pkg[0], pitch as f64 - pkg[1]].map(f64::to_degrees);
    println!(
        "realistic IMU: vs the accelerometer forward model {vs_model:.4?}°, vs the package \
         rotation {vs_mount:.3?}° (accel bias {:.3?} m/s²)",
        out.imu.accel_turn_on
    );
    assert!(vs_model.iter().all(|e| e.abs() < 0.05), "{vs_model:?}");
}

#[test]
fn configured_mounting_restores_the_attitude_accuracy() {
    let clean = fly("flight1", [0.0; 3], 3);
    let tilted = fly("flight1", [3.0, 5.0, 0.0], 3);
    let (base, _) = rms_error(&clean, Config::default());
    let (raw, _) = rms_error(&tilted, Config::default());
    let mut ahrs = Ahrs::try_new(Config::default()).expect("a valid configuration");
    let applied = ahrs.calibrate_level(&rest_calibration(&tilted)).unwrap();
    let (fixed, _) = rms_error(&tilted, *ahrs.config());
    println!(
        "flight1 RMS roll/pitch/yaw from 20 s: no offset {base:.3?}°, 3°/5° offset {raw:.3?}°"
    );
    println!(
        "  with the level calibration applied ({:.3?}°): {fixed:.3?}°",
        applied.map(|a| a.to_degrees())
    );
    assert!(raw[0] > 2.0 && raw[1] > 4.0, "the offset should show: {raw:?}");
    for i in 0..3 {
        assert!(fixed[i] <= base[i] * 1.2 + 0.03, "axis {i}: {fixed:?} vs {base:?}");
    }
}

#[test]
fn in_flight_estimate_finds_pitch_and_yaw_offsets() {
    let offset = [0.0, 4.0, 3.0];
    let mut sc = sim::load_scenario("flight1").unwrap().with_duration(300.0);
    sc.sensors.imu.mounting_offset_deg = offset;
    sc.repeat_every = Some(100.0);
    let out = sim::run(&sc, 4).unwrap();
    let mut cfg = Config::default();
    cfg.mounting.in_flight = InFlightMounting::Estimate;
    cfg.mounting.estimate_time = 1e9; // a plain mean over the whole flight
    let mut seq = 0;
    let (mut alpha, mut beta, mut n) = (0.0, 0.0, 0usize);
    let mut t_used = 0.0f32;
    let ahrs = replay::run(&out.log, cfg, |row, a| {
        let m = a.mounting();
        let x = &out.truth[(row.t * 100.0).round() as usize];
        if a.last_update().seq != seq {
            seq = a.last_update().seq;
            if m.averaged_s > t_used {
                // The truth α, β over the intervals the estimator used.
                t_used = m.averaged_s;
                alpha += x.alpha;
                beta += x.beta;
                n += 1;
            }
        }
    });
    let m = ahrs.mounting();
    let est = m.estimated.expect("steady flight was averaged").map(|a| a.to_degrees() as f64);
    let (alpha, beta) = ((alpha / n as f64).to_degrees(), (beta / n as f64).to_degrees());
    let err = [est[1] - (offset[1] + alpha), est[2] - (offset[2] - beta)];
    println!(
        "in-flight estimate over {:.0} s: pitch {:.3}° (offset {} + mean α {alpha:.3}), yaw \
         {:.3}° (offset {} − mean β {beta:.3}): error {err:.3?}°",
        m.averaged_s, est[1], offset[1], est[2], offset[2]
    );
    assert!(m.averaged_s > 30.0);
    // Pitch only: the yaw is what the course-aided heading allows (documented on
    // `MountingStatus::estimated`), not the offset.
    assert!(err[0].abs() < 0.3, "{err:?}");
}

#[test]
fn clipped_samples_are_counted_where_the_rates_exceed_full_scale() {
    let clip_deg = 40.0;
    let mut sc = sim::load_scenario("aggressive").unwrap();
    sc.sensors.imu.gyro_clip_deg_s = clip_deg;
    let out = sim::run(&sc, 5).unwrap();
    let cfg = Config { gyro_clip: (clip_deg as f32).to_radians(), ..Config::default() };
    let mut flagged = 0usize;
    let mut per_interval = 0u32;
    let mut must = 0usize;
    let mut may = 0usize;
    let ahrs = replay::run(&out.log, cfg, |row, a| {
        flagged += a.flags().has(Flags::IMU_CLIPPED) as usize;
        per_interval = per_interval.max(a.imu_clipped_last_interval());
        let x = &out.truth[(row.t * 100.0).round() as usize];
        let peak = x.body_rates.iter().fold(0.0f64, |m, w| m.max(w.abs())).to_degrees();
        // The thesis gyro's turn-on bias is 1.5°/s σ: ±6°/s around the rail is either.
        must += (peak > clip_deg + 6.0) as usize;
        may += (peak > 0.99 * clip_deg - 6.0) as usize;
    });
    let h = ahrs.health();
    println!(
        "aggressive, gyro full scale {clip_deg}°/s: {} clipped of {} samples (truth: ≥ {must}, \
         ≤ {may}); flagged on {flagged} samples; most in one GPS interval {per_interval}",
        h.imu_clipped, h.imu_samples
    );
    assert!(must > 0, "the flight should exceed the full scale");
    assert!((must..=may).contains(&(h.imu_clipped as usize)));
    assert!(flagged >= h.imu_clipped as usize && per_interval > 0);
    // Without clipping in the sensor, nothing is counted.
    let clean = fly("aggressive", [0.0; 3], 5);
    let ahrs = replay::run(&clean.log, Config::default(), |_, _| {});
    assert_eq!(ahrs.health().imu_clipped, 0);
}

/// `Apply` with the flight's true mean angle of attack as `expected_aoa` (what a user
/// with the airframe's cruise α would configure) against no correction: pitch RMS over
/// the last 100 s of 300 s. Without a known α it would tilt the pitch by the mean α, which
/// is why the default is `Off`.
#[test]
fn applied_in_flight_pitch_estimate_removes_the_offset_given_the_mean_aoa() {
    let offset = [0.0, 4.0, 0.0];
    let flight = |off: [f64; 3]| {
        let mut sc = sim::load_scenario("flight1").unwrap().with_duration(300.0);
        sc.sensors.imu.mounting_offset_deg = off;
        sc.repeat_every = Some(100.0);
        sim::run(&sc, 6).unwrap()
    };
    let pitch_rms = |out: &SimOutput, cfg: Config| {
        let (mut s, mut n) = (0.0, 0usize);
        let a = replay::run(&out.log, cfg, |row, a| {
            if row.t >= 200.0 {
                let d = a.attitude().pitch as f64 - row.truth.unwrap()[1];
                s += d * d;
                n += 1;
            }
        });
        ((s / n as f64).sqrt().to_degrees(), a.mounting())
    };
    let clean = flight([0.0; 3]);
    let tilted = flight(offset);
    // The cruise α: the mean over the steady flight the estimator averages (body rates
    // < 5°/s, |roll| < 15°; over the whole flight, turns and climbs included, it is ~1.5°
    // more, and that difference would remain as the pitch error).
    let steady: Vec<f64> = tilted
        .truth
        .iter()
        .zip(&tilted.log.rows)
        .filter(|(x, r)| {
            rot::norm(x.body_rates).to_degrees() < 5.0
                && r.truth.unwrap()[0].abs() < 15f64.to_radians()
        })
        .map(|(x, _)| x.alpha)
        .collect();
    let alpha = steady.iter().sum::<f64>() / steady.len() as f64;
    let (base, _) = pitch_rms(&clean, Config::default());
    let (raw, _) = pitch_rms(&tilted, Config::default());
    let mut cfg = Config::default();
    cfg.mounting.in_flight = InFlightMounting::Apply;
    cfg.mounting.estimate_time = 60.0;
    cfg.mounting.expected_aoa = alpha as f32;
    let (applied, m) = pitch_rms(&tilted, cfg);
    println!(
        "flight1 ×3, pitch RMS 200–300 s: clean {base:.3}°, 4° offset {raw:.3}°, Apply \
         (expected α {:.2}°) {applied:.3}°, applied pitch {:.3}° after {:.0} s averaged",
        alpha.to_degrees(),
        m.applied[1].to_degrees(),
        m.averaged_s
    );
    assert!(raw > 3.5, "{raw}");
    assert!(applied < 0.5, "{applied}");
}
