//! Local motion ([`crate::slide`]) with a complete floor plan ([`crate::Carto::add_floor_plan`]):
//! a FORWARD by a sliding way through its two cells when the straight way and the tracks beside
//! it are blocked (`pilot/safety.rs`, "Corridor"), and a turn made where in its cell the turning
//! circle clears.
//!
//! - **What may be crossed.** Every point held (the plan's: with a complete plan no reading
//!   adds one) must stay out of the body grown by the clearance, all along the way. Beyond the
//!   band of tracks a straight FORWARD may take, the space the body adds must be known free, and
//!   only a complete plan says so. An echo point stands for a surface anywhere across the cone, and beside it
//!   lies space no reading covered (`docs/journal/world-model.md`, round 10). The evidence grid's
//!   free cells were tried as that knowledge for the one-sonar robot and added hard collisions
//!   (round 11): they were placed from a belief 12 cm off at the 95th percentile, not free at the
//!   2 cm the way keeps. Without a plan, Carto keeps the corridor's tracks within the band and
//!   the turn's shift of `pilot/safety.rs`.
//! - **Turns.** A turn whose circle holds a point slides first to the nearest place in its cell
//!   where the circle clears, over the same lattice.
//! - **How it is driven.** Each leg is a shift at rest, holding the heading
//!   ([`crate::motor::Motor::start_shift`]), aimed at its point from where the odometry says the
//!   body is now, so errors do not add up from leg to leg; a FORWARD's last leg is the
//!   cartography FORWARD on its track ([`crate::motor::Motor::start_next_cell_on`]), with every
//!   watch of a FORWARD. The bumper pressed during a FORWARD's leg ends the FORWARD as a bump
//!   during it does; during a leg before a turn, it ends the turn as failed. A FORWARD stopped
//!   short (the bumper, a stall, a push) backs off over the places its way passed, in reverse
//!   ([`Pilot::retrace_slide`]): the straight way back to the cell's centre would cross what the
//!   way went round.
//! - **Where it ends.** On the next cell's centre line across, within the band of the line
//!   through the centres; when no such place clears, within the band of the centre, short of it
//!   or past it ([`crate::motor::Motor::start_next_cell_at`]): the odometry then holds the
//!   body off the centre, and the next command starts from there.
//! - **The way back.** The places the body passed on its last FORWARD (where it began, and the
//!   end of each leg of a sliding way) and the track of its last drive are kept while the body
//!   only turns on the spot. A FORWARD back into the cell it came from, facing back, goes the
//!   same way in reverse, mirrored into the cell's frame facing back ([`Pilot::way_back`]): a
//!   straight FORWARD as one drive on the mirrored track, a sliding way as its legs in reverse.
//!   That is space the body has just swept, so a straight echo within one cell refuses nothing
//!   there, and a robot that got into a pocket gets out the way it came. The places are the
//!   odometry's: the way back is as good as the belief. Any other move, a STOP, a failure or a
//!   new pose forgets them.
//! - **What Cute hears.** Nothing new: a FORWARD made, or refused as before; a turn made or not.

use std::collections::VecDeque;

use robot_model::grid::{GridPose, Move};
use robot_model::time::Instant;

use super::{Io, Pilot, Stage};
use crate::slide::{self, SlideGeometry};

/// The sliding way of the running command.
#[derive(Debug, Clone, Default)]
pub(super) struct Sliding {
    /// The points still to slide to, from the stored cell's centre.
    legs: VecDeque<(f64, f64)>,
    /// The track of a FORWARD's last leg, left of the line through the centres.
    track_left_m: f64,
    /// Where a FORWARD's last leg stops, ahead of the next cell's centre.
    stop_along_m: f64,
    /// Where the body stood when the running FORWARD's sliding way began and at the end of each
    /// leg since: a back-off retraces them ([`Pilot::retrace_slide`]).
    visited: Vec<(f64, f64)>,
    /// Where the body stood when the running FORWARD began, when it is driven straight (on its
    /// track, without legs).
    straight_from: Option<(f64, f64)>,
    /// The way the body came into its cell, when the body has only turned on the spot since the
    /// last FORWARD made: the way back ([`Pilot::way_back`]).
    way_in: Option<WayIn>,
}

/// A FORWARD made: the pose it started from, the places its body passed (where it began, and
/// the end of each leg of a sliding way), from that cell's centre in its heading's frame, and
/// the track of its last drive, left of the line through the centres.
#[derive(Debug, Clone, PartialEq)]
struct WayIn {
    from: GridPose,
    places: Vec<(f64, f64)>,
    track_left_m: f64,
}

impl Sliding {
    /// Forgets the legs of a way cut short (a STOP, a disconnect, a lost link), or of the last
    /// FORWARD when the next begins.
    pub(super) fn forget(&mut self) {
        self.legs.clear();
        self.visited.clear();
        self.straight_from = None;
    }

    /// A FORWARD driven straight on the track `track_left_m` begins with the body at
    /// `(along, left)` from its cell's centre.
    pub(super) fn straight_began(&mut self, at: (f64, f64), track_left_m: f64) {
        self.straight_from = Some(at);
        self.track_left_m = track_left_m;
    }

    /// Forgets also the way the body came in: it moves, or was moved, otherwise than by turning.
    pub(super) fn forget_way_in(&mut self) {
        self.forget();
        self.way_in = None;
    }

    /// A FORWARD from `from` was made: the places its body passed (where it began, and the end
    /// of each leg of a sliding way) are the way back ([`Pilot::way_back`]).
    pub(super) fn forward_made(&mut self, from: Option<GridPose>) {
        let mut places = core::mem::take(&mut self.visited);
        if places.is_empty() {
            places.extend(self.straight_from.take());
        }
        let track_left_m = self.track_left_m;
        self.way_in = from.filter(|_| !places.is_empty()).map(|from| WayIn { from, places, track_left_m });
    }
}

impl Pilot {
    /// The floor plan given is complete ([`crate::Carto::add_floor_plan`]).
    pub fn know_free_space(&mut self) {
        self.echoes.plan_is_complete();
    }

    /// Whether a complete floor plan was given.
    pub(super) fn free_space_known(&self) -> bool {
        self.echoes.has_complete_plan()
    }

    /// Plans with `plan` from where the robot believes it stands in its stored cell, over the
    /// points within reach of cells A and B (only those heard at rest and the plan's with
    /// `at_rest_only`); `None` without a complete floor plan.
    fn plan_slide<T>(
        &self,
        io: &Io<'_>,
        at_rest_only: bool,
        plan: impl Fn(
            &SlideGeometry,
            (f64, f64),
            &[(f64, f64)],
            &dyn Fn((f64, f64), (f64, f64)) -> bool,
        ) -> Option<T>,
    ) -> Option<T> {
        if !self.free_space_known() {
            return None;
        }
        let s = self.safety;
        let frame = self.place.cell_frame()?;
        let off = io.motor.odometry().offset();
        // the turning circle reaches farthest: half the body's diagonal plus the clearance
        let reach = s.turn_clear_m;
        let along = (-0.5 * s.cell_m - reach, 1.5 * s.cell_m + reach);
        let left = (-0.5 * s.cell_m - reach, 0.5 * s.cell_m + reach);
        let points = self.echoes.in_box(frame, along, left, at_rest_only);
        // the plan is complete: space without a point is free
        plan(&s.slide, (off.along_m, off.left_m), &points, &|_, _| true)
    }

    /// Whether, by a complete floor plan, the body itself fits in the cell ahead (within the stop
    /// tolerance of its centre, [`slide::fits_near`], keeping no clearance: what the cell is, not
    /// how near the robot may go); `None` without one.
    pub(super) fn fits_in_cell_ahead(&self) -> Option<bool> {
        if !self.free_space_known() {
            return None;
        }
        let g = self.safety.slide;
        let frame = self.place.cell_frame()?;
        let reach = g.stop_within_m + g.half_length_m.max(g.half_width_m);
        let points = self.echoes.in_box(frame, (g.cell_m - reach, g.cell_m + reach), (-reach, reach), true);
        Some(slide::fits_near(&g, (g.cell_m, 0.0), 0.0, &points))
    }

    /// A sliding way for the FORWARD from where the robot believes it stands, or `None`.
    pub(super) fn slide_way(&self, io: &Io<'_>) -> Option<slide::Slide> {
        self.plan_slide(io, false, slide::plan)
    }

    /// The FORWARD back into the cell the body came from by its last FORWARD, when that is the
    /// FORWARD asked for (the body stands where the way ended, turned round on the spot): the
    /// way's places in reverse, mirrored into the cell's frame facing back. That space the body
    /// swept, so a straight echo beside it (a leg the way went round) refuses nothing.
    pub(super) fn way_back(&self) -> Option<slide::Slide> {
        let way = self.sliding.way_in.as_ref()?;
        let pose = self.place.pose()?;
        let facing_back = pose.heading == way.from.heading.left().left();
        if !self.free_space_known() || !facing_back || pose.ahead() != Some((way.from.x, way.from.y)) {
            return None;
        }
        let cell = self.safety.cell_m;
        let &(start_along, _) = way.places.first()?;
        if way.places.len() == 1 {
            // driven straight: the same drive back, on the mirrored track, watched as any
            return Some(slide::Slide {
                legs: Vec::new(),
                track_left_m: -way.track_left_m,
                stop_along_m: -start_along,
            });
        }
        let legs: Vec<(f64, f64)> =
            way.places.iter().rev().map(|&(along, left)| (cell - along, -left)).collect();
        let &(end_along, end_left) = legs.last()?;
        // the last leg ends where the way began: the drive after it has nothing left to go (the
        // motor takes an offset past the next centre as the centre)
        Some(slide::Slide { legs, track_left_m: end_left, stop_along_m: end_along.min(cell) - cell })
    }

    /// Starts `way`, the FORWARD back the way the body came ([`Pilot::way_back`]), which
    /// `refused_by` would otherwise have refused.
    pub(super) fn start_way_back(&mut self, io: &mut Io<'_>, way: slide::Slide, refused_by: &str) {
        tracing::info!(refused_by, "FORWARD back the way the body came in: space it has swept");
        self.start_slide(io, way);
    }

    /// The legs to the nearest place in the cell where the turning circle clears, or `None`.
    pub(super) fn turn_place(&self, io: &Io<'_>) -> Option<Vec<(f64, f64)>> {
        self.plan_slide(io, true, slide::plan_turn)
    }

    /// Starts the sliding way `way` of a FORWARD.
    pub(super) fn start_slide(&mut self, io: &mut Io<'_>, way: slide::Slide) {
        tracing::info!(legs = ?way.legs, track_left_m = way.track_left_m, stop_along_m = way.stop_along_m, "FORWARD by a sliding way through its two cells");
        self.counters.forwards_slid += 1;
        self.sliding.way_in = None;
        self.sliding.straight_from = None;
        self.sliding.legs = way.legs.into();
        self.sliding.track_left_m = way.track_left_m;
        self.sliding.stop_along_m = way.stop_along_m;
        let off = io.motor.odometry().offset();
        self.sliding.visited = vec![(off.along_m, off.left_m)];
        self.next_leg(io, io.now, None);
    }

    /// Slides along `legs` to where the turn `mv` can be made, then turns.
    pub(super) fn slide_to_turn(&mut self, io: &mut Io<'_>, mv: Move, legs: Vec<(f64, f64)>) {
        tracing::info!(?legs, "turn: sliding to where its circle clears the known points first");
        self.counters.turns_shifted += 1;
        self.sliding.legs = legs.into();
        self.next_leg(io, io.now, Some(mv));
    }

    /// The next leg of the sliding way: a shift to its point, or, after the last, the FORWARD on
    /// its track or the turn `turn`.
    fn next_leg(&mut self, io: &mut Io<'_>, since: Instant, turn: Option<Move>) {
        let Some((along, left)) = self.sliding.legs.pop_front() else {
            if let Some(mv) = turn {
                return self.start_turn(io, mv);
            }
            self.forward.start(io, None);
            let (track, stop) = (self.sliding.track_left_m, self.sliding.stop_along_m);
            return match io.motor.start_next_cell_at(io.now, track, stop, io.sensors) {
                // the FORWARD's watches start with its drive, not with the legs before it
                Ok(_) => self.stage = Stage::Moving { kind: Move::Forward, since: io.now },
                Err(e) => self.fail(io.now, &e.to_string()),
            };
        };
        let off = io.motor.odometry().offset();
        match io.motor.start_shift(io.now, along - off.along_m, left - off.left_m, io.sensors) {
            Ok(()) => self.stage = Stage::Sliding { since, turn },
            Err(e) => self.fail(io.now, &format!("a leg of a sliding way: {e}")),
        }
    }

    /// Backs off over the running FORWARD's sliding way: to the last place the body passed,
    /// which it leaves; `false` when there is none (the FORWARD was not slid) or the motor cannot
    /// start. A sliding way goes round what blocks the straight one, so the straight way back
    /// to the cell's centre would cross it: the way back is the way the body came, space it has
    /// just swept.
    pub(super) fn retrace_slide(&mut self, io: &mut Io<'_>) -> bool {
        let Some((along, left)) = self.sliding.visited.pop() else { return false };
        let off = io.motor.odometry().offset();
        match io.motor.start_shift(io.now, along - off.along_m, left - off.left_m, io.sensors) {
            Ok(()) => true,
            Err(e) => {
                tracing::warn!(error = %e, "cannot back off over the sliding way");
                self.sliding.visited.clear();
                false
            }
        }
    }

    /// Follows a leg of the sliding way that started at `since`, before the turn `turn` or else
    /// a FORWARD; `false` while it runs.
    pub(super) fn poll_slide(&mut self, io: &mut Io<'_>, since: Instant, turn: Option<Move>) -> bool {
        if io.sensors.bumper_pressed_since(since) {
            self.sliding.legs.clear();
            match turn {
                Some(_) => {
                    io.motor.stop(io.now);
                    self.place.touched();
                    self.fail(io.now, "the bumper, sliding to where a turn can be made");
                }
                None => self.bumped(io),
            }
            return true;
        }
        match io.motor.take_outcome() {
            None if io.motor.is_busy() => false,
            None | Some(Ok(())) => {
                if turn.is_none() {
                    let off = io.motor.odometry().offset();
                    self.sliding.visited.push((off.along_m, off.left_m));
                }
                self.next_leg(io, since, turn);
                true
            }
            Some(Err(e)) => {
                self.sliding.legs.clear();
                match turn {
                    // as after the old shift before a turn: turn if the circle clears from here
                    Some(mv) => self.turn_after_failed_shift(io, mv, &e.to_string()),
                    None => {
                        self.echoes.forget_moving();
                        self.fail(io.now, &format!("a leg of a sliding way failed: {e}"));
                    }
                }
                true
            }
        }
    }
}
