//! Telemetry: MAVLink stream decoding (shared with `hil`) and the bench checker.
pub mod check;
pub mod cli;
pub mod stream;
