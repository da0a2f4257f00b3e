//! What the operator is told about session events: one log line each ([`describe`]), a pop-up
//! for those that need acknowledging ([`popup_for`]), and which are warnings that stay on the
//! status line until the next action ([`is_warning`]). Plain text, no GUI types, so the texts
//! are tested without a window; the GUI (`gui`, feature `window`) shows them.
//!
//! ```
//! use cute::notices::{describe, is_warning, popup_for};
//! use cute::session::{COMPAT_HINT, CuteEvent};
//! assert_eq!(describe(&CuteEvent::CompatHint), COMPAT_HINT);
//! assert!(is_warning(&CuteEvent::CompatHint));
//! assert_eq!(popup_for(&CuteEvent::CompatHint).unwrap().text, COMPAT_HINT);
//! ```

use crate::session::{COMPAT_HINT, CuteEvent};

/// A message box the operator must acknowledge.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Popup {
    /// Window title.
    pub title: String,
    /// Message.
    pub text: String,
}

/// The pop-up an event deserves, if any: no path, connection lost, obstacle met, and the
/// failures that end a mission.
pub fn popup_for(event: &CuteEvent) -> Option<Popup> {
    let (title, text) = match event {
        CuteEvent::NoPath { x, y } => ("No path", format!("No path over known free cells to ({x}, {y}).")),
        CuteEvent::ConnectionLost => {
            ("Connection lost", "The connection to Carto was lost; reconnecting.".to_string())
        }
        CuteEvent::ObstacleMet { x, y } => {
            ("Obstacle", format!("The robot met an obstacle at ({x}, {y}); the trajectory was aborted."))
        }
        CuteEvent::MoveTimeout { waiting_for } => {
            ("Timeout", format!("Carto did not answer in time (waiting for {waiting_for:?})."))
        }
        CuteEvent::MoveRejected { command } => {
            ("Move refused", format!("Carto keeps refusing {command}; cartography stopped."))
        }
        CuteEvent::ProtocolError { message, fatal: true } => {
            ("Protocol error", format!("{message}; the connection was closed."))
        }
        CuteEvent::BatchDropped { .. } => ("Batch dropped", describe(event)),
        CuteEvent::CompatHint => ("Carto does not answer", COMPAT_HINT.to_string()),
        _ => return None,
    };
    Some(Popup { title: title.to_string(), text })
}

/// One log line for an event.
pub fn describe(event: &CuteEvent) -> String {
    match event {
        CuteEvent::Connected => "connected to Carto".to_string(),
        CuteEvent::ConnectionLost => "connection lost".to_string(),
        CuteEvent::PositionAcknowledged => "position acknowledged".to_string(),
        CuteEvent::ObstacleMet { x, y } => format!("obstacle met at ({x}, {y})"),
        CuteEvent::NoPath { x, y } => format!("no path to ({x}, {y})"),
        CuteEvent::Reached { x, y } => format!("reached ({x}, {y})"),
        CuteEvent::TrajectorySent { commands } => format!("trajectory of {commands} commands sent"),
        CuteEvent::PlannedThroughUnknown { x, y, cells } => format!(
            "going to ({x}, {y}) through {cells} unknown cells planned as free (--compat explobot-2024: \
             the 2024 Carto cannot map nor see obstacles during a trajectory; --map FILE loads a known map)"
        ),
        CuteEvent::BatchDropped { commands, x, y } => format!(
            "a STOP was sent before, so the 2024 Carto drops this batch of {commands} commands: the \
             robot stays at ({x}, {y}); click again to move it"
        ),
        CuteEvent::CompatHint => COMPAT_HINT.to_string(),
        CuteEvent::MappingDone { free, obstacles, unreachable, moves } => format!(
            "mapping done: {free} free, {obstacles} obstacles, {unreachable} unreachable, {moves} moves"
        ),
        CuteEvent::MoveTimeout { waiting_for } => format!("timeout waiting for {waiting_for:?}"),
        CuteEvent::MoveRejected { command } => format!("{command} refused"),
        CuteEvent::TurnNotMade { faced } => format!(
            "the robot faces {faced}: Carto did not make the last turn (it refuses a turn that would \
             touch something it has seen); following the robot"
        ),
        CuteEvent::WayNotClear { x, y } => format!(
            "Carto did not drive into ({x}, {y}): the way there is not clear of the robot's width; \
             that move is blocked, the cell is not marked as an obstacle"
        ),
        CuteEvent::Stopped => "stopped".to_string(),
        CuteEvent::ProtocolError { message, fatal } => {
            format!("protocol error{}: {message}", if *fatal { " (fatal)" } else { "" })
        }
    }
}

/// True for warnings the operator should keep seeing until the next action (the GUI puts them
/// on its notice line): compat plans through unknown cells, dropped batches, the compat hint, a
/// turn Carto did not make.
pub fn is_warning(event: &CuteEvent) -> bool {
    matches!(
        event,
        CuteEvent::PlannedThroughUnknown { .. }
            | CuteEvent::BatchDropped { .. }
            | CuteEvent::CompatHint
            | CuteEvent::TurnNotMade { .. }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn issue_14_compat_warnings_say_what_happens() {
        let through = CuteEvent::PlannedThroughUnknown { x: 2, y: 3, cells: 5 };
        assert_eq!(
            describe(&through),
            "going to (2, 3) through 5 unknown cells planned as free (--compat explobot-2024: the 2024 \
             Carto cannot map nor see obstacles during a trajectory; --map FILE loads a known map)"
        );
        assert!(is_warning(&through) && popup_for(&through).is_none(), "a notice, not a pop-up per click");
        let dropped = CuteEvent::BatchDropped { commands: 4, x: 1, y: 0 };
        let text = describe(&dropped);
        assert!(
            text.contains("drops this batch of 4 commands") && text.contains("stays at (1, 0)"),
            "{text}"
        );
        assert_eq!(popup_for(&dropped).map(|p| p.title), Some("Batch dropped".to_string()));
        assert_eq!(popup_for(&CuteEvent::CompatHint).map(|p| p.title), Some("Carto does not answer".into()));
        assert!(!is_warning(&CuteEvent::Connected));
    }

    #[test]
    fn a_way_not_clear_says_why_and_that_the_cell_is_not_an_obstacle() {
        let text = describe(&CuteEvent::WayNotClear { x: 2, y: 4 });
        assert!(text.starts_with("Carto did not drive into (2, 4)") && text.contains("not clear"), "{text}");
        assert!(text.contains("not marked as an obstacle"), "{text}");
    }

    #[test]
    fn a_turn_carto_did_not_make_is_a_warning_with_its_likely_reason() {
        let e = CuteEvent::TurnNotMade { faced: robot_model::grid::Heading::East };
        let text = describe(&e);
        assert!(text.starts_with("the robot faces EAST") && text.contains("refuses a turn"), "{text}");
        assert!(is_warning(&e) && popup_for(&e).is_none());
    }
}
