//! The drive v2 setpoint Carto sends the motor board.

/// A drive v2 setpoint: percentages, vx forward, vy left, omega counter-clockwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Drive {
    /// Forward speed, percent (±100).
    pub vx: i8,
    /// Leftward speed, percent (±100).
    pub vy: i8,
    /// Counter-clockwise rotation, percent (±100).
    pub omega: i8,
}

impl Drive {
    /// All zero: the wheels stop.
    pub const STOP: Drive = Drive { vx: 0, vy: 0, omega: 0 };

    /// Whether this is the zero command.
    pub fn is_stop(&self) -> bool {
        *self == Drive::STOP
    }
}
