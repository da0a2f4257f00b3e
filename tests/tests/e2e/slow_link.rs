//! A slow, lossy motor link must not make Cute give up on a move Carto is still making.
//!
//! `scenarios/lossy-motor.ron` with seed 3: in cell (1, 0) Carto first backs 2 cm clear of a
//! wall it ranged, then turns; over the 50 ms link with 1 % corrupted bytes each settle nudge of
//! the turn overshoots, and the two motions take longer than 5 s. With Cute's old 5 s move
//! timeout Cute sent STOP in the middle of the turn and the mapping ended at 34 % of the room.
//! Cute's default timeout is now 20 s, above Carto's worst case (two motions, each ended by its
//! own 8 s limit): the run maps the whole room.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

use twin::runner::Lockstep;
use twin::setup::RunSetup;

#[test]
fn a_shift_and_a_slow_turn_over_a_lossy_link_finish_before_cute_gives_up() {
    let loaded = RunSetup::load(Path::new("../scenarios/lossy-motor.ron")).unwrap();
    let mut run = Lockstep::new(loaded, Some(3)).unwrap();
    run.run_to_end(|_| {});
    let r = run.report(0.0);
    assert!(r.passed, "lossy-motor seed 3:\n{}", r.to_text());
    assert!(r.coverage >= 1.0, "lossy-motor seed 3: coverage {}", r.coverage);
}
