//! sim-harness: the host side of wing-ahrs — flight simulation, sensor models,
//! flight-log CSV, replay through the core facade, metrics and figures, QEMU
//! hardware-in-the-loop and the bench telemetry checker.

pub mod accel_cal;
pub mod compare;
pub mod csv;
pub mod data;
pub mod estimate;
pub mod figures;
pub mod headline;
pub mod hil;
pub mod import;
pub mod jsbsim;
pub mod latency;
pub mod log;
pub mod metrics;
pub mod montecarlo;
pub mod peers;
pub mod pypi_logs;
pub mod real_logs;
pub mod replay;
pub mod report;
pub mod robust;
pub mod sim;
pub mod telemetry;
