//! Measurement models: each turns sensor data into a measured attitude `z = [φm, θm, ψm]`
//! so that the update is linear (`H = [I₃ 0]`). One file per model or ingredient.

pub mod accel_roll_pitch;
pub mod air_window;
pub mod airspeed_roll_pitch;
pub mod gps_delta;
pub mod heading;
pub mod interval;
pub mod noise;
pub mod solver;
pub mod va_slope;

/// A measured roll/pitch pair; `None` where the geometry gave no measurement.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RollPitch {
    /// Measured roll, rad.
    pub roll: Option<f32>,
    /// Measured pitch, rad.
    pub pitch: Option<f32>,
    /// How many solver calls clamped |c| to the radius.
    pub clamped: u8,
    /// Whether any part was degenerate (no measurement formed).
    pub degenerate: bool,
    /// (sin, cos) of the measured pitch when the model has them at no cost (EKF1).
    pub pitch_sin_cos: Option<(f32, f32)>,
}
