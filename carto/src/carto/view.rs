//! What Carto shows of itself, read-only: the belief, the evidence grid and its uncertainty,
//! the echo points, the activity, a status snapshot and the counters. Nothing here changes
//! Carto's state.

use robot_model::grid::GridPose;
use robot_model::time::Instant;

use super::{Belief, Carto, CartoStats, CartoStatus};
use crate::estimate::grid::EvidenceGrid;
#[cfg(doc)]
use crate::pilot::Pilot;

impl Carto {
    /// Where Carto believes the robot is: the stored pose and the dead-reckoned offset from that
    /// cell's centre (the `pose` and `cell_offset` of [`Carto::status`], without building the
    /// whole snapshot). `None` until a pose is stored.
    pub fn believed_pose(&self) -> Option<(GridPose, crate::odometry::CellOffset)> {
        self.pilot.pose().map(|pose| (pose, self.motor.odometry().offset()))
    }

    /// Carto's belief of the robot's pose at `now` ([`Belief`]): what it would act on if it
    /// moved now. Read-only; `None` until a pose is stored.
    pub fn belief(&self, now: Instant) -> Option<Belief> {
        let pose = self.pilot.pose()?;
        Some(Belief {
            pose,
            offset: self.motor.cell_offset(now, &self.sensors),
            off_heading_deg: self
                .sensors
                .predicted_yaw(now, self.motor.config())
                .zip(self.motor.reference_deg())
                .map_or(0.0, |(yaw, reference)| yaw - reference),
        })
    }

    /// Every echo point the safety checks hold now, in the grid's metric frame
    /// ([`crate::surroundings`]; the floor plan's not included).
    pub fn echo_points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.pilot.echo_points()
    }

    /// Carto's evidence grid, in the grid's metric frame ([`Pilot::evidence`]): what map.png,
    /// the window and the MCAP output draw as Carto's map.
    pub fn evidence(&self) -> &EvidenceGrid {
        self.pilot.evidence()
    }

    /// The covariance of the believed position, m², in the grid's metric frame; `None` before
    /// the first reading ([`Pilot::position_covariance`]).
    pub fn position_covariance(&self) -> Option<[[f64; 2]; 2]> {
        self.pilot.position_covariance()
    }

    /// What the pilot is doing now ([`Pilot::activity`]).
    pub fn activity(&self) -> crate::pilot::Activity {
        self.pilot.activity()
    }

    /// A snapshot of the state.
    pub fn status(&self) -> CartoStatus {
        CartoStatus {
            pose: self.pilot.pose(),
            busy: self.pilot.is_busy(),
            pending: self.pilot.pending(),
            client: self.peer.clone(),
            sensor_board_ok: self.health().sensor_board,
            motor_board_ok: self.motor_link_up,
            command: self.motor.command(),
            yaw_deg: self.sensors.yaw_deg().map(|y| y.value),
            distance_cm: self.ultrasound.latest().map(|d| d.value),
            cell_offset: self.motor.odometry().offset(),
            imu_drift_deg: self.sensors.imu_drift_deg(),
            coast_bias_m: self.motor.coast_bias_m(),
        }
    }

    /// The counters.
    pub fn stats(&self) -> CartoStats {
        CartoStats {
            pilot: self.pilot.counters(),
            heading_jumps: self.sensors.imu_drift_jumps(),
            push_jumps: self.sensors.drift_counts().pushes,
            ..self.stats
        }
    }
}
