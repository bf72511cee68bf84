//! Receivers that do not report their accuracy honestly, and in-air starts: the learnt
//! GPS velocity noise against the simulator's true noise, the C172 in a 7 m/s wind with a
//! receiver reporting 50× its noise (JSBSim), and a short form of `sim-harness robust`.

use sim_harness::estimate::replay_estimates;
use sim_harness::metrics::compare;
use sim_harness::robust::{self, Start, World};
use sim_harness::sim::{self, SensorSpec};
use sim_harness::{data, replay};
use wing_ahrs::Config;

/// The filter's learnt σ matches the noise the simulated receiver adds, whatever it reports.
#[test]
fn learns_the_receivers_true_velocity_noise() {
    for (sacc, spec) in [("x10", "thesis"), ("none", "thesis"), ("x0.3", "realistic")] {
        let name = format!("flight2+spec={spec},gps=5,sacc={sacc}");
        let sc = sim::load_scenario(&name).unwrap();
        let g = &sc.sensors.gps;
        let truth = ((2.0 * g.vel_noise_ne_m_s.powi(2) + g.vel_noise_d_m_s.powi(2)) / 3.0).sqrt();
        let log = sim::run(&sc, 3).unwrap().log;
        let ahrs = replay::run(&log, Config::default(), |_, _| {});
        let learnt = ahrs.gps_vel_sigma().expect("learnt") as f64;
        eprintln!("{name}: learnt σ {learnt:.4} m/s, true {truth:.4}");
        assert!((learnt / truth - 1.0).abs() < 0.25, "{name}: learnt {learnt} vs true {truth}");
    }
}

fn world(base: &str, spec: SensorSpec, rate_hz: f64, start: Start) -> World {
    World { base: base.into(), spec, rate_hz, latency_s: 0.0, start, wind: String::new(), seed: 1 }
}

/// The reset rules' sweep: every world of seeds 3–6 and 10 (those of seeds 1–14 where the
/// rules fire; the JSBSim worlds where python3 has `jsbsim`) with every receiver report,
/// `f(seed, world index, world, report, log)`.
fn sweep(mut f: impl FnMut(u64, usize, &World, &'static str, &sim_harness::log::FlightLog)) {
    let jsbsim = data::python_has("jsbsim");
    if !jsbsim {
        eprintln!("python3 without jsbsim: the simulator's worlds only");
    }
    for seed in [3, 4, 5, 6, 10] {
        let worlds = robust::worlds(96, seed);
        for (k, w) in
            worlds.iter().enumerate().filter(|(_, w)| jsbsim || w.base.starts_with("sim:"))
        {
            for sacc in ["honest", "x3", "x10", "x0.3", "none"] {
                let log = robust::flight(w, sacc.parse().unwrap()).unwrap();
                f(seed, k, w, sacc, &log);
            }
        }
    }
}

/// The case that lost the attitude while reporting ±1°: a C172 in JSBSim, 7 m/s wind,
/// 30–45° turns, 10 Hz fixes of 0.01 m/s noise reported as 0.5 m/s. Learning the noise
/// keeps it; taking the report as the truth does not do as well.
#[test]
fn c172_in_wind_with_a_pessimistic_receiver() {
    let test = "c172_in_wind_with_a_pessimistic_receiver";
    if !data::python_has("jsbsim") {
        return data::skip(test, "python3 with the PyPI package jsbsim absent");
    }
    let w = world("jsbsim:c172_wind7", SensorSpec::Thesis, 10.0, Start::First);
    let mut as_reported = Config::default();
    as_reported.quat_mut().expect("quaternion filter").learn_vel_noise = false;
    let r = robust::run(0, &w, "x50", Config::default()).unwrap();
    let old = robust::run(0, &w, "x50", as_reported).unwrap();
    let d = r.rms.map(f64::to_degrees);
    let o = old.rms.map(f64::to_degrees);
    eprintln!(
        "{test}: learnt roll/pitch/yaw RMS {:.3}/{:.3}/{:.3}° (NEES {:.2}); as reported {:.3}/{:.3}/{:.3}° (NEES {:.2})",
        d[0], d[1], d[2], r.nees, o[0], o[1], o[2], old.nees
    );
    assert!(!r.lost(), "lost: {r:?}");
    assert!(d[0] <= 0.3 && d[1] <= 0.3, "roll/pitch RMS {d:?} > 0.3°");
    assert!(d[2] <= 1.5, "yaw RMS {:.3}° > 1.5°", d[2]);
    assert!(r.roll_pitch() < 0.8 * old.roll_pitch(), "learning does not help: {d:?} vs {o:?}");
}

/// A short `sim-harness robust`: six worlds, each with the five sAcc reports. How the
/// receiver reports its accuracy must not lose a world the honest report keeps, nor cost
/// more than 1.35× its roll/pitch RMS. The goal is 1.3×, which these six worlds meet (the
/// worst, the C172 switched on level at 4 Hz without a report, 1.25× since the learner
/// starts during the alignment's wait; 1.52× before), but not the whole suite
/// (docs/open-problems.md); the margin is for the JSBSim flights, which a newer JSBSim may
/// fly a little differently. (A world lost with every report is not the report's doing: it
/// is printed, and counted in docs/harness.md's table.)
#[test]
fn short_robustness_suite() {
    let test = "short_robustness_suite";
    let mut worlds = robust::worlds(6, 7);
    if !data::python_has("jsbsim") {
        data::skip(test, "python3 with jsbsim absent: simulator worlds only");
        worlds.retain(|w| !w.base.starts_with("jsbsim:"));
    }
    let res = robust::run_all(&worlds, Config::default()).unwrap();
    eprintln!("{}", robust::table(&worlds, &res));
    eprintln!("{}", robust::details(&worlds, &res));
    let mut kept = 0;
    for r in res.iter().filter(|r| r.sacc != robust::SACC_EULER) {
        let h = res.iter().find(|h| h.world == r.world && h.sacc == "honest").unwrap();
        if h.lost() {
            continue;
        }
        kept += 1;
        let label = worlds[r.world].label();
        assert!(!r.lost(), "{label} with sAcc {} lost where honest is not: {r:?}", r.sacc);
        let ratio = r.roll_pitch() / h.roll_pitch();
        assert!(ratio < 1.35, "{label} sAcc {}: {ratio:.2}× the honest RMS", r.sacc);
        let tilt = r.tilt_rms / h.tilt_rms;
        assert!(tilt < 1.35, "{label} sAcc {}: {tilt:.2}× the honest tilt RMS (NED)", r.sacc);
    }
    assert!(kept >= 20, "only {kept} runs in worlds the honest report keeps");
}

/// Switched on in flight in a 25–35° bank (a power cycle in a turn): the tilt from the GPS
/// acceleration in the turn, not from the accelerometer alone (which reads a coordinated
/// turn as wings level), and the heading from the turn, not from a ground course a strong
/// wind crabs by up to 35° (`flight1` in 12 m/s at 4 Hz with a 150 ms receiver: lost in
/// every run of seeds 4 and 13 with the course alone, tilt 7–9° past 20 s).
#[test]
fn in_air_start_in_a_bank_aligns_the_tilt() {
    // The goals are 1° at 5 s and 0.3° RMS from 15 s. With a 150 ms receiver at 4 Hz they
    // are not all reached: in 12 m/s from 315° 1.15° at 5 s, in still air 1.9° at 5 s and
    // 0.46° RMS from 15 s; the heading stays 2–4° off at σ 4–5° until the wind is known, and
    // the rotation about the specific force takes tilt with it (docs/open-problems.md).
    // There the bounds guard what is reached.
    for (base, wind, hz, latency_s, at5_max, rms_max) in [
        ("sim:flight2", "", 10.0, 0.0, 1.0, 0.3),
        ("sim:coordinated_turn", "", 10.0, 0.0, 1.0, 0.3),
        ("sim:flight1", "wind=12@0", 4.0, 0.15, 1.0, 0.3),
        ("sim:flight1", "wind=12@315", 4.0, 0.15, 1.3, 0.3),
        ("sim:flight1", "", 4.0, 0.15, 2.2, 0.55),
    ] {
        let w = World {
            wind: wind.into(),
            latency_s,
            ..world(base, SensorSpec::Thesis, hz, Start::AirBank)
        };
        let log = robust::flight(&w, "honest".parse().unwrap()).unwrap();
        let t0 = log.rows[0].t;
        let first_fixes: Vec<f64> =
            log.rows.iter().filter(|r| r.gps.is_some()).map(|r| r.t).take(2).collect();
        let tf = first_fixes[1];
        let mut at5 = f64::NAN;
        let mut late = Vec::new();
        replay::run(&log, Config::default(), |row, ahrs| {
            let (Some(tr), a) = (row.truth, ahrs.attitude()) else { return };
            let e = sim_harness::metrics::tilt_error([a.roll, a.pitch, a.yaw].map(f64::from), tr);
            if at5.is_nan() && row.t >= tf + 5.0 {
                at5 = e;
            }
            if row.t >= t0 + 15.0 {
                late.push(e);
            }
        });
        let rms = (late.iter().map(|e| e * e).sum::<f64>() / late.len() as f64).sqrt();
        eprintln!(
            "{}: switched on at {t0:.1} s in a {:.0}° bank: tilt error {:.2}° 5 s after the first two fixes, {:.3}° RMS from 15 s",
            w.label(),
            log.rows[0].truth.unwrap()[0].to_degrees(),
            at5.to_degrees(),
            rms.to_degrees()
        );
        assert!(at5.to_degrees() <= at5_max, "{}: tilt {:.2}° at 5 s", w.label(), at5.to_degrees());
        assert!(
            rms.to_degrees() <= rms_max,
            "{}: tilt RMS {:.3}° from 15 s",
            w.label(),
            rms.to_degrees()
        );
    }
}

/// Where the course keeps disagreeing with the heading (`QuatConfig::course_doubt_after`;
/// counted in `gate_resets[2]`), letting the heading go must pay. Since the alignment takes
/// the heading from the turn, no run of the robustness suite's seeds 1–14 needs the rule, so
/// the heading is put wrong on purpose: a glitch of the IMU's z rate (+0.5 rad/s for 1 s,
/// a 29° heading kick no bias explains) in level flight after 60 s, on six simulated flights
/// in wind, with an honest receiver and one that reports nothing. The rule fires on at least
/// half of the runs, the yaw error from the kick to the end sums to under 0.8× that without
/// the rule, and no run is worse by a tenth.
#[test]
fn a_course_that_keeps_disagreeing_resets_the_heading() {
    let yaw_rms = |log: &sim_harness::log::FlightLog, after: u8, from: f64| {
        let mut cfg = Config::default();
        cfg.quat_mut().unwrap().course_doubt_after = after;
        let (est, ahrs) = replay_estimates(log, cfg);
        let c = compare(log, &est, from).expect("simulated truth");
        (c.att[2].rms.to_degrees(), ahrs.health().gate_resets[2])
    };
    let (mut fired, mut runs, mut worse, mut with_sum, mut without_sum) = (0, 0, 0, 0.0, 0.0);
    for (base, wind) in [
        ("sim:flight1", "wind=7@90"),
        ("sim:flight1", "wind=12@200"),
        ("sim:flight2", "wind=6@0"),
        ("sim:flight2", "wind=3@90"),
        ("sim:aggressive", "wind=6@45"),
        ("sim:coordinated_turn", "wind=7@300"),
    ] {
        let w = World { wind: wind.into(), ..world(base, SensorSpec::Thesis, 5.0, Start::First) };
        for sacc in ["honest", "none"] {
            let mut log = robust::flight(&w, sacc.parse().unwrap()).unwrap();
            let t0 = log.rows[0].t;
            // The first straight second after 60 s: the kick turns the heading, not the tilt.
            let kick = log
                .rows
                .iter()
                .position(|r| r.t > t0 + 60.0 && r.truth.is_some_and(|tr| tr[0].abs() < 0.05))
                .expect("a level moment");
            let tk = log.rows[kick].t;
            for r in log.rows.iter_mut().filter(|r| r.t >= tk && r.t < tk + 1.0) {
                r.gyro[2] += 0.5;
            }
            let (with, resets) = yaw_rms(&log, 5, tk);
            let (without, gated) = yaw_rms(&log, 0, tk);
            eprintln!(
                "{} {sacc}: kick at {:.1} s — yaw RMS after it {with:.2}° with {resets} heading resets, {without:.2}° with {gated}",
                w.label(),
                tk - t0
            );
            runs += 1;
            fired += usize::from(resets > gated);
            worse += usize::from(with > 1.1 * without);
            (with_sum, without_sum) = (with_sum + with, without_sum + without);
        }
    }
    eprintln!("rule fired on {fired} of {runs} runs: yaw RMS summed {with_sum:.2}° with it, {without_sum:.2}° without; {worse} worse by a tenth");
    assert!(2 * fired >= runs, "the rule fired on {fired} of {runs} runs");
    // 0.80× before the biases widened while the latency tracker learns (docs/design.md):
    // the kicked heading's bias share is then learnt again faster without the rule too.
    assert!(with_sum < 0.85 * without_sum, "yaw {with_sum:.2}° with vs {without_sum:.2}° without");
    assert_eq!(worse, 0, "{worse} runs worse by a tenth with the rule");
}

/// A gyro-bias estimate beyond `QuatConfig::bias_plausible_sigmas` turn-on σ resets the
/// biases and aligns the attitude again (counted in `gate_resets[1]`). Over the robustness
/// suite's worlds of five draws (seeds 3–6 and 10, 96 worlds each, every receiver report;
/// the JSBSim worlds where python3 has `jsbsim`; of seeds 1–14 those where it fires) the
/// rule fires somewhere, and where it fires it must pay: no more runs lost, the share of
/// samples beyond 4σ summed lower than without it, and at most a quarter of those runs
/// lost only with it. A sweep, not one scripted flight.
#[test]
fn an_implausible_gyro_bias_is_reset() {
    let off = {
        let mut c = Config::default();
        c.quat_mut().unwrap().bias_plausible_sigmas = 0.0;
        c
    };
    let (mut fired, mut worse, mut lost_with, mut lost_without) = (0, 0, 0, 0);
    let (mut tail_with, mut tail_without) = (0.0, 0.0);
    sweep(|seed, k, w, sacc, log| {
        let (_, ahrs) = replay_estimates(log, Config::default());
        let resets = ahrs.health().gate_resets[1];
        if resets == 0 {
            return;
        }
        let with = robust::run(k, w, sacc, Config::default()).unwrap();
        let without = robust::run(k, w, sacc, off).unwrap();
        eprintln!(
            "seed {seed} world {k} {sacc}: {} — {resets} bias resets: tilt max {:.1}° / {:.1}°, beyond 4σ {:.1} % / {:.1} %, NEES {:.1} / {:.1} (with / without)",
            w.label(),
            with.tilt_max.to_degrees(),
            without.tilt_max.to_degrees(),
            100.0 * with.beyond4,
            100.0 * without.beyond4,
            with.nees,
            without.nees
        );
        fired += 1;
        lost_with += usize::from(with.lost());
        lost_without += usize::from(without.lost());
        worse += usize::from(with.lost() && !without.lost());
        (tail_with, tail_without) = (tail_with + with.beyond4, tail_without + without.beyond4);
    });
    eprintln!(
        "{fired} runs reset: {lost_with} lost with the rule, {lost_without} without ({worse} lost only with it); beyond 4σ summed {:.1} % with, {:.1} % without",
        100.0 * tail_with,
        100.0 * tail_without
    );
    assert!(fired >= 1, "the rule never fired");
    assert!(lost_with <= lost_without, "lost {lost_with} with the rule, {lost_without} without");
    assert!(tail_with < tail_without, "beyond 4σ {tail_with:.3} with, {tail_without:.3} without");
    assert!(4 * worse <= fired, "{worse} of {fired} runs lost only with the rule");
}

/// The suite tells each world's filter its IMU's accelerometer bias and axis misalignment
/// (`robust::told`). Thesis Table 5.1's IMU has neither, and with the default's 0.1 m/s²
/// and 0.3° the reported σ was several times the error (NEES 0.2–0.4 against a lower bound
/// of 2.35). Told, the σ is nearer the filter's own and still covers the error; the
/// estimate does not move.
#[test]
fn the_imus_figures_move_the_reported_sigma_not_the_estimate() {
    use sim_harness::montecarlo::record_run;
    let worlds: Vec<World> = robust::worlds(24, 1)
        .into_iter()
        .filter(|w| w.spec == SensorSpec::Thesis && w.base.starts_with("sim:"))
        .collect();
    assert!(worlds.len() >= 5, "{} thesis worlds", worlds.len());
    let mean = |v: &[Option<f64>]| {
        let v: Vec<f64> = v.iter().flatten().copied().collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (mut shipped, mut told) = (0.0, 0.0);
    for w in &worlds {
        let log = robust::flight(w, "honest".parse().unwrap()).unwrap();
        let t_from = log.rows[0].t + 20.0;
        let a = record_run(w.seed, &log, Config::default(), t_from);
        let b = record_run(w.seed, &log, robust::told(Config::default(), w), t_from);
        assert_eq!(a.err.map(|s| s.rms), b.err.map(|s| s.rms), "{}: the estimate moved", w.label());
        let (na, nb) = (mean(&a.nees3), mean(&b.nees3));
        eprintln!("{}: NEES att {na:.2} as shipped, {nb:.2} told", w.label());
        (shipped, told) = (shipped + na, told + nb);
    }
    let n = worlds.len() as f64;
    let (shipped, told) = (shipped / n, told / n);
    eprintln!("mean NEES att over {n} worlds: {shipped:.2} as shipped, {told:.2} told");
    assert!(told > 3.0 * shipped, "told {told:.2} against {shipped:.2} as shipped");
    assert!(told < 3.73, "told {told:.2}: above the upper bound, over-confident");
}

/// Switched on in the T-6's aerobatics (JSBSim, 2 Hz fixes, 60 ms receiver): the first
/// intervals span an aileron roll, 80–100° of rotation each. Their body-frame mean
/// specific force is the vector of no one attitude; only a receiver whose honest σ made the
/// length test strict skipped them, and a report of none or 10× aligned 57° off and took
/// 30 s to recover (roll/pitch RMS from 20 s 4–5× the honest run's). The alignment now waits
/// for an interval over which the body held still against the specific force
/// (`align::steady`): every report within 1.3× of the honest one.
#[test]
fn an_aileron_roll_at_switch_on_is_not_aligned_on() {
    let test = "an_aileron_roll_at_switch_on_is_not_aligned_on";
    if !data::python_has("jsbsim") {
        return data::skip(test, "python3 with the PyPI package jsbsim absent");
    }
    // The robustness suite's seed 17, world 77.
    let w = World {
        latency_s: 0.06,
        seed: 94,
        ..world("jsbsim:t6_aerobatics_wind6", SensorSpec::Thesis, 2.0, Start::AirBank)
    };
    let honest = robust::run(0, &w, "honest", Config::default()).unwrap();
    assert!(!honest.lost(), "{honest:?}");
    for sacc in ["none", "x10", "x3"] {
        let r = robust::run(0, &w, sacc, Config::default()).unwrap();
        let ratio = r.roll_pitch() / honest.roll_pitch();
        eprintln!(
            "{sacc}: roll/pitch RMS {:.3}° against the honest {:.3}° ({ratio:.2}×)",
            r.roll_pitch().to_degrees(),
            honest.roll_pitch().to_degrees()
        );
        assert!(ratio < 1.3, "{sacc}: {ratio:.2}× the honest RMS");
    }
}

/// Switched on in a steady bank at 1 Hz with the wind unknown, the heading comes from the
/// turn on every fix (`course::turn_direction`: the ground acceleration is across the air
/// velocity whatever the wind), not from a ground course the 7 m/s wind crabs by up to 8°.
/// Without it the attitude about the specific force, which no GPS acceleration sees in a
/// steady turn, drifted with the roll-gyro bias until the turn ended: tilt 5.0–6.4° past
/// 20 s in every report of the robustness suite's C172 worlds at 1 Hz (seeds 10, 13, 22),
/// and 4.6° here (bank, honest). The turn only aids a heading less known than one fix's
/// course (most of its error is shared by a turn's fixes), so the level start with a 150 ms
/// receiver keeps 2.9–3.4°: the bound is what that reaches.
#[test]
fn a_c172_switched_on_in_a_bank_at_1_hz_keeps_its_tilt() {
    let test = "a_c172_switched_on_in_a_bank_at_1_hz_keeps_its_tilt";
    if !data::python_has("jsbsim") {
        return data::skip(test, "python3 with the PyPI package jsbsim absent");
    }
    for (start, latency_s) in [(Start::AirBank, 0.06), (Start::AirLevel, 0.15)] {
        let w = World { latency_s, ..world("jsbsim:c172_wind7", SensorSpec::Thesis, 1.0, start) };
        for sacc in ["honest", "x10", "none"] {
            let r = robust::run(0, &w, sacc, Config::default()).unwrap();
            let d = r.rms.map(f64::to_degrees);
            eprintln!(
                "{test}: {} sAcc {sacc}: roll/pitch/yaw RMS {:.3}/{:.3}/{:.3}°, tilt max {:.2}° past 20 s, NEES {:.2}",
                w.label(),
                d[0],
                d[1],
                d[2],
                r.tilt_max.to_degrees(),
                r.nees
            );
            assert!(!r.lost(), "{} sAcc {sacc} lost: {r:?}", w.label());
            assert!(
                r.tilt_max.to_degrees() <= 3.5,
                "{} sAcc {sacc}: tilt max {:.2}°",
                w.label(),
                r.tilt_max.to_degrees()
            );
        }
    }
}

/// A latency tracker that wanders weighs the snap rolls of turbulent flight as the
/// wander deserves. Seed 19's world 82 (flight2 in light turbulence, realistic sensors,
/// 20 Hz, no receiver delay but the receiver's 0.1 s smoothing): the tracker swung
/// between 0.03 and 0.28 s while its variance counted only intervals (σ ≈ 0.03 s), and
/// a GPS update in a 150°/s roll reversal at 53 s put 5.5–5.7° into the tilt with every
/// receiver: all five runs lost. With the estimate's own scatter as its variance
/// (`mekf/latency.rs`), the tilt past 20 s stays at 2.5–3.9°.
#[test]
fn a_wandering_latency_estimate_does_not_tilt_the_attitude_in_a_snap_roll() {
    let test = "a_wandering_latency_estimate_does_not_tilt_the_attitude_in_a_snap_roll";
    let w = &robust::worlds(96, 19)[82];
    assert_eq!(w.label(), "sim:flight2+wind=6@180,turb=light realistic 20Hz 0ms air-level");
    for sacc in robust::SACC {
        let r = robust::run(82, w, sacc, Config::default()).unwrap();
        eprintln!(
            "{test}: sAcc {sacc}: tilt max {:.2}° past 20 s, NEES {:.2}",
            r.tilt_max.to_degrees(),
            r.nees
        );
        assert!(!r.lost(), "sAcc {sacc} lost: {r:?}");
        assert!(
            r.tilt_max.to_degrees() <= 4.5,
            "sAcc {sacc}: tilt max {:.2}°",
            r.tilt_max.to_degrees()
        );
    }
}

/// A wind learnt from the heading cannot confirm that heading. Seed 1's world 65
/// (`jsbsim:c172_wind7`, thesis sensors, 20 Hz, 150 ms, switched on in a 32° bank): the
/// wind filter took the heading error of the first turn in (10 m/s off at σ 1 m/s), and
/// one course from it, 1.5° off a heading 8° off, cut the heading σ from 5.4° to 2.4°. With
/// the 10× report that run was lost (tilt 5.13° past 20 s, 7.5 % of samples beyond 4σ).
/// With the wind's heading coupling in the course's R (`mekf/wind.rs`) no receiver is
/// lost, and none is beyond 4σ on more than 1 % of its samples.
#[test]
fn a_course_from_a_wind_learnt_with_the_heading_does_not_confirm_it() {
    let test = "a_course_from_a_wind_learnt_with_the_heading_does_not_confirm_it";
    if !data::python_has("jsbsim") {
        return data::skip(test, "python3 with the PyPI package jsbsim absent");
    }
    let w = &robust::worlds(96, 1)[65];
    assert_eq!(w.label(), "jsbsim:c172_wind7 thesis 20Hz 150ms air-bank30");
    for sacc in robust::SACC {
        let r = robust::run(65, w, sacc, Config::default()).unwrap();
        eprintln!(
            "{test}: sAcc {sacc}: tilt max {:.2}° past 20 s, NEES {:.2}, {:.2} % beyond 4σ",
            r.tilt_max.to_degrees(),
            r.nees,
            100.0 * r.beyond4
        );
        assert!(!r.lost(), "sAcc {sacc} lost: {r:?}");
        assert!(r.beyond4 <= 0.01, "sAcc {sacc}: {:.2} % beyond 4σ", 100.0 * r.beyond4);
    }
}

/// The latency the tracker has not yet learnt, carried as a Schmidt consider parameter
/// (`QuatConfig::latency_consider`), against white noise in R (the default). Every
/// switch-on of the robustness suite's seeds 1–27 in a banked `coordinated_turn` with
/// realistic sensors and 1 or 5 Hz fixes 150 ms late (honest reports): the tracker cannot
/// learn 150 ms from the few intervals of the first turn, and the default sums the same
/// latency error of every update of the turn as independent evidence (NEES 10–16 on four
/// of them). Carried, the error is not averaged away: the summed and the worst NEES are
/// lower, and none of them is lost.
#[test]
fn an_untracked_latency_carried_as_a_consider_parameter_is_not_averaged_away() {
    let on = {
        let mut c = Config::default();
        c.quat_mut().unwrap().latency_consider = true;
        c
    };
    let (mut n, mut sum_white, mut sum_carried, mut worst_white, mut worst_carried) =
        (0, 0.0, 0.0, 0.0f64, 0.0f64);
    for seed in 1..=27 {
        for (k, w) in robust::worlds(96, seed).iter().enumerate() {
            let l = w.label();
            let slow = l.ends_with("realistic 1Hz 150ms air-bank30")
                || l.ends_with("realistic 5Hz 150ms air-bank30");
            if !(l.starts_with("sim:coordinated_turn") && slow) {
                continue;
            }
            let white = robust::run(k, w, "honest", Config::default()).unwrap();
            let carried = robust::run(k, w, "honest", on).unwrap();
            eprintln!(
                "seed {seed} world {k} {l}: NEES {:.2} → {:.2}, beyond 4σ {:.1} → {:.1} %, yaw RMS {:.2} → {:.2}° (white → carried)",
                white.nees,
                carried.nees,
                100.0 * white.beyond4,
                100.0 * carried.beyond4,
                white.rms[2].to_degrees(),
                carried.rms[2].to_degrees()
            );
            assert!(!carried.lost(), "seed {seed} world {k}: {carried:?}");
            n += 1;
            sum_white += white.nees;
            sum_carried += carried.nees;
            worst_white = worst_white.max(white.nees);
            worst_carried = worst_carried.max(carried.nees);
        }
    }
    eprintln!("{n} runs: NEES summed {sum_white:.1} → {sum_carried:.1}, worst {worst_white:.2} → {worst_carried:.2}");
    assert!(n >= 4, "only {n} such worlds");
    assert!(sum_carried < sum_white, "NEES summed {sum_carried:.1} carried, {sum_white:.1} white");
    assert!(
        worst_carried < worst_white,
        "worst NEES {worst_carried:.2} carried, {worst_white:.2} white"
    );
}
