//! What the navigation peers (PX4 EKF2, fusion-nav) are handed at a GPS fix, built the same
//! way for both: the fix's epoch on a microsecond clock, its NED velocity, a WGS-84
//! position and the accuracies a receiver would report.
//!
//! Where the log has no position (`lat`/`lon`/`alt` empty), one is synthesised by
//! integrating the fixes' velocities (trapezoid between epochs) from a fixed origin and
//! converting north/east metres to degrees with the WGS-84 radii of curvature there. It is
//! consistent with the velocities but carries no absolute information; the table says so.

use crate::log::{GpsSample, LogRow};

/// Origin of a synthesised position: deg, deg, m (WGS-84). Any mid-latitude site would do.
pub const SYNTH_ORIGIN: [f64; 3] = [47.397_742, 8.545_594, 488.0];
/// Receiver accuracies handed to both peers (1-σ): horizontal and vertical position, m,
/// typical of a u-blox M8/M9 with a clear sky (the sim has no position error model).
pub const H_ACC: f64 = 1.0;
/// See [`H_ACC`].
pub const V_ACC: f64 = 1.5;
/// Speed accuracy when the log gives none, m/s (1-σ).
pub const DEFAULT_SACC: f64 = 0.3;
/// Offset added to the log clock so the first sample is not time 0 (PX4 treats 0 as unset), µs.
pub const CLOCK_OFFSET_US: u64 = 1_000_000;

/// A log time in microseconds on the peers' clock.
pub fn micros(t: f64) -> u64 {
    (t.max(0.0) * 1e6).round() as u64 + CLOCK_OFFSET_US
}

/// One fix as the peers receive it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fix {
    /// Epoch, µs on the peers' clock.
    pub time_us: u64,
    /// Latitude, longitude (deg), height (m, WGS-84).
    pub lla: [f64; 3],
    /// NED velocity, m/s.
    pub vel: [f64; 3],
    /// Speed accuracy, m/s 1-σ.
    pub sacc: f64,
    /// Whether `lla` was synthesised from the velocities.
    pub synthetic: bool,
}

/// Turns log fixes into [`Fix`]es, synthesising position where the log has none.
#[derive(Debug, Clone, Default)]
pub struct GnssFeed {
    /// Last epoch (s), its velocity and the synthesised NED position there (m).
    last: Option<(f64, [f64; 3], [f64; 3])>,
    /// Where the log gives arrival times only: the receiver latency, s; each fix's epoch is
    /// its row's time minus this (`Setup::for_log`).
    latency: Option<f64>,
}

/// WGS-84 semi-major axis, m, and first eccentricity squared.
const A: f64 = 6_378_137.0;
const E2: f64 = 6.694_379_990_14e-3;

/// North/east/down metres about `origin` (deg, deg, m) to latitude, longitude, height.
pub fn ned_to_lla(origin: [f64; 3], ned: [f64; 3]) -> [f64; 3] {
    let lat0 = origin[0].to_radians();
    let s = lat0.sin();
    let w = (1.0 - E2 * s * s).sqrt();
    let r_n = A * (1.0 - E2) / (w * w * w); // meridian radius
    let r_e = A / w; // prime vertical radius
    [
        origin[0] + (ned[0] / r_n).to_degrees(),
        origin[1] + (ned[1] / (r_e * lat0.cos())).to_degrees(),
        origin[2] - ned[2],
    ]
}

impl GnssFeed {
    /// A feed with no fix seen yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// A feed that stamps each fix's epoch at its row's time minus `latency`, s, when
    /// given (a log with arrival times only), else at the log's `gps_t`.
    pub fn with_latency(latency: Option<f64>) -> Self {
        GnssFeed { last: None, latency }
    }

    /// The fix at `row`, if one arrived there.
    pub fn fix(&mut self, row: &LogRow) -> Option<Fix> {
        let mut g: GpsSample = row.gps?;
        if let Some(l) = self.latency {
            g.t = row.t - l;
        }
        let pos = match self.last {
            Some((t0, v0, p0)) if g.t > t0 => {
                let dt = g.t - t0;
                core::array::from_fn(|i| p0[i] + 0.5 * (v0[i] + g.vel[i]) * dt)
            }
            Some((_, _, p0)) => p0,
            None => [0.0; 3],
        };
        self.last = Some((g.t, g.vel, pos));
        let (lla, synthetic) = match g.lla {
            Some(lla) => (lla, false),
            None => (ned_to_lla(SYNTH_ORIGIN, pos), true),
        };
        Some(Fix {
            time_us: micros(g.t),
            lla,
            vel: g.vel,
            sacc: g.speed_acc.unwrap_or(DEFAULT_SACC).max(0.05),
            synthetic,
        })
    }
}
