//! Flights from JSBSim (an independent flight-dynamics model): `scripts/jsbsim_fly.py`
//! writes JSBSim's truth (t, NED position/velocity, attitude, body rates, specific force,
//! airspeed, wind) to CSV, and [`export`] passes it through this harness's own sensor
//! models into a flight-log CSV that `report` and `compare` read as `jsbsim:NAME`.

use std::path::PathBuf;

/// Where the flight log of JSBSim flight `name` is written and read.
pub fn log_path(name: &str) -> PathBuf {
    let dir = std::env::var_os("WING_AHRS_JSBSIM_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/jsbsim"));
    dir.join(format!("{name}.csv"))
}
