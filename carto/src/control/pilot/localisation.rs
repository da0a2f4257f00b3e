//! Where Carto believes the robot is: the pose Cute sent (the stored grid pose), the localiser
//! that corrects the odometry from straight readings at rest, and what the corrections and the
//! shifts before a turn need to remember (the last straight reading, the way the body came).
//!
//! Invariants: the stored pose changes only by [`Localisation::set_pose`] (a
//! `SEND_ROBOT_POSITION`), [`Localisation::move_made`] (a completed move) and
//! [`Localisation::unmake_turn`] (a turn taken back before its `MOVE_DONE`); a new pose forgets
//! the localiser's surfaces, the last straight reading and the way the body came.

use robot_model::grid::{GridPose, Heading, Move};
use robot_model::time::Instant;

use super::Io;
use crate::CartoConfig;
use crate::estimate::localiser::Localiser;
use crate::estimate::sonar::Reading;
use crate::odometry::CellOffset;
use crate::surroundings::Pose2;

/// The belief's standard deviation across the heading above which, with a floor plan, Carto
/// looks aside before a FORWARD (`pilot/safety.rs`, "Looking aside"): a third of the 5 cm a
/// run's belief may be off (`RobotProfile`'s `belief_error_max_m`), so the error stays inside it
/// at 3 σ.
pub(super) const LOOK_ASIDE_SIGMA_M: f64 = 0.05 / 3.0;

/// A grid heading as a counter-clockwise angle from east, degrees.
pub(super) fn heading_deg(h: Heading) -> f64 {
    match h {
        Heading::East => 0.0,
        Heading::North => 90.0,
        Heading::West => 180.0,
        Heading::South => -90.0,
    }
}

/// A straight reading at rest, remembered as the stall watch's first echo.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Straight {
    pose: GridPose,
    range_m: f64,
}

/// The stored pose and the belief around it.
#[derive(Debug, Clone)]
pub(super) struct Localisation {
    pose: Option<GridPose>,
    /// The last straight reading at rest, for the along-track fix of the next one.
    last_straight: Option<Straight>,
    /// Surfaces seen straight ahead, for the absolute along-track fix.
    localiser: Localiser,
    /// The heading of the last FORWARD made from the stored pose (`None`: none yet): the way the
    /// body came, for the shift before a turn (`pilot/safety.rs`, "Turns").
    travel: Option<Heading>,
    /// A cell's side, metres.
    cell_m: f64,
}

impl Localisation {
    /// No pose yet.
    pub(super) fn new(cfg: &CartoConfig) -> Localisation {
        Localisation {
            pose: None,
            last_straight: None,
            localiser: Localiser::new(cfg),
            travel: None,
            cell_m: cfg.cell_size_m,
        }
    }

    /// The stored pose, if Cute sent one.
    pub(super) fn pose(&self) -> Option<GridPose> {
        self.pose
    }

    /// The stored cell's centre, facing the stored grid heading, in the grid's metric frame.
    pub(super) fn cell_frame(&self) -> Option<Pose2> {
        let GridPose { x: row, y: col, heading } = self.pose?;
        Some(Pose2 {
            x: f64::from(col) * self.cell_m,
            y: -f64::from(row) * self.cell_m,
            yaw_deg: heading_deg(heading),
        })
    }

    /// The localiser: its grid and its filter.
    pub(super) fn localiser(&self) -> &Localiser {
        &self.localiser
    }

    /// The cell ahead of the stored pose, when there is one.
    pub(super) fn cell_ahead(&self) -> Option<(u8, u8)> {
        self.pose.and_then(|p| p.ahead())
    }

    /// Known surface points for the localiser ([`crate::Carto::add_known_surfaces`]).
    pub(super) fn pin(&mut self, points: impl IntoIterator<Item = (f64, f64)>) {
        self.localiser.pin(points);
    }

    /// Stores the pose Cute sent. Whether it differs from the one held: then the localiser's
    /// surfaces, the last straight reading and the way the body came are forgotten.
    pub(super) fn set_pose(&mut self, pose: GridPose) -> bool {
        let new = self.pose != Some(pose);
        if new {
            self.last_straight = None;
            self.localiser.reset();
            self.travel = None;
        }
        self.pose = Some(pose);
        new
    }

    /// The move `kind` succeeded: the stored pose follows it. The new pose and, for a FORWARD,
    /// the cell it entered; `None` without a pose.
    pub(super) fn move_made(&mut self, kind: Move) -> Option<(GridPose, Option<(u8, u8)>)> {
        let pose = self.pose.as_mut()?;
        let mut entered = None;
        match kind {
            Move::Forward => {
                self.travel = Some(pose.heading);
                if let Some((x, y)) = pose.ahead() {
                    pose.x = x;
                    pose.y = y;
                    entered = Some((x, y));
                }
            }
            Move::Right => pose.heading = pose.heading.right(),
            Move::Left => pose.heading = pose.heading.left(),
        }
        Some((*pose, entered))
    }

    /// Takes back the turn `turn` in the stored heading; the pose after, `None` without one.
    pub(super) fn unmake_turn(&mut self, turn: Move) -> Option<GridPose> {
        let pose = self.pose.as_mut()?;
        pose.heading = if turn == Move::Left { pose.heading.right() } else { pose.heading.left() };
        Some(*pose)
    }

    /// A STOP, a disconnect or a lost link: the last reading no longer follows from the next.
    pub(super) fn forget_last_reading(&mut self) {
        self.last_straight = None;
        self.localiser.forget_last_reading();
    }

    /// A bump, a push or a stall: the belief widens (`pilot/safety.rs`, "Belief").
    pub(super) fn touched(&mut self) {
        self.localiser.touched();
    }

    /// A reading heard from `robot` while turning, for the localiser's surfaces.
    pub(super) fn learn(&mut self, robot: Pose2, reading: Reading) {
        self.localiser.learn(robot, reading);
    }

    /// The straight reading at rest last taken, metres, when it was taken from the stored pose.
    pub(super) fn straight_range_m(&self) -> Option<f64> {
        self.last_straight.filter(|s| Some(s.pose) == self.pose).map(|s| s.range_m)
    }

    /// How far the last FORWARD's heading lies counter-clockwise of the stored heading, degrees
    /// (0 without either).
    pub(super) fn travel_turned_deg(&self) -> f64 {
        match (self.pose, self.travel) {
            (Some(pose), Some(travel)) => heading_deg(travel) - heading_deg(pose.heading),
            _ => 0.0,
        }
    }

    /// Where Carto believes the robot is, in the frame of [`crate::surroundings`]: the stored
    /// cell's centre, plus the odometry's offset, facing the grid heading plus the IMU's offset
    /// from the reference heading. `None` without a pose from Cute.
    pub(super) fn believed(&self, io: &Io<'_>) -> Option<Pose2> {
        self.believed_with(io, io.motor.odometry().offset())
    }

    /// [`Self::believed`] with the odometry's offset `off` from the stored cell's centre (carried
    /// to another moment).
    pub(super) fn believed_with(&self, io: &Io<'_>, off: CellOffset) -> Option<Pose2> {
        let centre = self.cell_frame()?;
        let (x, y) = centre.offset(off.along_m, off.left_m);
        let turned = match (io.motor.reference_deg(), io.sensors.yaw_deg()) {
            (Some(reference), Some(yaw)) => yaw.value - reference,
            _ => 0.0,
        };
        Some(Pose2 { x, y, yaw_deg: centre.yaw_deg + turned })
    }

    /// Corrects the belief from the straight reading `cm` taken at rest now (`pilot/safety.rs`,
    /// "Belief"): the localiser's correction moves the odometry, and the reading is remembered
    /// for the stall watch. Whether the belief was corrected.
    pub(super) fn at_rest(&mut self, io: &mut Io<'_>, cm: Option<f32>) -> bool {
        let (Some(pose), Some(robot)) = (self.pose, self.believed(io)) else {
            self.last_straight = None;
            return false;
        };
        let reading = cm.map_or(Reading::NoEcho, |cm| Reading::Echo(f64::from(cm) / 100.0));
        let fix = self.localiser.at_rest(io.now, pose, robot, reading);
        self.last_straight = cm.map(|cm| Straight { pose, range_m: f64::from(cm) / 100.0 });
        correct_odometry(io, pose, fix)
    }

    /// Whether a look aside is due at `now` before the next FORWARD from `robot`, the believed
    /// pose (`pilot/safety.rs`, "Looking aside"): a floor plan is given and the belief's
    /// standard deviation across the heading exceeds [`LOOK_ASIDE_SIGMA_M`].
    pub(super) fn wants_look_aside(&self, now: Instant, robot: Pose2) -> bool {
        self.localiser.has_plan()
            && self.localiser.sigma_across_m(now, robot).is_some_and(|sigma| sigma > LOOK_ASIDE_SIGMA_M)
    }

    /// Corrects the belief from the reading `cm` taken at rest looking aside (the body turned off
    /// the grid heading): against the floor plan only. Whether the belief was corrected.
    pub(super) fn at_look(&mut self, io: &mut Io<'_>, cm: Option<f32>) -> bool {
        let (Some(pose), Some(robot)) = (self.pose, self.believed(io)) else { return false };
        let reading = cm.map_or(Reading::NoEcho, |cm| Reading::Echo(f64::from(cm) / 100.0));
        let fix = self.localiser.at_look(io.now, robot, reading);
        correct_odometry(io, pose, fix)
    }
}

/// Moves the odometry by the localiser's correction `(dx, dy)` (Carto's frame) into the nominal
/// frame of `pose`, in which its offset is kept. Whether there was a correction.
fn correct_odometry(io: &mut Io<'_>, pose: GridPose, (dx, dy): (f64, f64)) -> bool {
    if dx == 0.0 && dy == 0.0 {
        return false;
    }
    let (sin, cos) = heading_deg(pose.heading).to_radians().sin_cos();
    let fix = CellOffset { along_m: dx * cos + dy * sin, left_m: -dx * sin + dy * cos };
    tracing::debug!(fix.along_m, fix.left_m, "belief corrected from a range at rest");
    io.motor.correct_offset(fix);
    true
}
