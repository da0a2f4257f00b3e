//! Carto's own map and belief in world metres, beside the truth: what `map.png`, the window's
//! "Carto's map" layer and the MCAP channels `/carto/grid` and `/carto/belief` draw.
//!
//! - [`CartoMap`]: every cell of Carto's evidence grid ([`carto::estimate::grid`]) that holds
//!   evidence, with what the grid makes of it (free, occupied, or not yet either), at the cell's
//!   centre in the world.
//! - [`BeliefEllipse`]: where Carto believes the robot is (the pose it would act on now) and the
//!   2σ ellipse of its position filter's covariance, world metres.
//!
//! Carto's metric frame has its origin at the centre of cell (0, 0) and its axes along the
//! world's ([`crate::oracle::to_carto_frame`]); a picture of Carto's grid therefore sits on the
//! true room exactly where Carto believes its evidence lies, and where it leaves the true
//! surfaces Carto's map is wrong.
//!
//! ```
//! use twin::carto_map::BeliefEllipse;
//! // σ 2 cm east-west, 1 cm north-south: the 2σ ellipse's half axes are 4 and 2 cm
//! let e = BeliefEllipse::from_covariance((1.0, 2.0, 0.0), [[4e-4, 0.0], [0.0, 1e-4]]);
//! assert!((e.half_axes.0 - 0.04).abs() < 1e-6 && (e.half_axes.1 - 0.02).abs() < 1e-6);
//! assert!(e.angle.abs() < 1e-6);
//! ```

use carto::Carto;
pub use carto::estimate::grid::Occupancy;
use robot_model::time::Instant;

use crate::grid::GridFrame;
use crate::localisation::carto_belief;

/// Carto's evidence grid in world metres.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CartoMap {
    /// Side of a cell, metres.
    pub cell_m: f32,
    /// Every cell that holds evidence: its centre (world metres) and what the grid says of it,
    /// in a fixed order.
    pub cells: Vec<((f32, f32), Occupancy)>,
}

impl CartoMap {
    /// Carto's grid as it stands, laid on the world through the grid frame `frame`.
    pub fn of(carto: &Carto, frame: &GridFrame) -> CartoMap {
        let grid = carto.evidence();
        let (ox, oy) = frame.cell_center(0, 0);
        let cells = grid
            .written_cells()
            .into_iter()
            .map(|(c, occupancy)| {
                let (x, y) = grid.centre(c);
                ((ox + x as f32, oy + y as f32), occupancy)
            })
            .collect();
        CartoMap { cell_m: grid.params().resolution_m as f32, cells }
    }

    /// The cells the grid calls `occupancy`.
    pub fn cells_that_are(&self, occupancy: Occupancy) -> impl Iterator<Item = (f32, f32)> + '_ {
        self.cells.iter().filter(move |(_, o)| *o == occupancy).map(|(p, _)| *p)
    }
}

/// Carto's believed pose and the 2σ ellipse of its position, world metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeliefEllipse {
    /// Believed position and heading: x, y (metres), heading (radians counter-clockwise).
    pub pose: (f32, f32, f32),
    /// Half axes of the 2σ ellipse, metres, the larger first.
    pub half_axes: (f32, f32),
    /// Direction of the larger axis, radians counter-clockwise from east.
    pub angle: f32,
}

impl BeliefEllipse {
    /// Carto's belief at `now`: the pose it would act on and its filter's covariance. `None`
    /// before Carto stores a pose or takes its first reading.
    pub fn of(carto: &Carto, frame: &GridFrame, now: Instant) -> Option<BeliefEllipse> {
        let belief = carto.belief(now)?;
        let (x, y) = carto_belief(frame, belief.pose, belief.offset)?;
        let heading = belief.pose.heading.world_angle() + (belief.off_heading_deg as f32).to_radians();
        Some(BeliefEllipse::from_covariance((x, y, heading), carto.position_covariance()?))
    }

    /// The ellipse of the covariance `p` (m², `[[xx, xy], [xy, yy]]`) around `pose`.
    pub fn from_covariance(pose: (f32, f32, f32), p: [[f64; 2]; 2]) -> BeliefEllipse {
        let (a, b, c) = (p[0][0], 0.5 * (p[0][1] + p[1][0]), p[1][1]);
        let mid = 0.5 * (a + c);
        let spread = (0.25 * (a - c).powi(2) + b * b).sqrt();
        let sigma = |lambda: f64| lambda.max(0.0).sqrt();
        BeliefEllipse {
            pose,
            half_axes: ((2.0 * sigma(mid + spread)) as f32, (2.0 * sigma(mid - spread)) as f32),
            angle: (0.5 * (2.0 * b).atan2(a - c)) as f32,
        }
    }

    /// `n` points around the ellipse, world metres.
    pub fn outline(&self, n: usize) -> Vec<(f32, f32)> {
        let (s, c) = self.angle.sin_cos();
        let (x0, y0, _) = self.pose;
        (0..n.max(3))
            .map(|k| {
                let t = std::f32::consts::TAU * k as f32 / n.max(3) as f32;
                let (u, v) = (self.half_axes.0 * t.cos(), self.half_axes.1 * t.sin());
                (x0 + c * u - s * v, y0 + s * u + c * v)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use carto::CartoConfig;

    #[test]
    fn a_correlated_covariance_tilts_the_ellipse_along_its_larger_axis() {
        // equal variances, positively correlated: the larger axis runs north-east
        let e = BeliefEllipse::from_covariance((0.0, 0.0, 0.0), [[2e-4, 1e-4], [1e-4, 2e-4]]);
        assert!((e.angle - std::f32::consts::FRAC_PI_4).abs() < 1e-5, "{}", e.angle);
        assert!((e.half_axes.0 - 2.0 * 3e-4f32.sqrt()).abs() < 1e-5);
        assert!((e.half_axes.1 - 2.0 * 1e-4f32.sqrt()).abs() < 1e-5);
        for (x, y) in e.outline(16) {
            let (u, v) = (x * e.angle.cos() + y * e.angle.sin(), -x * e.angle.sin() + y * e.angle.cos());
            let r = (u / e.half_axes.0).powi(2) + (v / e.half_axes.1).powi(2);
            assert!((r - 1.0).abs() < 1e-3, "({x}, {y}) is off the ellipse: {r}");
        }
    }

    #[test]
    fn known_surfaces_show_as_occupied_cells_where_they_are_in_the_world() {
        let frame = GridFrame::for_bounds((0.0, 0.0), (1.2, 1.2), 0.3);
        let mut carto = Carto::new(CartoConfig::default());
        // a wall point 0.63 m east and 0.9 m north of the world origin, in Carto's frame
        let world = (0.63, 0.90);
        carto.add_known_surfaces([crate::oracle::to_carto_frame(&frame, world)]);
        let map = CartoMap::of(&carto, &frame);
        let occupied: Vec<_> = map.cells_that_are(Occupancy::Occupied).collect();
        assert_eq!(occupied.len(), 1, "{occupied:?}");
        let (x, y) = occupied[0];
        assert!((x - 0.63).abs() <= map.cell_m / 2.0 + 1e-4 && (y - 0.90).abs() <= map.cell_m / 2.0 + 1e-4);
        assert!(BeliefEllipse::of(&carto, &frame, Instant::ZERO).is_none(), "no pose stored yet");
    }
}
