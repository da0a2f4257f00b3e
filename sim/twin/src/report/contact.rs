//! The run's first contact ([`FirstContact`]): what the robot was doing, what the ground truth
//! says of it, and whether the sonar had heard the spot.

use carto::pilot::Activity;
use serde::{Deserialize, Serialize};

use crate::world::Touched;

/// What the robot was doing at the run's first contact, and what the ground truth says of it.
/// One contact is enough to fail a real-room run and usually costs the pose, so the first one is
/// what a sweep counts to tell a blind spot of the sonar from a localisation error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FirstContact {
    /// Sim time, seconds.
    pub t_s: f64,
    /// The grid cell the robot was really in.
    pub cell: Option<(usize, usize)>,
    /// What Carto's pilot was doing, in words ([`Activity::describe`]).
    pub carto_activity: String,
    /// How far the robot's centre really was from its cell's centre, metres.
    pub off_centre_m: f64,
    /// How far Carto's belief (its cell plus its dead-reckoned offset) was from the robot's
    /// centre, metres; `None` without a pose. During a FORWARD the belief lags the motion by
    /// design, so this is the localisation error only for turns and other moves on the spot.
    pub belief_error_m: Option<f64>,
    /// The contact's class.
    pub cause: ContactCause,
    /// What the robot touched (`None` in results written before it was recorded).
    #[serde(default)]
    pub touched: Option<Touched>,
    /// Whether the sonar had reported an echo from what was touched, within [`HEARD_NEAR_M`] of
    /// where it was touched, before the contact (`None` in results written before it was
    /// recorded).
    #[serde(default)]
    pub touched_heard: Option<Heard>,
    /// How far from where the robot touched the nearest echo point Carto's safety checks held at
    /// that moment lies, metres, each point placed in the world from the grid frame as Carto
    /// placed it (from the pose it believed when it heard it). `None` when Carto held no point
    /// (or in results written before it was recorded). Beside [`FirstContact::touched_heard`] it
    /// tells a spot that was heard and forgotten (or cleared) from one Carto still held when it
    /// moved into it.
    #[serde(default)]
    pub touched_held_m: Option<f64>,
}

/// A reported echo counts for a contact if it came from the touched shape this close to where it
/// was touched, metres. A chosen radius: it takes in a leg (2–8 cm) heard on its other side, and
/// keeps one end of a long face from standing for the other.
pub const HEARD_NEAR_M: f32 = 0.10;

/// Whether the sonar had reported an echo from near where the robot touched a shape, before it
/// touched it ([`HEARD_NEAR_M`]): if never, no use of the sonar's readings could have told Carto
/// that surface was there (a face seen elsewhere says nothing of how far it goes); heard before,
/// it was within Carto's knowledge, if only as a range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Heard {
    /// No reported echo came from there.
    Never,
    /// Reported echoes came from there.
    Before {
        /// The first one, seconds of sim time.
        first_s: f64,
        /// The shortest range of any of them, metres: from farther than about 1 m the cone is
        /// wider than the body (24 cm across at 0.9 m).
        nearest_m: f64,
    },
}

impl Heard {
    /// In words, for the report.
    pub fn describe(self) -> String {
        match self {
            Heard::Never => format!("never heard by the sonar within {HEARD_NEAR_M:.2} m of there before"),
            Heard::Before { first_s, nearest_m } => format!(
                "heard by the sonar within {HEARD_NEAR_M:.2} m of there from {first_s:.1} s, from {nearest_m:.2} m at the nearest"
            ),
        }
    }
}

/// Classes of [`FirstContact`], from Carto's activity and the truth ([`crate::truth`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactCause {
    /// A FORWARD from Carto's cell along a move the truth does not have: something in the body's
    /// path that the sonar did not report (beside its cone, or a surface at a glancing angle).
    ForwardBlockedMove,
    /// A FORWARD along a move the truth has: the robot was off its path (localisation).
    ForwardOffPath,
    /// A turn, a scan look or a shift in a cell where the truth allows no turn on the spot.
    TurnWhereNoTurn,
    /// A turn where the truth allows one at the centre: the robot was off it, by a localisation
    /// error or by Carto's own shift before the turn (see [`FirstContact::belief_error_m`]).
    TurnOffCentre,
    /// Driving back after the bumper, a stalled FORWARD or a pushed one.
    BackingOff,
    /// Anything else (between commands, idle, a FORWARD without a stored pose).
    Other,
}

impl ContactCause {
    /// Classifies a contact from Carto's `activity`, whether the truth has the move ahead of
    /// Carto's stored pose, and whether the truth allows a turn in the robot's cell.
    pub fn classify(
        activity: Activity,
        move_ahead_exists: Option<bool>,
        cell_turnable: Option<bool>,
    ) -> ContactCause {
        match activity {
            Activity::DrivingForward => match move_ahead_exists {
                Some(true) => ContactCause::ForwardOffPath,
                Some(false) => ContactCause::ForwardBlockedMove,
                None => ContactCause::Other,
            },
            a if a.is_turning() && cell_turnable == Some(true) => ContactCause::TurnOffCentre,
            a if a.is_turning() => ContactCause::TurnWhereNoTurn,
            Activity::BackingOff => ContactCause::BackingOff,
            _ => ContactCause::Other,
        }
    }

    /// One line for people.
    pub fn describe(self) -> &'static str {
        match self {
            ContactCause::ForwardBlockedMove => {
                "FORWARD along a move the truth blocks (the sonar did not report it)"
            }
            ContactCause::ForwardOffPath => "FORWARD along a move the truth has (off the path: localisation)",
            ContactCause::TurnWhereNoTurn => "turn in a cell where the truth allows no turn",
            ContactCause::TurnOffCentre => {
                "turn in a cell where the truth allows one at the centre (off it: localisation or Carto's shift)"
            }
            ContactCause::BackingOff => "backing off after the bumper, a stall or a push",
            ContactCause::Other => "other",
        }
    }
}
