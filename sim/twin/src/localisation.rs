//! How far Cute's belief is from where the robot really is (information; runs are judged on
//! Carto's own belief, [`crate::belief`]).
//!
//! Cute believes the robot stands at the centre of one cell, facing one of four headings. At the
//! end of every move (each `MOVE_DONE` Cute receives) and at the end of the run, the runner
//! compares that belief with the true pose of the twin's body:
//! - the **position error** is the distance from the true robot centre to the centre of the
//!   believed cell;
//! - the **heading error** is the angle between the true heading and the believed grid heading.
//!
//! During a move the belief lags the robot by up to a cell by design (Cute learns the new cell
//! when the move is done), so the errors are sampled only at those moments. The report keeps the
//! largest of each, when and where it happened, and the number of samples.
//! `RUST_LOG=crate::localisation=trace` logs every sample: the believed cell and how far east
//! (`dx_m`) and north (`dy_m`) of its centre the robot really is.
//!
//! ```
//! use robot_model::grid::{GridFrame, Heading};
//! use robot_model::pose::Pose2;
//! use twin::localisation::Localisation;
//! let frame = GridFrame::for_bounds((0.0, 0.0), (0.9, 0.9), 0.3);
//! let mut l = Localisation::default();
//! // believed (1, 1) facing EAST; the robot is 3 cm east of that cell's centre, turned 2° left
//! l.sample(10.0, &frame, (1, 1, Heading::East), Pose2::new(0.48, 0.45, 2f32.to_radians()));
//! assert!((l.position_error_max_m - 0.03).abs() < 1e-6);
//! assert!((l.heading_error_max_deg - 2.0).abs() < 1e-4);
//! ```

use carto::odometry::CellOffset;
use robot_model::grid::{GridFrame, GridPose, Heading};
use robot_model::pose::Pose2;
use serde::Serialize;

/// Where Carto believes the robot is, world metres: the centre of the cell Carto stores, plus its
/// dead-reckoned offset from that centre (`along_m` ahead of the stored heading, `left_m` to its
/// left). `map.png` draws these points as the believed trail. `None` when the stored cell is off
/// the grid.
pub fn carto_belief(frame: &GridFrame, pose: GridPose, offset: CellOffset) -> Option<(f32, f32)> {
    let (row, col) = (usize::from(pose.x), usize::from(pose.y));
    if row >= frame.rows || col >= frame.cols {
        return None;
    }
    let (cx, cy) = frame.cell_center(row, col);
    let (sin, cos) = pose.heading.world_angle().sin_cos();
    let (along, left) = (offset.along_m as f32, offset.left_m as f32);
    Some((cx + along * cos - left * sin, cy + along * sin + left * cos))
}

/// The largest gaps between Cute's belief and the truth seen so far.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Localisation {
    /// Moments compared.
    pub samples: u64,
    /// Largest distance from the true centre to the believed cell's centre, metres.
    pub position_error_max_m: f64,
    /// Sim time of that largest distance, seconds.
    pub position_error_at_s: f64,
    /// Largest angle between the true and the believed heading, degrees.
    pub heading_error_max_deg: f64,
    /// Sim time of that largest angle, seconds.
    pub heading_error_at_s: f64,
}

impl Localisation {
    /// Compares Cute's belief `(row, col, heading)` with the true `pose` at sim time `t_s`.
    pub fn sample(&mut self, t_s: f64, frame: &GridFrame, believed: (u8, u8, Heading), pose: Pose2) {
        let (row, col, heading) = believed;
        let (cx, cy) = frame.cell_center(usize::from(row), usize::from(col));
        let position = f64::from((pose.x - cx).hypot(pose.y - cy));
        let heading_error =
            angle_between(f64::from(pose.theta), f64::from(heading.world_angle())).to_degrees();
        self.samples += 1;
        tracing::trace!(
            t_s,
            row,
            col,
            dx_m = pose.x - cx,
            dy_m = pose.y - cy,
            heading_error,
            "belief against truth"
        );
        keep_largest(position, t_s, &mut self.position_error_max_m, &mut self.position_error_at_s);
        keep_largest(heading_error, t_s, &mut self.heading_error_max_deg, &mut self.heading_error_at_s);
    }
}

/// Keeps `value`, seen at sim time `t_s`, in `max` and its time in `at` when it is larger.
pub(crate) fn keep_largest(value: f64, t_s: f64, max: &mut f64, at: &mut f64) {
    if value > *max {
        *max = value;
        *at = t_s;
    }
}

/// The absolute angle between two directions, radians in 0..=π.
pub(crate) fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn carto_belief_is_the_cell_centre_plus_the_offset_in_the_stored_heading() {
        let frame = GridFrame::for_bounds((0.0, 0.0), (1.2, 0.9), 0.3);
        let (x, y) = frame.cell_center(1, 2);
        let offset = CellOffset { along_m: 0.10, left_m: 0.02 };
        let north = GridPose { x: 1, y: 2, heading: Heading::North };
        let (bx, by) = carto_belief(&frame, north, offset).unwrap_or_default();
        // Facing north, ahead is +y and left is −x.
        assert!((bx - (x - 0.02)).abs() < 1e-5 && (by - (y + 0.10)).abs() < 1e-5, "{bx} {by}");
        let east = GridPose { heading: Heading::East, ..north };
        let (bx, by) = carto_belief(&frame, east, offset).unwrap_or_default();
        assert!((bx - (x + 0.10)).abs() < 1e-5 && (by - (y + 0.02)).abs() < 1e-5, "{bx} {by}");
        assert_eq!(carto_belief(&frame, GridPose { x: 3, ..north }, offset), None);
    }

    #[test]
    fn the_largest_errors_are_kept_with_their_time() {
        let frame = GridFrame::for_bounds((0.0, 0.0), (1.2, 0.9), 0.3);
        let mut l = Localisation::default();
        let (x, y) = frame.cell_center(2, 3);
        l.sample(1.0, &frame, (2, 3, Heading::North), Pose2::new(x, y + 0.04, 93f32.to_radians()));
        l.sample(2.0, &frame, (2, 3, Heading::North), Pose2::new(x + 0.01, y, 89f32.to_radians()));
        assert_eq!(l.samples, 2);
        assert!((l.position_error_max_m - 0.04).abs() < 1e-6);
        assert_eq!(l.position_error_at_s, 1.0);
        assert!((l.heading_error_max_deg - 3.0).abs() < 1e-3);
    }

    #[test]
    fn heading_errors_wrap_around_the_circle() {
        assert!((angle_between(179f64.to_radians(), -179f64.to_radians()).to_degrees() - 2.0).abs() < 1e-3);
        assert!((angle_between(0.0, std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-6);
        // Believed SOUTH (−90°), truly facing −88° plus a full turn.
        let frame = GridFrame::for_bounds((0.0, 0.0), (0.3, 0.3), 0.3);
        let mut l = Localisation::default();
        let (x, y) = frame.cell_center(0, 0);
        l.sample(0.0, &frame, (0, 0, Heading::South), Pose2::new(x, y, (-88f32 + 360.0).to_radians()));
        assert!((l.heading_error_max_deg - 2.0).abs() < 1e-3);
    }

    #[test]
    fn a_wrong_cell_is_a_cell_away() {
        let frame = GridFrame::for_bounds((0.0, 0.0), (0.9, 0.9), 0.3);
        let mut l = Localisation::default();
        let (x, y) = frame.cell_center(1, 1);
        l.sample(5.0, &frame, (1, 2, Heading::East), Pose2::new(x, y, 0.0));
        assert!((l.position_error_max_m - 0.3).abs() < 1e-6);
    }
}
