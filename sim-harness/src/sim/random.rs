//! Randomised scenarios for Monte Carlo (`random:SEED`): so the defaults are not tuned
//! to a few scripted flights. Each seed draws, independently of the sensor-noise seed:
//!
//! - the flight kind: 70 % a 6-DoF flight (the Aerosonde or the Easystar-sized airframe
//!   — not the Zagi, which the autopilot cannot hold — with mass and
//!   inertia ×[0.8, 1.25], aerodynamic derivatives ×[0.85, 1.15], control power
//!   ×[0.85, 1.15]; a script of turns, climbs, descents, speed changes and, with a
//!   rudder, doublets and slips), 30 % a kinematic aerobatic flight (a random sequence of
//!   the [`super::kinematic::Figure`]s with random pitch and roll rates, entry speed
//!   18–30 m/s, altitude kept in bounds);
//! - wind: speed uniform in [0, min(10, 0.45·Va)] m/s from a uniform direction,
//!   turbulence none / light / moderate (50 / 30 / 20 %), shear (25 %), gusts (25 %);
//! - sensors: thesis or realistic (50 / 50), the realistic GPS latency in [0, 0.15] s.
//!
//! The draw is written as scenario TOML (the description says what was drawn), so a
//! random flight can be reproduced from its name alone. 120 s each.

use anyhow::{anyhow, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write;

/// Duration of a random flight, s.
pub const DURATION_S: f64 = 120.0;

/// Parses `random:SEED`.
pub fn parse_name(name: &str) -> Option<Result<u64>> {
    let s = name.strip_prefix("random:")?;
    Some(s.parse().map_err(|_| anyhow!("random:SEED needs an unsigned integer seed, not {s:?}")))
}

/// The scenario TOML text for `seed`.
pub fn scenario_toml(seed: u64) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(0x5eed);
    let kinematic = rng.gen_bool(0.3);
    let mut body = String::new();
    let mut what = Vec::new();
    let va = if kinematic {
        kinematic_script(&mut rng, &mut body, &mut what)
    } else {
        sixdof_script(&mut rng, &mut body, &mut what)
    };
    // Wind.
    let w = rng.gen_range(0.0..=(10.0f64).min(0.45 * va));
    let from = rng.gen_range(0.0..360.0f64);
    let turb = match rng.gen_range(0..10) {
        0..=4 => "none",
        5..=7 => "light",
        _ => "moderate",
    };
    let d = from.to_radians();
    let _ = write!(
        body,
        "\n[wind]\nned_m_s = [{}, {}, 0.0]\nturbulence = \"{turb}\"\n",
        -w * d.cos(),
        -w * d.sin()
    );
    what.push(format!("wind {w:.1} m/s from {from:.0}°, turbulence {turb}"));
    if rng.gen_bool(0.25) {
        let g = rng.gen_range(0.01..0.05);
        let _ = writeln!(body, "shear_m_s_per_m = [{}, {}, 0.0]", -g * d.cos(), -g * d.sin());
        what.push(format!("shear {g:.3} (m/s)/m"));
    }
    if rng.gen_bool(0.25) {
        let a = rng.gen_range(1.0..4.0);
        for k in 0..rng.gen_range(1..5) {
            let t = rng.gen_range(15.0..DURATION_S - 10.0);
            let dir = rng.gen_range(0.0..std::f64::consts::TAU);
            let up = rng.gen_range(-0.5..0.5);
            let _ = write!(
                body,
                "\n[[wind.gust]]\nt_s = {t}\nduration_s = {}\nned_m_s = [{}, {}, {}]\n",
                rng.gen_range(2.0..6.0),
                a * dir.cos(),
                a * dir.sin(),
                a * up
            );
            if k == 0 {
                what.push(format!("1 − cos gusts of {a:.1} m/s"));
            }
        }
    }
    // Sensors.
    if rng.gen_bool(0.5) {
        let lat = rng.gen_range(0.0..0.15);
        let _ =
            write!(body, "\n[sensors]\npreset = \"realistic\"\n[sensors.gps]\nlatency_s = {lat}\n");
        what.push(format!("realistic sensors, GPS latency {:.0} ms", lat * 1e3));
    } else {
        body.push_str("\n[sensors]\npreset = \"thesis\"\n");
        what.push("thesis sensors".into());
    }
    format!(
        "name = \"random:{seed}\"\ndescription = \"{}\"\nduration_s = {DURATION_S}\n{body}",
        what.join("; ")
    )
}

fn sixdof_script(rng: &mut ChaCha8Rng, s: &mut String, what: &mut Vec<String>) -> f64 {
    // Not the Zagi: without a rudder it is directionally unstable here (C_nβ < 0) and
    // the autopilot loses it within a minute at any bank (every random Zagi flight crashed).
    let (af, va_lo, va_hi, bank_max, roll_err) = match rng.gen_range(0..2) {
        0 => ("aerosonde", 22.0, 30.0, 50.0, 30.0),
        _ => ("easystar_scaled", 13.0, 17.0, 50.0, 12.0),
    };
    let va: f64 = rng.gen_range(va_lo..va_hi);
    let mut r = |lo: f64, hi: f64| rng.gen_range(lo..hi);
    let (m, j, a, c) = (r(0.8, 1.25), r(0.8, 1.25), r(0.85, 1.15), r(0.85, 1.15));
    let h0 = r(150.0, 300.0);
    let _ = write!(
        s,
        "airframe = \"{af}\"\nroll_error_max_deg = {roll_err}\nairframe_scale = {{ mass = {m}, inertia = {j}, aero = {a}, control = {c} }}\n\n[initial]\naltitude_m = {h0}\nairspeed_m_s = {va}\nheading_deg = {}\n",
        r(0.0, 360.0)
    );
    what.push(format!(
        "6-DoF {af} ×(mass {m:.2}, inertia {j:.2}, aero {a:.2}, control {c:.2}) at {va:.1} m/s"
    ));
    let (mut t, mut h) = (rng.gen_range(4.0..8.0), h0);
    let mut n = 0;
    while t < DURATION_S - 8.0 {
        let leg: f64 = rng.gen_range(6.0..15.0);
        let _ = write!(s, "\n[[maneuver]]\nt = {t}\n");
        match rng.gen_range(0..10) {
            0..=3 => {
                let b = rng.gen_range(15.0..bank_max) * if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
                let _ = writeln!(s, "bank_deg = {b}\nclimb_m_s = 0.0");
            }
            4 | 5 => {
                // Climb or descend within [80, 400] m.
                let c: f64 = rng.gen_range(1.0..3.0);
                let c = if h + c * leg > 400.0 || (h - c * leg > 80.0 && rng.gen_bool(0.5)) {
                    -c
                } else {
                    c
                };
                h += c * leg;
                let b = rng.gen_range(-bank_max / 2.0..bank_max / 2.0);
                let _ = writeln!(s, "bank_deg = {b}\nclimb_m_s = {c}");
            }
            6 => {
                let v = rng.gen_range(va_lo..va_hi);
                let _ = writeln!(s, "bank_deg = 0.0\nclimb_m_s = 0.0\nairspeed_m_s = {v}");
            }
            7 => {
                let _ = writeln!(
                    s,
                    "bank_deg = 0.0\nclimb_m_s = 0.0\ncoordinated = false\nrudder_doublet = {{ amplitude_deg = {}, period_s = {} }}",
                    rng.gen_range(10.0..25.0),
                    rng.gen_range(1.5..3.0)
                );
                let _ = write!(s, "\n[[maneuver]]\nt = {}\ncoordinated = true\n", t + 4.0);
            }
            8 => {
                let _ = writeln!(s, "bank_deg = 0.0\nsideslip_deg = {}", rng.gen_range(-6.0..6.0));
                let _ = write!(s, "\n[[maneuver]]\nt = {}\nsideslip_deg = 0.0\n", t + leg * 0.7);
            }
            _ => {
                let _ = writeln!(s, "bank_deg = 0.0\nclimb_m_s = 0.0");
            }
        }
        t += leg;
        n += 1;
    }
    what.push(format!("{n} legs"));
    va
}

fn kinematic_script(rng: &mut ChaCha8Rng, s: &mut String, what: &mut Vec<String>) -> f64 {
    use super::kinematic::Figure;
    let va: f64 = rng.gen_range(18.0..30.0);
    let h0 = 500.0;
    let _ = write!(
        s,
        "\n[initial]\naltitude_m = {h0}\nairspeed_m_s = {va}\nheading_deg = {}\n",
        rng.gen_range(0.0..360.0)
    );
    let _ =
        write!(s, "\n[[segment]]\nfigure = \"straight\"\nhold_s = {}\n", rng.gen_range(10.0..15.0));
    let (mut t, mut h) = (15.0, h0);
    let mut names = Vec::new();
    while t < DURATION_S - 10.0 {
        let (name, _) = Figure::ALL[rng.gen_range(0..Figure::ALL.len() - 1)];
        let q: f64 = rng.gen_range(30.0..60.0);
        let radius = va / q.to_radians();
        // Keep within [150, 900] m: split-S loses 2R, Immelmann and vertical gain.
        let dh = match name {
            "split_s" => -2.5 * radius,
            "immelmann" => 2.0 * radius,
            "vertical" => 2.0 * radius + 5.0 * va * 0.75,
            "cuban_eight" => -radius,
            _ => 0.0,
        };
        if !(150.0..=900.0).contains(&(h + dh)) {
            continue;
        }
        h += dh;
        let hold: f64 = rng.gen_range(2.0..8.0);
        let bank: f64 = rng.gen_range(60.0..80.0) * if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
        let _ = write!(
            s,
            "\n[[segment]]\nfigure = \"{name}\"\npitch_rate_deg_s = {q}\nroll_rate_deg_s = {}\nhold_s = {hold}\nbank_deg = {bank}\n",
            rng.gen_range(60.0..180.0)
        );
        let gap: f64 = rng.gen_range(2.0..5.0);
        let _ = write!(s, "\n[[segment]]\nfigure = \"straight\"\nhold_s = {gap}\n");
        // Rough figure length, only to fill the flight.
        t += gap + hold.min(8.0) + 2.0 * std::f64::consts::PI / q.to_radians() * 0.75;
        names.push(name);
    }
    what.push(format!("kinematic aerobatics at {va:.1} m/s: {}", names.join(", ")));
    va
}
