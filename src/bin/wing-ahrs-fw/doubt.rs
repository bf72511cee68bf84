//! Whether the attitude can be trusted, in a ground station's terms: the one predicate
//! ([`unreliable`]) behind the SYS_STATUS AHRS health bit, HEARTBEAT `MAV_STATE_CRITICAL`,
//! ESTIMATOR_STATUS' attitude flag and the WARNING / "recovered" STATUSTEXTs.
//!
//! Fed from what the core exposes: per sample `Ahrs::flags()` and each new
//! `Ahrs::last_update()`, once a second `Ahrs::health()`'s gate resets. It runs in the
//! telemetry task, never in the IMU interrupt. Onset is immediate; recovery waits
//! [`RECOVER_US`] with the predicate false, so a flapping condition cannot flood the link.

use wing_ahrs::{AxisStatus, AxisUpdate, Config, Flags, UpdateRecord};

/// GPS updates remembered for the gating test (a bit each).
const WINDOW: u32 = 16;
/// Unreliable when at least this many of the last [`WINDOW`] updates failed the gate: a
/// manoeuvre's onset fails a few in a row, a corrupted or inconsistent GPS fails most.
const GATED_OF_WINDOW: u32 = 8;
/// A gate reset (heading let go, tilt aligned again) keeps the attitude doubtful this long.
const RESET_HOLD_US: u64 = 10_000_000;
/// The heading may go unmeasured this long (a vertical manoeuvre, a slow pass) before it is
/// doubtful: the gyro holds it meanwhile.
const HEADING_HOLD_US: u64 = 10_000_000;
/// The predicate must stay false this long before "recovered" is announced.
pub const RECOVER_US: u64 = 3_000_000;

/// Why the attitude is unreliable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// No usable GPS fix for `gps_timeout`: gyro only.
    GpsLost,
    /// The filter let the heading go, or is aligning the tilt again, after persistent
    /// gating (or a non-finite state).
    Realigned,
    /// Most recent GPS updates rejected by the χ² gate.
    Gating,
    /// Ground speed too low for the heading to be measured, for [`HEADING_HOLD_US`].
    HeadingUnobservable,
}

impl Reason {
    /// The WARNING STATUSTEXT (≤ 50 characters).
    pub fn text(self) -> &'static str {
        match self {
            Reason::GpsLost => "AHRS unreliable: GPS lost",
            Reason::Realigned => "AHRS unreliable: attitude re-aligned",
            Reason::Gating => "AHRS unreliable: GPS updates rejected",
            Reason::HeadingUnobservable => "AHRS unreliable: heading unobservable",
        }
    }
}

/// What the predicate looks at (once the filter has been aligned).
#[derive(Clone, Copy, Debug)]
pub struct Evidence {
    /// The core's flags of the latest sample (`ALIGNED` clear: aligning again).
    pub flags: Flags,
    /// Of the last [`WINDOW`] GPS updates, how many failed the gate.
    pub gated_recent: u32,
    /// Time since the filter last reset after gating, µs (None: never).
    pub since_reset_us: Option<u64>,
    /// How long the heading has gone unmeasured (`Flags::YAW_UNOBSERVABLE`), µs.
    pub heading_unmeasured_us: u64,
}

/// THE predicate: why the attitude is unreliable now, or None. A new health flag of the
/// core is one more line here (e.g. `if f.has(Flags::DOUBTFUL) { return Some(..) }`).
pub fn unreliable(e: &Evidence) -> Option<Reason> {
    let f = e.flags;
    if f.has(Flags::GPS_LOST) {
        return Some(Reason::GpsLost);
    }
    if !f.has(Flags::ALIGNED) || e.since_reset_us.is_some_and(|t| t < RESET_HOLD_US) {
        return Some(Reason::Realigned);
    }
    // The core's own doubt: a run of gated updates it has not yet recovered from.
    if e.gated_recent >= GATED_OF_WINDOW || f.has(Flags::UNRELIABLE) {
        return Some(Reason::Gating);
    }
    if e.heading_unmeasured_us >= HEADING_HOLD_US {
        return Some(Reason::HeadingUnobservable);
    }
    None
}

/// χ² gates of the configured filter, for the innovation test ratios.
#[derive(Clone, Copy, Debug)]
pub struct Gates {
    /// Quaternion filter: the 3-dof gate on the GPS-acceleration NIS; Euler: per axis.
    vel: [f32; 3],
    /// Whether `vel` gates the sum of the three axes (quaternion) or each axis (Euler).
    joint: bool,
    /// Heading (course) gate, quaternion filter.
    heading: f32,
}

impl Gates {
    /// The gates `cfg` runs with.
    pub fn of(cfg: &Config) -> Self {
        match (cfg.quat(), cfg.euler_config()) {
            (Some(q), _) => {
                Gates { vel: [q.gate_chi2; 3], joint: true, heading: q.gate_chi2_heading }
            }
            (None, Some(e)) => Gates { vel: e.gate_chi2, joint: false, heading: f32::INFINITY },
            (None, None) => Gates { vel: [f32::INFINITY; 3], joint: false, heading: f32::INFINITY },
        }
    }
}

fn failed(a: &AxisUpdate) -> bool {
    matches!(a.status, AxisStatus::Gated | AxisStatus::ForcedAfterGate)
}

/// A change to announce.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// The attitude became unreliable.
    Raised(Reason),
    /// It is reliable again.
    Recovered,
}

/// The monitor's memory between samples.
pub struct Monitor {
    gates: Gates,
    /// Last [`WINDOW`] updates, bit set = failed the gate (bit 0 newest).
    gated: u16,
    /// Whether the filter has been aligned: before, it is calibrating, not unreliable.
    aligned_once: bool,
    /// Since when `Flags::YAW_UNOBSERVABLE` has been set, µs.
    yaw_unobservable_since: Option<u64>,
    resets: Option<u32>,
    reset_at_us: Option<u64>,
    /// The announced state: Some while unreliable.
    raised: Option<Reason>,
    clear_since_us: Option<u64>,
    /// Largest velocity / heading test ratio since [`Monitor::take_ratios`].
    ratios: (f32, f32),
}

impl Monitor {
    /// A monitor for a filter with these gates.
    pub const fn new(gates: Gates) -> Self {
        Monitor {
            gates,
            gated: 0,
            aligned_once: false,
            yaw_unobservable_since: None,
            resets: None,
            reset_at_us: None,
            raised: None,
            clear_since_us: None,
            ratios: (0.0, 0.0),
        }
    }

    /// A new measurement update: its gate outcome and test ratios (ν²/S over the gate,
    /// from S's diagonal: > 1 means rejected, as in PX4's ESTIMATOR_STATUS).
    pub fn on_update(&mut self, u: &UpdateRecord) {
        let g = &self.gates;
        let measured = |a: &AxisUpdate| a.nis().filter(|n| n.is_finite());
        let mut vel = 0.0f32;
        for (a, gate) in u.axes.iter().zip(g.vel) {
            if let Some(n) = measured(a) {
                vel = if g.joint { vel + n } else { vel.max(n / gate) };
            }
        }
        if g.joint {
            vel /= g.vel[0];
        }
        let heading = measured(&u.course).map_or(0.0, |n| n / g.heading);
        self.ratios = (self.ratios.0.max(vel), self.ratios.1.max(heading));
        let bad = u.axes.iter().any(failed) || failed(&u.course);
        let any = u.axes.iter().chain([&u.course]).any(|a| a.status != AxisStatus::NotMeasured);
        if any {
            self.gated = (self.gated << 1) | bad as u16;
        }
    }

    /// The core's gate-reset total (`Health::gate_resets` summed), once a second.
    pub fn on_resets(&mut self, t_us: u64, total: u32) {
        if self.resets.is_some_and(|r| r != total) {
            self.reset_at_us = Some(t_us);
        }
        self.resets = Some(total);
    }

    /// Evaluates the predicate at sample time `t_us`; returns what to announce.
    pub fn step(&mut self, t_us: u64, flags: Flags) -> Option<Change> {
        self.aligned_once |= flags.has(Flags::ALIGNED);
        let heading_unmeasured_us = if flags.has(Flags::YAW_UNOBSERVABLE) {
            t_us.saturating_sub(*self.yaw_unobservable_since.get_or_insert(t_us))
        } else {
            self.yaw_unobservable_since = None;
            0
        };
        if !self.aligned_once {
            return None; // still calibrating: not a warning
        }
        let e = Evidence {
            flags,
            gated_recent: (self.gated as u32 & ((1 << WINDOW) - 1)).count_ones(),
            since_reset_us: self.reset_at_us.map(|r| t_us.saturating_sub(r)),
            heading_unmeasured_us,
        };
        match (unreliable(&e), self.raised) {
            (Some(r), None) => {
                self.raised = Some(r);
                self.clear_since_us = None;
                Some(Change::Raised(r))
            }
            (Some(_), Some(_)) => {
                self.clear_since_us = None;
                None
            }
            (None, Some(_)) => {
                let since = *self.clear_since_us.get_or_insert(t_us);
                if t_us.saturating_sub(since) >= RECOVER_US {
                    self.raised = None;
                    self.clear_since_us = None;
                    return Some(Change::Recovered);
                }
                None
            }
            (None, None) => None,
        }
    }

    /// Whether the filter has been aligned (HEARTBEAT: calibrating until then).
    pub fn aligned_once(&self) -> bool {
        self.aligned_once
    }

    /// The announced state: why the attitude is unreliable, or None.
    pub fn raised(&self) -> Option<Reason> {
        self.raised
    }

    /// The largest velocity and heading test ratios since the last call, then resets them.
    pub fn take_ratios(&mut self) -> (f32, f32) {
        core::mem::replace(&mut self.ratios, (0.0, 0.0))
    }
}
