//! sim-harness: the host side of wing-ahrs — flight simulation, sensor models,
//! flight-log CSV, replay through the core facade, metrics and figures, QEMU
//! hardware-in-the-loop and the bench telemetry checker.

pub mod accel_cal;
pub mod bias_share;
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
pub mod trace_cli;

/// `println!` panics when stdout is a closed pipe (`sim-harness demo | head`, or a trace
/// example piped into `head`): that is the reader having seen enough, so exit quietly; any
/// other panic keeps the default report. Call it first in a binary's `main`.
pub fn quiet_on_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("Broken pipe") || msg.contains("os error 32") {
            std::process::exit(0);
        }
        default(info);
    }));
}
