//! The report's first contact: what Carto was doing when the robot first touched something, and
//! what the ground truth says of it (issue 10's diagnosis of real-room failures).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use twin::report::{ContactCause, Heard};
use twin::runner::Lockstep;
use twin::setup::RunSetup;

/// One row of three 0.45 m cells. A door jamb (a thin wall end) stands on the line between
/// columns 1 and 2 and reaches 14 cm up from the bottom wall: 3.5 cm into the body's path (the
/// path's centre line is at 22.5 cm, the body 12 cm either side of it), and outside the sonar's
/// 15° cone from columns 0 and 1 (which reaches at most 7.2 cm off the centre line at the jamb).
/// Cell (0, 2) is free (the footprint at its centre clears the jamb); the move (0, 1) → (0, 2)
/// is not.
const JAMB_ROOM: &str = r#"Scenario(
    name: "jamb",
    cell: Some(0.45),
    room: [(0.0, 0.0), (1.35, 0.0), (1.35, 0.45), (0.0, 0.45)],
    obstacles: [Segment(from: (0.9, 0.0), to: (0.9, 0.14))],
    start: (row: 0, col: 0, heading: East),
    physics: (max_sim_s: 60.0),
    mission: [StartCartography, WaitUntilMapped],
)"#;

#[test]
fn a_forward_into_a_door_jamb_the_sonar_cannot_see_is_classified_as_such() {
    let loaded = RunSetup::from_ron_str(JAMB_ROOM, "jamb.ron", std::path::Path::new(".")).unwrap();
    let truth = loaded.truth();
    assert!(truth.is_free(0, 1) && truth.is_free(0, 2) && truth.can_turn(0, 1));
    assert!(!truth.can_move((0, 1), (0, 2)));
    let mut run = Lockstep::new(loaded, None).unwrap();
    run.run_to_end(|_| {});
    let report = run.report(1.0);
    assert!(report.collisions >= 1, "{report:?}");
    let first = report.first_contact.clone().expect("the robot touches the jamb");
    assert_eq!(first.cause, ContactCause::ForwardBlockedMove, "{first:?}");
    assert_eq!(first.carto_activity, "driving forward");
    assert!(matches!(first.cell, Some((0, 1 | 2))), "{first:?}");
    // Carto drove straight from the centre of (0, 1): the robot is on the row's centre line.
    assert!(first.off_centre_m < 0.225, "{first:?}");
    assert!(first.belief_error_m.is_some_and(|e| e < 0.45), "{first:?}");
    assert!(report.to_text().contains("first contact"), "{}", report.to_text());
    // outside the cone from every cell the robot stood in: no echo ever came from the jamb
    assert_eq!(first.touched_heard, Some(Heard::Never), "{first:?}");
    // and Carto held no echo point there
    assert!(first.touched_held_m.is_none_or(|d| d > 0.10), "{first:?}");
    assert!(report.to_text().contains("never heard by the sonar"), "{}", report.to_text());
}

/// The measured lossy-motor room, seed 2: 0.45 m cells, and a 0.30 m box whose right face
/// lies 7.5 cm west of the centre of cell (2, 3), inside the 19.7 cm circle the body sweeps
/// turning there: the one cell of the room where the truth allows no turn at the centre. The
/// robot hears the box head-on from half a metre in its first row, but by the time it turns in
/// (2, 3) Carto no longer holds an echo point near the spot it touches; the report says the sonar
/// had heard that spot long before.
#[test]
fn a_first_contact_says_whether_the_sonar_had_heard_the_spot_before() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/measured");
    let loaded = RunSetup::load(&dir.join("lossy-motor.ron")).unwrap();
    let mut run = Lockstep::new(loaded, Some(2)).unwrap();
    run.run_to_end(|_| {});
    let first = run.report(1.0).first_contact.expect("the robot touches the box");
    assert_eq!((first.cause, first.cell), (ContactCause::TurnWhereNoTurn, Some((2, 3))), "{first:?}");
    let Some(Heard::Before { first_s, nearest_m }) = first.touched_heard else {
        panic!("the box's face was heard: {first:?}");
    };
    assert!(first_s + 30.0 < first.t_s, "{first:?}");
    assert!(nearest_m < 1.0, "{first:?}");
    // heard, but no longer held: Carto's nearest echo point lay well away from the spot
    assert!(first.touched_held_m.is_some_and(|d| d > 0.10), "{first:?}");
    assert!(run.report(1.0).to_text().contains("Carto's nearest echo point"));
}

#[test]
fn a_run_that_touches_nothing_has_no_first_contact() {
    let text = JAMB_ROOM.replace("obstacles: [Segment(from: (0.9, 0.0), to: (0.9, 0.14))]", "obstacles: []");
    let loaded = RunSetup::from_ron_str(&text, "open.ron", std::path::Path::new(".")).unwrap();
    let mut run = Lockstep::new(loaded, None).unwrap();
    run.run_to_end(|_| {});
    let report = run.report(1.0);
    assert_eq!((report.collisions, report.first_contact.clone()), (0, None), "{report:?}");
    assert!(!report.to_text().contains("first contact"));
}

#[test]
fn the_classes_follow_carto_s_activity_and_the_truth() {
    use carto::pilot::Activity;
    let c = ContactCause::classify;
    assert_eq!(c(Activity::DrivingForward, Some(false), Some(true)), ContactCause::ForwardBlockedMove);
    assert_eq!(
        c(Activity::DrivingForward, None, None),
        ContactCause::Other,
        "no pose: no stored move to judge"
    );
    assert_eq!(c(Activity::DrivingForward, Some(true), Some(false)), ContactCause::ForwardOffPath);
    assert_eq!(c(Activity::Turning, Some(true), Some(false)), ContactCause::TurnWhereNoTurn);
    assert_eq!(c(Activity::ScanLook, None, Some(true)), ContactCause::TurnOffCentre);
    assert_eq!(c(Activity::ShiftingBeforeTurn, None, None), ContactCause::TurnWhereNoTurn);
    assert_eq!(c(Activity::BackingOff, Some(true), Some(true)), ContactCause::BackingOff);
    assert_eq!(c(Activity::Idle, Some(true), Some(true)), ContactCause::Other);
}
