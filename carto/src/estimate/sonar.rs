//! The sonar's inverse sensor model: how one reading changes the [`EvidenceGrid`] (style rule
//! 16; Nav2's range-sensor layer updates its grid the same way).
//!
//! Contract, for a reading taken from `sensor` (the sonar's own pose: its position and the axis
//! of its cone) and every cell whose centre lies in the cone (within the half angle, with half a
//! cell of slack):
//! - **An echo at range `r`** says the nearest surface that faces the sonar lies somewhere on
//!   the arc at `r`. Cells nearer than `r − band` are free evidence; cells within `±band` of `r`
//!   are occupied evidence, shared over the arc: an arc of `n` cells gives each
//!   `min(1, SonarModel::sharp_arc_cells / n)` of it, so a close echo (a narrow arc) marks hard
//!   and a far one (a wide arc) marks softly until other readings agree. Cells beyond say
//!   nothing. `band` is the range quantisation's half step or two σ of the range noise,
//!   whichever is larger, plus half a cell.
//! - **No echo** is weak free evidence up to [`SonarModel::no_echo_reach_m`]: a surface turned
//!   past the incidence limit returns nothing, so silence does not prove the space empty; an echo
//!   under the sonar's minimum range reads as no echo too, so the cells nearer than it get none.
//! - Every amount is weighted by `1 − (sin φ / sin α)²` for a cell whose point nearest the axis
//!   is `φ` off the axis of a cone of half angle `α`: the edges of the cone are where a glancing surface stays silent and where an
//!   echo is least likely to come from.
//!
//! ```
//! use carto::estimate::grid::{EvidenceGrid, GridParams, Occupancy};
//! use carto::estimate::sonar::{Reading, SonarModel};
//! use carto::surroundings::Pose2;
//! let (mut grid, model) = (EvidenceGrid::new(GridParams::default()), SonarModel::default());
//! let sonar = Pose2 { x: 0.0, y: 0.0, yaw_deg: 0.0 };
//! for _ in 0..3 {
//!     model.update(&mut grid, sonar, Reading::Echo(0.6)); // a wall 60 cm ahead
//! }
//! assert_eq!(grid.cell(grid.cell_of(0.3, 0.0)), Occupancy::Free);
//! assert_eq!(grid.cell(grid.cell_of(0.6, 0.0)), Occupancy::Occupied);
//! assert_eq!(grid.cell(grid.cell_of(0.9, 0.0)), Occupancy::Unknown);
//! ```

use super::grid::EvidenceGrid;
use crate::CartoConfig;
use crate::surroundings::Pose2;

/// One sonar reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reading {
    /// An echo at this range, metres.
    Echo(f64),
    /// No echo within the sonar's range.
    NoEcho,
}

/// The sonar's geometry and how much evidence a reading carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SonarModel {
    /// Half the cone's width, degrees.
    pub cone_half_deg: f64,
    /// Shortest echo the sonar reports, metres.
    pub min_range_m: f64,
    /// Longest echo the sonar reports, metres.
    pub max_range_m: f64,
    /// Standard deviation of the range, metres.
    pub range_sigma_m: f64,
    /// Step of the reported range, metres.
    pub quantisation_m: f64,
    /// Free evidence of an echo for a cell on the axis nearer than the echo, log-odds.
    pub free_log_odds: f64,
    /// Occupied evidence of an echo for a cell on the axis on a sharp arc, log-odds.
    pub occupied_log_odds: f64,
    /// An arc this many cells wide (or narrower) gets the whole occupied evidence.
    pub sharp_arc_cells: f64,
    /// Free evidence of a reading with no echo, on the axis, log-odds.
    pub no_echo_free_log_odds: f64,
    /// How far a reading with no echo gives free evidence, metres.
    pub no_echo_reach_m: f64,
}

impl Default for SonarModel {
    /// The HC-SR04 of the default robot: a 15° cone, 2 cm to 4 m, 3 mm σ, 1 cm steps.
    fn default() -> Self {
        SonarModel {
            cone_half_deg: 7.5,
            min_range_m: 0.02,
            max_range_m: 4.0,
            range_sigma_m: 0.003,
            quantisation_m: 0.01,
            free_log_odds: 0.4,
            occupied_log_odds: 1.2,
            sharp_arc_cells: 3.0,
            no_echo_free_log_odds: 0.05,
            no_echo_reach_m: 1.5,
        }
    }
}

impl SonarModel {
    /// The model of the sonar Carto's configuration describes.
    pub fn from_config(cfg: &CartoConfig) -> Self {
        SonarModel {
            cone_half_deg: cfg.sonar.cone_deg / 2.0,
            max_range_m: cfg.sonar.max_m,
            range_sigma_m: cfg.sonar.sigma_m,
            no_echo_reach_m: SonarModel::default().no_echo_reach_m.min(cfg.sonar.max_m),
            ..SonarModel::default()
        }
    }

    /// Half the width of the band round an echo's range that gets occupied evidence, metres.
    pub fn band_m(&self, resolution_m: f64) -> f64 {
        (self.quantisation_m / 2.0).max(2.0 * self.range_sigma_m) + resolution_m / 2.0
    }

    /// Adds one reading, taken from `sensor`, to the grid (see the module docs).
    pub fn update(&self, grid: &mut EvidenceGrid, sensor: Pose2, reading: Reading) {
        let cone = Cone::new(self, grid.params().resolution_m, sensor, reading);
        let rows = cone_rows(grid, sensor, cone.reach, cone.alpha);
        grid.update_rows(&rows, |p| cone.evidence(p));
    }
}

/// One reading's evidence, ready to be asked cell by cell.
#[derive(Debug, Clone, Copy)]
struct Cone {
    model: SonarModel,
    sensor: Pose2,
    sin: f64,
    cos: f64,
    alpha: f64,
    tan_alpha: f64,
    sin_alpha: f64,
    half_cell: f64,
    band: f64,
    reach: f64,
    echo: Option<f64>,
    occupied_share: f64,
}

impl Cone {
    fn new(model: &SonarModel, res: f64, sensor: Pose2, reading: Reading) -> Self {
        let band = model.band_m(res);
        let (reach, echo) = match reading {
            Reading::Echo(r) if r.is_finite() && r >= model.min_range_m && r <= model.max_range_m => {
                (r + band, Some(r))
            }
            _ => (model.no_echo_reach_m, None),
        };
        let alpha = model.cone_half_deg.to_radians().clamp(1e-6, 1.5);
        let occupied_share = echo.map_or(0.0, |r| {
            let arc_cells = (2.0 * r * alpha.tan() / res).max(1.0);
            (model.sharp_arc_cells / arc_cells).min(1.0)
        });
        let (sin, cos) = sensor.yaw_deg.to_radians().sin_cos();
        Cone {
            model: *model,
            sensor,
            sin,
            cos,
            alpha,
            tan_alpha: alpha.tan(),
            sin_alpha: alpha.sin(),
            half_cell: res / 2.0,
            band,
            reach,
            echo,
            occupied_share,
        }
    }

    /// The evidence for the cell centred on `(x, y)`, log-odds (0 outside the cone).
    fn evidence(&self, (x, y): (f64, f64)) -> f64 {
        let (dx, dy) = (x - self.sensor.x, y - self.sensor.y);
        let along = dx * self.cos + dy * self.sin;
        let across = (dy * self.cos - dx * self.sin).abs();
        // In the cone, with half a cell of slack: a cell whose centre is just outside still
        // overlaps it.
        if along <= 0.0 || across > along * self.tan_alpha + self.half_cell {
            return 0.0;
        }
        let d = (dx * dx + dy * dy).sqrt();
        if d > self.reach || d < self.half_cell {
            return 0.0;
        }
        // The weight falls with the square of the sine of the angle off the axis, taken at the
        // cell's point nearest the axis (close to the sensor the cone is narrower than a cell).
        let w = 1.0 - ((across - self.half_cell).max(0.0) / d / self.sin_alpha).min(1.0).powi(2);
        let m = &self.model;
        match self.echo {
            Some(r) if d < r - self.band => -m.free_log_odds * w,
            Some(_) => m.occupied_log_odds * self.occupied_share * w,
            None if d >= m.min_range_m => -m.no_echo_free_log_odds * w,
            None => 0.0,
        }
    }
}

/// The rows of cells that may hold part of the cone, each as `(j, i0, i1)`: the polygon of the
/// sensor and five points on the arc at `reach` (whose chords cut the arc by at most
/// `reach·(1 − cos(α/4))`, 2 mm at 4 m for a 15° cone), grown by a cell, cut by each row's line.
fn cone_rows(grid: &EvidenceGrid, sensor: Pose2, reach: f64, alpha: f64) -> Vec<(i32, i32, i32)> {
    let res = grid.params().resolution_m;
    let yaw = sensor.yaw_deg.to_radians();
    let mut poly = vec![(sensor.x, sensor.y)];
    poly.extend((0..5).map(|k| {
        let a = yaw - alpha + alpha * f64::from(k) / 2.0;
        (sensor.x + reach * a.cos(), sensor.y + reach * a.sin())
    }));
    let grow = res + reach * (1.0 - (alpha / 4.0).cos());
    let (y_lo, y_hi) =
        poly.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let (j0, j1) = (grid.cell_of(0.0, y_lo - grow).1, grid.cell_of(0.0, y_hi + grow).1);
    let mut rows = Vec::with_capacity((j1 - j0 + 1).max(0) as usize);
    for j in j0..=j1 {
        // The row's band of y, grown: where the polygon's edges cross it.
        let (band_lo, band_hi) = (f64::from(j) * res - grow, f64::from(j + 1) * res + grow);
        let (mut x_lo, mut x_hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            // The part of edge a-b inside the band, by its two ends' parameters.
            let (ya, yb) = (a.1, b.1);
            let (t0, t1) = if (yb - ya).abs() < 1e-12 {
                if ya < band_lo || ya > band_hi { continue } else { (0.0, 1.0) }
            } else {
                let (u, v) = ((band_lo - ya) / (yb - ya), (band_hi - ya) / (yb - ya));
                (u.min(v).max(0.0), u.max(v).min(1.0))
            };
            if t0 > t1 {
                continue;
            }
            for t in [t0, t1] {
                let x = a.0 + t * (b.0 - a.0);
                x_lo = x_lo.min(x);
                x_hi = x_hi.max(x);
            }
        }
        if x_lo <= x_hi {
            rows.push((j, grid.cell_of(x_lo - grow, 0.0).0, grid.cell_of(x_hi + grow, 0.0).0));
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::super::grid::{GridParams, Occupancy};
    use super::*;

    fn setup() -> (EvidenceGrid, SonarModel, Pose2) {
        (
            EvidenceGrid::new(GridParams::default()),
            SonarModel::default(),
            Pose2 { x: 1.0, y: 2.0, yaw_deg: 90.0 },
        )
    }

    #[test]
    fn an_echo_clears_before_it_marks_on_it_and_says_nothing_beyond() {
        let (mut g, m, s) = setup();
        // A 26 cm arc at 1 m: each reading gives a cell on it a quarter of a sharp echo's
        // evidence, so it takes four to agree.
        for _ in 0..3 {
            m.update(&mut g, s, Reading::Echo(1.0));
        }
        assert_eq!(g.cell(g.cell_of(1.0, 3.0)), Occupancy::Unknown);
        m.update(&mut g, s, Reading::Echo(1.0));
        assert_eq!(g.cell(g.cell_of(1.0, 2.5)), Occupancy::Free);
        assert_eq!(g.cell(g.cell_of(1.0, 3.0)), Occupancy::Occupied);
        assert_eq!(g.cell(g.cell_of(1.0, 3.2)), Occupancy::Unknown);
        // Outside the 15° cone (10° off the axis at 0.8 m) nothing is said.
        let off = (1.0 - 0.8 * 10f64.to_radians().sin(), 2.0 + 0.8 * 10f64.to_radians().cos());
        assert_eq!(g.log_odds(g.cell_of(off.0, off.1)), 0.0);
    }

    #[test]
    fn a_close_echo_marks_at_once_a_far_one_softly() {
        let (mut g, m, s) = setup();
        m.update(&mut g, s, Reading::Echo(0.2));
        assert_eq!(g.cell(g.cell_of(1.0, 2.2)), Occupancy::Occupied, "a 5 cm arc: one reading");
        // Closer than a cone as wide as a cell, the cell on the axis still gets it.
        m.update(&mut g, Pose2 { x: 0.0, y: 0.0, yaw_deg: 30.0 }, Reading::Echo(0.06));
        let (x, y) = (0.06 * 30f64.to_radians().cos(), 0.06 * 30f64.to_radians().sin());
        assert_eq!(g.cell(g.cell_of(x, y)), Occupancy::Occupied);
        m.update(&mut g, s, Reading::Echo(2.5));
        let far = g.log_odds(g.cell_of(1.0, 4.5));
        assert!(far > 0.0 && far < 0.85, "a 66 cm arc shares the evidence: {far}");
    }

    #[test]
    fn no_echo_is_weak_evidence_and_never_clears_a_close_echo_at_once() {
        let (mut g, m, s) = setup();
        for _ in 0..2 {
            m.update(&mut g, s, Reading::Echo(0.3));
        }
        let c = g.cell_of(1.0, 2.3);
        assert_eq!(g.cell(c), Occupancy::Occupied);
        for _ in 0..3 {
            m.update(&mut g, s, Reading::NoEcho);
        }
        assert_eq!(g.cell(c), Occupancy::Occupied, "{}", g.log_odds(c));
        assert!(g.log_odds(g.cell_of(1.0, 3.0)) < 0.0);
        assert_eq!(g.log_odds(g.cell_of(1.0, 2.0 + 1.6)), 0.0, "beyond the reach of silence");
        // An echo the sonar cannot report (under its minimum or beyond its maximum) is silence.
        let (mut h, _, _) = setup();
        m.update(&mut h, s, Reading::Echo(9.0));
        assert!(h.log_odds(h.cell_of(1.0, 3.0)) < 0.0);
        assert_eq!(h.log_odds(h.cell_of(1.0, 2.0 + 1.6)), 0.0);
    }

    #[test]
    fn the_edges_of_the_cone_get_less_than_its_axis() {
        let (mut g, m, s) = setup();
        m.update(&mut g, s, Reading::Echo(1.5));
        let axis = g.log_odds(g.cell_of(1.0, 2.8));
        let a = 6.5f64.to_radians();
        let edge = g.log_odds(g.cell_of(1.0 - 0.8 * a.sin(), 2.0 + 0.8 * a.cos()));
        assert!(axis < edge && edge < 0.0, "axis {axis}, edge {edge}");
    }

    /// The rows the update visits hold every cell of the cone: the same readings through a box
    /// round the whole cone leave the same grid.
    #[test]
    fn the_rows_visited_hold_every_cell_of_the_cone() {
        let m = SonarModel::default();
        for (k, reading) in [Reading::Echo(0.05), Reading::Echo(0.7), Reading::Echo(3.9), Reading::NoEcho]
            .into_iter()
            .enumerate()
        {
            for yaw in [0.0, 7.0, 44.0, 90.0, 133.0, 180.0, -101.0, -1.0] {
                let sensor = Pose2 { x: -0.37 + k as f64, y: 0.11, yaw_deg: yaw };
                let mut rows = EvidenceGrid::new(GridParams::default());
                m.update(&mut rows, sensor, reading);
                let mut boxed = EvidenceGrid::new(GridParams::default());
                let cone = Cone::new(&m, 0.02, sensor, reading);
                let (lo, hi) = (
                    boxed.cell_of(sensor.x - 4.2, sensor.y - 4.2),
                    boxed.cell_of(sensor.x + 4.2, sensor.y + 4.2),
                );
                boxed.update_box(lo, hi, |p| cone.evidence(p));
                assert_eq!(rows.written_cells(), boxed.written_cells(), "{reading:?} at {yaw} deg");
                assert!(!rows.written_cells().is_empty(), "{reading:?} at {yaw} deg: nothing written");
            }
        }
    }

    #[test]
    fn readings_from_the_other_side_clear_a_soft_mark() {
        let (mut g, m, s) = setup();
        m.update(&mut g, s, Reading::Echo(2.0));
        let c = g.cell_of(1.0, 4.0);
        assert!(g.log_odds(c) > 0.0);
        // A robot farther on, looking back, sees past it to a wall 3 m away.
        let back = Pose2 { x: 1.0, y: 5.0, yaw_deg: -90.0 };
        for _ in 0..3 {
            m.update(&mut g, back, Reading::Echo(3.0));
        }
        assert_eq!(g.cell(c), Occupancy::Free);
    }
}
