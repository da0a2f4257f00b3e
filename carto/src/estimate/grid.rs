//! The evidence grid: what Carto knows of the space around the robot, as log-odds of occupancy
//! on a fine square lattice (after Moravec and Elfes; Nav2's range-sensor layer keeps the same
//! kind of grid for sonar and IR).
//!
//! Contract:
//! - **Frame.** Carto's metric frame ([`Pose2`]): `x` east, `y` north, metres. Cell `(i, j)`
//!   covers `[i·r, (i+1)·r) × [j·r, (j+1)·r)` for the resolution `r`; its centre is the cell's
//!   point for every query.
//! - **Evidence.** Each cell holds the log-odds `ln(p / (1 − p))` that it is occupied, 0 when
//!   nothing is known. Updates add evidence and clamp it to `±`[`GridParams::clamp`], so no single
//!   reading decides a cell for ever: a cell marked by one echo is cleared by a few readings that
//!   see through it, and the reverse. Marking and clearing are one update.
//! - **Pinned cells.** A cell pinned occupied ([`EvidenceGrid::pin_segment`], a floor plan given
//!   beforehand) ignores every later update.
//! - **Bounded memory.** Cells live in square tiles allocated on first write; at most
//!   [`GridParams::max_tiles`] are kept, and when a new one is needed the tile farthest from the
//!   robot goes (ties by tile index: deterministic). An unwritten cell reads as unknown.
//! - **Queries** ([`EvidenceGrid::classify_rect`], [`EvidenceGrid::classify_circle`],
//!   [`EvidenceGrid::first_occupied_in_rect`]) look at every cell whose square overlaps the shape
//!   and answer the worst: occupied if any cell is, else unknown if any cell is, else free.
//!
//! The sonar's update is in [`crate::estimate::sonar`].
//!
//! ```
//! use carto::estimate::grid::{EvidenceGrid, GridParams, Occupancy};
//! use carto::surroundings::Pose2;
//! let mut grid = EvidenceGrid::new(GridParams::default());
//! let robot = Pose2 { x: 1.0, y: 1.0, yaw_deg: 0.0 };
//! assert_eq!(grid.classify_rect(robot, 0.0, 0.3, 0.1), Occupancy::Unknown);
//! grid.clear_rect(robot, -0.15, 0.15, 0.12); // the body stands here: certainly free
//! assert_eq!(grid.classify_rect(robot, -0.1, 0.1, 0.1), Occupancy::Free);
//! grid.pin_segment((1.5, 0.0), (1.5, 2.0)); // a wall 50 cm ahead
//! assert!(grid.first_occupied_in_rect(robot, 0.0, 0.6, 0.1).is_some());
//! assert!(grid.memory_bytes() < 64 * 1024);
//! ```

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use crate::surroundings::Pose2;

/// Cells per tile side.
pub const TILE: usize = 32;
/// The stored value of a pinned cell (above every clamp).
const PINNED: i8 = i8::MAX;
/// Log-odds per stored unit: values are kept in an `i8` as `round(l / LOG_ODDS_STEP)`.
pub const LOG_ODDS_STEP: f64 = 0.05;

/// What the grid says of a cell or a shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Occupancy {
    /// Known free: evidence at or below `−`[`GridParams::free_below`].
    Free,
    /// Not enough evidence either way.
    Unknown,
    /// Known occupied: evidence at or above [`GridParams::occupied_above`], or pinned.
    Occupied,
}

/// The grid's resolution, bounds and thresholds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridParams {
    /// Side of a cell, metres.
    pub resolution_m: f64,
    /// Most tiles kept ([`TILE`]² bytes each).
    pub max_tiles: usize,
    /// Evidence is kept within `±clamp`, log-odds.
    pub clamp: f64,
    /// A cell with at least this much evidence is occupied, log-odds.
    pub occupied_above: f64,
    /// A cell with at most minus this is free, log-odds.
    pub free_below: f64,
}

impl Default for GridParams {
    /// 2 cm cells; 1,024 tiles of 32 × 32 (1 MiB, 420 m²: a 15 × 15 m room takes about 600);
    /// clamped at ±3.5 (p 0.03–0.97); occupied from p 0.70, free up to p 0.30.
    fn default() -> Self {
        GridParams { resolution_m: 0.02, max_tiles: 1024, clamp: 3.5, occupied_above: 0.85, free_below: 0.85 }
    }
}

/// A log-odds occupancy grid in tiles (see the module docs).
#[derive(Debug, Clone)]
pub struct EvidenceGrid {
    params: GridParams,
    clamp: i8,
    occupied_above: i8,
    free_below: i8,
    tiles: Tiles,
    /// Where the robot was last said to be, for eviction.
    robot: (f64, f64),
}

/// A multiplicative hasher for tile indices: the grid looks a tile up for every cell it
/// touches, and the standard hasher (built to resist hostile keys, which tile indices are not)
/// costs more than the update itself.
#[derive(Debug, Default, Clone, Copy)]
pub struct TileHasher(u64);

impl Hasher for TileHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_i32(&mut self, n: i32) {
        self.write_u64(u64::from(n as u32));
    }
    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x51_7C_C1_B7_27_22_0A_95);
    }
}

type Tiles = HashMap<(i32, i32), Box<[i8; TILE * TILE]>, BuildHasherDefault<TileHasher>>;

/// A cell's integer index.
pub type CellIndex = (i32, i32);

fn to_units(l: f64) -> i8 {
    (l / LOG_ODDS_STEP).round().clamp(-126.0, 126.0) as i8
}

impl EvidenceGrid {
    /// An empty grid: every cell unknown.
    pub fn new(params: GridParams) -> Self {
        EvidenceGrid {
            params,
            clamp: to_units(params.clamp),
            occupied_above: to_units(params.occupied_above),
            free_below: to_units(params.free_below),
            tiles: Tiles::default(),
            robot: (0.0, 0.0),
        }
    }

    /// The grid's parameters.
    pub fn params(&self) -> &GridParams {
        &self.params
    }

    /// Tells the grid where the robot is: tiles farthest from here are evicted first.
    pub fn set_robot(&mut self, x: f64, y: f64) {
        self.robot = (x, y);
    }

    /// The cell holding the point `(x, y)`.
    pub fn cell_of(&self, x: f64, y: f64) -> CellIndex {
        let r = self.params.resolution_m;
        ((x / r).floor() as i32, (y / r).floor() as i32)
    }

    /// The centre of cell `c`, metres.
    pub fn centre(&self, c: CellIndex) -> (f64, f64) {
        let r = self.params.resolution_m;
        ((f64::from(c.0) + 0.5) * r, (f64::from(c.1) + 0.5) * r)
    }

    /// The evidence in cell `c`, log-odds (0 when never written; [`f64::INFINITY`] when pinned).
    pub fn log_odds(&self, c: CellIndex) -> f64 {
        match self.raw(c) {
            PINNED => f64::INFINITY,
            v => f64::from(v) * LOG_ODDS_STEP,
        }
    }

    /// What cell `c` is.
    pub fn cell(&self, c: CellIndex) -> Occupancy {
        self.classify_raw(self.raw(c))
    }

    fn classify_raw(&self, v: i8) -> Occupancy {
        if v >= self.occupied_above {
            Occupancy::Occupied
        } else if v <= -self.free_below {
            Occupancy::Free
        } else {
            Occupancy::Unknown
        }
    }

    fn split(c: CellIndex) -> ((i32, i32), usize) {
        let t = TILE as i32;
        let tile = (c.0.div_euclid(t), c.1.div_euclid(t));
        let (u, v) = (c.0.rem_euclid(t) as usize, c.1.rem_euclid(t) as usize);
        (tile, v * TILE + u)
    }

    fn raw(&self, c: CellIndex) -> i8 {
        let (tile, i) = Self::split(c);
        self.tiles.get(&tile).map_or(0, |t| t[i])
    }

    fn slot(&mut self, c: CellIndex) -> &mut i8 {
        let (tile, i) = Self::split(c);
        &mut self.tile_mut(tile)[i]
    }

    fn tile_mut(&mut self, tile: (i32, i32)) -> &mut [i8; TILE * TILE] {
        if !self.tiles.contains_key(&tile) && self.tiles.len() >= self.params.max_tiles.max(1) {
            self.evict_one();
        }
        self.tiles.entry(tile).or_insert_with(|| Box::new([0; TILE * TILE]))
    }

    /// Drops the tile farthest from the robot (ties: the larger tile index).
    fn evict_one(&mut self) {
        let side = TILE as f64 * self.params.resolution_m;
        let (rx, ry) = self.robot;
        let far = self.tiles.keys().copied().max_by(|a, b| {
            let d = |t: &(i32, i32)| {
                let (cx, cy) = ((f64::from(t.0) + 0.5) * side, (f64::from(t.1) + 0.5) * side);
                (cx - rx).powi(2) + (cy - ry).powi(2)
            };
            d(a).total_cmp(&d(b)).then(a.cmp(b))
        });
        if let Some(t) = far {
            self.tiles.remove(&t);
        }
    }

    /// Adds `delta` log-odds to cell `c`, clamped; pinned cells do not change.
    pub fn add(&mut self, c: CellIndex, delta: f64) {
        let clamp = self.clamp;
        let d = to_units(delta);
        let v = self.slot(c);
        if *v != PINNED {
            *v = v.saturating_add(d).clamp(-clamp, clamp);
        }
    }

    /// Adds to every cell from `lo` to `hi` (inclusive, both corners) the evidence `evidence`
    /// gives for its centre, in log-odds (0: none); see [`EvidenceGrid::update_rows`].
    pub fn update_box(&mut self, lo: CellIndex, hi: CellIndex, evidence: impl FnMut((f64, f64)) -> f64) {
        let rows: Vec<(i32, i32, i32)> = (lo.1..=hi.1).map(|j| (j, lo.0, hi.0)).collect();
        self.update_rows(&rows, evidence);
    }

    /// Adds to every cell of the rows `(j, i0, i1)` (cells `(i0..=i1, j)`, rows in increasing
    /// `j`, each once) the evidence `evidence` gives for its centre, in log-odds (0: none). Tile
    /// by tile: a tile is looked up, or allocated, once, and only when one of its cells gets
    /// evidence.
    pub fn update_rows(&mut self, rows: &[(i32, i32, i32)], mut evidence: impl FnMut((f64, f64)) -> f64) {
        let t = TILE as i32;
        let mut deltas = [0i8; TILE * TILE];
        let mut start = 0;
        while start < rows.len() {
            // The rows of one tile row.
            let ty = rows[start].0.div_euclid(t);
            let end = start + rows[start..].iter().take_while(|r| r.0.div_euclid(t) == ty).count();
            let band = &rows[start..end];
            start = end;
            let (Some(min_i), Some(max_i)) = (band.iter().map(|r| r.1).min(), band.iter().map(|r| r.2).max())
            else {
                continue;
            };
            for tx in min_i.div_euclid(t)..=max_i.div_euclid(t) {
                let (x0, x1) = (tx * t, tx * t + t - 1);
                let mut any = false;
                for &(j, i0, i1) in band {
                    let row = ((j - ty * t) as usize) * TILE;
                    for i in i0.max(x0)..=i1.min(x1) {
                        let d = to_units(evidence(self.centre((i, j))));
                        deltas[row + (i - x0) as usize] = d;
                        any |= d != 0;
                    }
                }
                if !any {
                    continue;
                }
                let clamp = self.clamp;
                let tile = self.tile_mut((tx, ty));
                for &(j, i0, i1) in band {
                    let row = ((j - ty * t) as usize) * TILE;
                    for i in i0.max(x0)..=i1.min(x1) {
                        let k = row + (i - x0) as usize;
                        let (d, v) = (deltas[k], &mut tile[k]);
                        if d != 0 && *v != PINNED {
                            *v = v.saturating_add(d).clamp(-clamp, clamp);
                        }
                    }
                }
            }
        }
    }

    /// Sets cell `c` to the clamp: certainly free (`occupied` false) or occupied. Pinned cells do
    /// not change.
    pub fn set_certain(&mut self, c: CellIndex, occupied: bool) {
        let value = if occupied { self.clamp } else { -self.clamp };
        let v = self.slot(c);
        if *v != PINNED {
            *v = value;
        }
    }

    /// Pins every cell the segment from `a` to `b` passes through as occupied, for good.
    pub fn pin_segment(&mut self, a: (f64, f64), b: (f64, f64)) {
        for c in self.cells_on_segment(a, b) {
            *self.slot(c) = PINNED;
        }
    }

    /// Sets every cell the segment from `a` to `b` passes through certainly occupied (a contact).
    pub fn mark_segment(&mut self, a: (f64, f64), b: (f64, f64)) {
        for c in self.cells_on_segment(a, b) {
            self.set_certain(c, true);
        }
    }

    /// The cells a segment passes through, sampled every quarter cell (ends included).
    fn cells_on_segment(&self, a: (f64, f64), b: (f64, f64)) -> Vec<CellIndex> {
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let n = (len / (self.params.resolution_m / 4.0)).ceil().max(1.0) as usize;
        let mut cells: Vec<CellIndex> = (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                self.cell_of(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
            })
            .collect();
        cells.dedup();
        cells
    }

    /// Sets every cell overlapping the rectangle certainly free: the body stands or has driven
    /// there. The rectangle runs from `from` to `to` metres along `pose`'s heading and
    /// `half_width` either side.
    pub fn clear_rect(&mut self, pose: Pose2, from: f64, to: f64, half_width: f64) {
        // Only cells wholly inside are cleared: a cell half under the body may hold what it
        // touches. A cell overlaps a rectangle shrunk by twice its half extent only if it lies
        // wholly inside the rectangle.
        let inner = 2.0 * self.half_extent(pose.yaw_deg);
        let cells = self.cells_in_rect(pose, from + inner, to - inner, half_width - inner);
        for c in cells {
            self.set_certain(c, false);
        }
    }

    /// Every cell whose square may overlap the rectangle from `from` to `to` along `pose`'s
    /// heading, `half_width` either side.
    pub fn cells_in_rect(&self, pose: Pose2, from: f64, to: f64, half_width: f64) -> Vec<CellIndex> {
        let mut out = Vec::new();
        self.for_rect(pose, from, to, half_width, |c, _| out.push(c));
        out
    }

    /// Half the extent of a cell's square along a heading of `yaw_deg` (and across it): half a
    /// cell along the grid's axes, half its diagonal at 45°.
    fn half_extent(&self, yaw_deg: f64) -> f64 {
        let (sin, cos) = yaw_deg.to_radians().sin_cos();
        self.params.resolution_m / 2.0 * (sin.abs() + cos.abs())
    }

    /// Every cell whose square overlaps the disc of `radius` round `centre`.
    pub fn cells_in_circle(&self, centre: (f64, f64), radius: f64) -> Vec<CellIndex> {
        let half = self.params.resolution_m / 2.0;
        let reach = radius + half;
        let (c0, c1) = (
            self.cell_of(centre.0 - reach, centre.1 - reach),
            self.cell_of(centre.0 + reach, centre.1 + reach),
        );
        let mut out = Vec::new();
        for i in c0.0..=c1.0 {
            for j in c0.1..=c1.1 {
                let (x, y) = self.centre((i, j));
                if (((x - centre.0).abs() - half).max(0.0)).powi(2)
                    + (((y - centre.1).abs() - half).max(0.0)).powi(2)
                    <= radius * radius
                {
                    out.push((i, j));
                }
            }
        }
        out
    }

    /// Calls `visit` with every cell whose square may overlap the rectangle from `from` to `to`
    /// along `pose`'s heading, `half_width` either side, and the cell centre's distance along
    /// the heading.
    fn for_rect(
        &self,
        pose: Pose2,
        from: f64,
        to: f64,
        half_width: f64,
        mut visit: impl FnMut(CellIndex, f64),
    ) {
        if to < from || half_width < 0.0 {
            return;
        }
        // Separating axes along and across the heading: exact for the grid's own headings,
        // conservative between them.
        let pad = self.half_extent(pose.yaw_deg);
        let (sin, cos) = pose.yaw_deg.to_radians().sin_cos();
        let corners = [(from, -half_width), (from, half_width), (to, -half_width), (to, half_width)]
            .map(|(a, l)| (pose.x + a * cos - l * sin, pose.y + a * sin + l * cos));
        let (lo, hi) = bounding(&corners, pad);
        let (c0, c1) = (self.cell_of(lo.0, lo.1), self.cell_of(hi.0, hi.1));
        for i in c0.0..=c1.0 {
            for j in c0.1..=c1.1 {
                let (x, y) = self.centre((i, j));
                let (dx, dy) = (x - pose.x, y - pose.y);
                let along = dx * cos + dy * sin;
                let left = -dx * sin + dy * cos;
                if along >= from - pad && along <= to + pad && left.abs() <= half_width + pad {
                    visit((i, j), along);
                }
            }
        }
    }

    /// The worst of the cells overlapping the rectangle from `from` to `to` along `pose`'s
    /// heading, `half_width` either side.
    pub fn classify_rect(&self, pose: Pose2, from: f64, to: f64, half_width: f64) -> Occupancy {
        let mut worst = Occupancy::Free;
        self.for_rect(pose, from, to, half_width, |c, _| worst = worst.max(self.cell(c)));
        worst
    }

    /// The worst of the cells overlapping the disc of `radius` round `centre`.
    pub fn classify_circle(&self, centre: (f64, f64), radius: f64) -> Occupancy {
        self.cells_in_circle(centre, radius)
            .into_iter()
            .map(|c| self.cell(c))
            .max()
            .unwrap_or(Occupancy::Free)
    }

    /// The centre of the occupied cell nearest `centre` among those overlapping the disc of
    /// `radius` round it, if any.
    pub fn nearest_occupied_in_circle(&self, centre: (f64, f64), radius: f64) -> Option<(f64, f64)> {
        self.cells_in_circle(centre, radius)
            .into_iter()
            .filter(|&c| self.cell(c) == Occupancy::Occupied)
            .map(|c| self.centre(c))
            .min_by(|a, b| {
                let d = |p: &(f64, f64)| (p.0 - centre.0).powi(2) + (p.1 - centre.1).powi(2);
                d(a).total_cmp(&d(b)).then(a.0.total_cmp(&b.0)).then(a.1.total_cmp(&b.1))
            })
    }

    /// The centre of the occupied cell nearest along the heading in the rectangle, if any: what
    /// a FORWARD along it would meet first.
    pub fn first_occupied_in_rect(
        &self,
        pose: Pose2,
        from: f64,
        to: f64,
        half_width: f64,
    ) -> Option<(f64, f64)> {
        let mut first: Option<(f64, CellIndex)> = None;
        self.for_rect(pose, from, to, half_width, |c, along| {
            if self.cell(c) == Occupancy::Occupied && first.is_none_or(|(a, f)| (along, c) < (a, f)) {
                first = Some((along, c));
            }
        });
        first.map(|(_, c)| self.centre(c))
    }

    /// Bytes held by the cells (tiles), not counting the map's own bookkeeping.
    pub fn memory_bytes(&self) -> usize {
        self.tiles.len() * TILE * TILE
    }

    /// Every cell written so far with its evidence, in a fixed order (for pictures and logs).
    pub fn written_cells(&self) -> Vec<(CellIndex, Occupancy)> {
        let mut keys: Vec<_> = self.tiles.keys().copied().collect();
        keys.sort_unstable();
        let t = TILE as i32;
        let mut out = Vec::new();
        for k in keys {
            let Some(tile) = self.tiles.get(&k) else { continue };
            for (i, &v) in tile.iter().enumerate() {
                if v != 0 {
                    let (u, w) = ((i % TILE) as i32, (i / TILE) as i32);
                    out.push(((k.0 * t + u, k.1 * t + w), self.classify_raw(v)));
                }
            }
        }
        out
    }
}

fn bounding(points: &[(f64, f64)], pad: f64) -> ((f64, f64), (f64, f64)) {
    let mut lo = (f64::INFINITY, f64::INFINITY);
    let mut hi = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for &(x, y) in points {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    ((lo.0 - pad, lo.1 - pad), (hi.0 + pad, hi.1 + pad))
}

#[cfg(test)]
mod tests;
