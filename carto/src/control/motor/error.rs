//! Why a move fails ([`MoveError`]).

/// Why a move failed. The robot is stopped whenever one of these is reported.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MoveError {
    /// The move did not finish in time.
    #[error("move timed out after {after_ms} ms")]
    Timeout {
        /// Milliseconds since the move started.
        after_ms: u64,
    },
    /// A sensor the move needs has never reported.
    #[error("no {sensor} reading")]
    MissingReading {
        /// Which sensor.
        sensor: &'static str,
    },
    /// A sensor the move needs stopped reporting.
    #[error("{sensor} reading is stale ({age_ms} ms old)")]
    StaleReading {
        /// Which sensor.
        sensor: &'static str,
        /// Age of its last reading.
        age_ms: u64,
    },
    /// The robot did not settle within tolerance after all corrections.
    #[error("no convergence after {corrections} corrections (error {error:.3})")]
    NotConverged {
        /// Corrections tried.
        corrections: u8,
        /// Remaining error (metres or degrees).
        error: f64,
    },
    /// A return move was asked with no FORWARD to return from.
    #[error("no forward move to return from")]
    NothingToReturnFrom,
    /// A turn stopped coming closer to its target: the body is jammed against something.
    #[error("turn jammed: no progress for {after_ms} ms, {left_deg:.1} deg short of the target")]
    Jammed {
        /// How long the heading did not come closer, milliseconds.
        after_ms: u64,
        /// Degrees still to turn.
        left_deg: f64,
    },
    /// A turn back was asked with no failed turn to undo.
    #[error("no failed turn to undo")]
    NothingToTurnBack,
}
