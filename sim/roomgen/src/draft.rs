//! Pieces and the draft room: what a piece is, how it meets others, and the room being drawn.

use super::geometry::*;
use super::*;

/// How a piece meets others.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// Walls and pillars built into them: they may meet each other.
    Wall,
    /// Furniture standing on its whole footprint.
    Solid,
    /// A table or desk: only its legs stand on the floor; chairs may stand under its top.
    Legged,
    /// A chair.
    Seat,
    /// Floor kept free (doorways, corridors, closet insides): not written to the file.
    Clear,
}

#[derive(Debug, Clone)]
pub(super) struct Item {
    pub(super) label: String,
    pub(super) kind: Kind,
    pub(super) footprint: Obstacle,
    pub(super) parts: Vec<Obstacle>,
    /// Closes against walls on purpose (closet walls, a unit across a corner): wall checks skipped.
    pub(super) seals: bool,
}

/// Table and desk legs.
#[derive(Debug, Clone, Copy)]
pub(super) enum Legs {
    /// Four round legs of diameter `d`, `inset` from the top's edges.
    Round { d: f32, inset: f32 },
    /// Four square legs of side `s`.
    Square { s: f32, inset: f32 },
    /// Two side panels `th` thick at the short ends.
    Panels { th: f32, inset: f32 },
}

impl Legs {
    /// Four legs of `lo`–`hi` metres (round or square), or two panels with probability `panels`.
    pub(super) fn draw(rng: &mut ChaCha8Rng, lo: f32, hi: f32, panels: f64) -> Legs {
        if chance(rng, panels) {
            return Legs::Panels { th: mm(uniform(rng, 0.018, 0.03)), inset: mm(uniform(rng, 0.0, 0.03)) };
        }
        let size = mm(uniform(rng, lo, hi));
        let inset = mm(uniform(rng, 0.01, 0.05));
        if chance(rng, 0.7) { Legs::Round { d: size, inset } } else { Legs::Square { s: size, inset } }
    }

    pub(super) fn describe(self) -> String {
        match self {
            Legs::Round { d, .. } => format!("four round legs {:.0} mm", d * 1000.0),
            Legs::Square { s, .. } => format!("four square legs {:.0} mm", s * 1000.0),
            Legs::Panels { th, .. } => format!("two side panels {:.0} mm", th * 1000.0),
        }
    }

    pub(super) fn parts(self, center: Pt, size: Pt, angle: f32) -> Vec<Obstacle> {
        let (w, h) = size;
        let quad = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        match self {
            Legs::Round { d, inset } => {
                let (dx, dy) = (w * 0.5 - inset - d * 0.5, h * 0.5 - inset - d * 0.5);
                quad.iter().map(|&(sx, sy)| disc(local(center, angle, (sx * dx, sy * dy)), d * 0.5)).collect()
            }
            Legs::Square { s, inset } => {
                let (dx, dy) = (w * 0.5 - inset - s * 0.5, h * 0.5 - inset - s * 0.5);
                quad.iter()
                    .map(|&(sx, sy)| rect(local(center, angle, (sx * dx, sy * dy)), (s, s), angle))
                    .collect()
            }
            Legs::Panels { th, inset } => [-1.0f32, 1.0]
                .iter()
                .map(|&sx| {
                    let c = local(center, angle, (sx * (w * 0.5 - inset - th * 0.5), 0.0));
                    rect(c, (th, h - 2.0 * inset), angle)
                })
                .collect(),
        }
    }
}

impl Item {
    pub(super) fn solid(label: String, center: Pt, size: Pt, angle: f32) -> Item {
        let fp = rect(center, size, angle);
        Item { label, kind: Kind::Solid, parts: vec![fp.clone()], footprint: fp, seals: false }
    }

    pub(super) fn round(label: String, center: Pt, radius: f32) -> Item {
        let fp = disc(center, radius);
        Item { label, kind: Kind::Solid, parts: vec![fp.clone()], footprint: fp, seals: false }
    }

    pub(super) fn legged(label: String, kind: Kind, center: Pt, size: Pt, angle: f32, legs: Legs) -> Item {
        let angle = tenth(angle);
        let (center, size) = ((mm(center.0), mm(center.1)), (mm(size.0), mm(size.1)));
        let parts = legs.parts(center, size, angle);
        Item { label, kind, footprint: rect(center, size, angle), parts, seals: false }
    }

    pub(super) fn clear(footprint: Obstacle) -> Item {
        Item { label: String::new(), kind: Kind::Clear, footprint, parts: Vec::new(), seals: false }
    }
}

pub(super) struct Placed {
    pub(super) item: Item,
    pub(super) footprint: Shaped,
    pub(super) parts: Vec<Shaped>,
}

/// What a draft room holds, for its description.
#[derive(Debug, Default)]
pub(super) struct Facts {
    pub(super) rooms: usize,
    pub(super) doors: usize,
    pub(super) pockets: usize,
    pub(super) pillars: usize,
    pub(super) furniture: usize,
    pub(super) racks: usize,
}

/// A room being drawn: its outline and the pieces placed so far.
pub(super) struct Draft {
    pub(super) room: Vec<Pt>,
    pub(super) edges: Vec<Shaped>,
    pub(super) placed: Vec<Placed>,
    pub(super) facts: Facts,
    pub(super) kind_name: &'static str,
}

impl Draft {
    pub(super) fn new(room: Vec<Pt>, kind_name: &'static str) -> Draft {
        let room: Vec<Pt> = room.iter().map(|&(x, y)| (mm(x), mm(y))).collect();
        let edges = (0..room.len())
            .filter_map(|i| shaped(&Obstacle::Segment { from: room[i], to: room[(i + 1) % room.len()] }))
            .collect();
        Draft { room, edges, placed: Vec::new(), facts: Facts::default(), kind_name }
    }

    /// Places `item` if it is physically plausible there; `region` (a polygon) must hold its
    /// footprint when given.
    pub(super) fn place(&mut self, item: Item, region: Option<&[Pt]>) -> bool {
        let Some(footprint) = shaped(&item.footprint) else { return false };
        let Some(parts) = item.parts.iter().map(shaped).collect::<Option<Vec<_>>>() else { return false };
        if !self.fits(&item, &footprint, &parts, region) {
            return false;
        }
        self.placed.push(Placed { item, footprint, parts });
        true
    }

    pub(super) fn fits(
        &self,
        item: &Item,
        footprint: &Shaped,
        parts: &[Shaped],
        region: Option<&[Pt]>,
    ) -> bool {
        let furniture = !matches!(item.kind, Kind::Wall | Kind::Clear);
        if furniture {
            let inset = if item.seals { 2.0 * SEAL } else { 0.0 };
            let pts = corners(&item.footprint, inset);
            if !pts.iter().all(|&(x, y)| grid::point_in_polygon(&self.room, x, y)) {
                return false;
            }
            if let Some(region) = region
                && !pts.iter().all(|&(x, y)| grid::point_in_polygon(region, x, y))
            {
                return false;
            }
            if !item.seals && self.edges.iter().any(|e| near(e, footprint, 0.0)) {
                return false;
            }
        }
        self.placed.iter().all(|p| compatible(item, footprint, parts, p))
    }

    /// Counts the furniture: everything standing on the floor but walls, pillars and racks.
    pub(super) fn count_furniture(&mut self) {
        let standing =
            self.placed.iter().filter(|p| !matches!(p.item.kind, Kind::Wall | Kind::Clear)).count();
        self.facts.furniture = standing.saturating_sub(self.facts.pillars + self.facts.racks);
    }
}

/// Whether a new piece can stand beside a placed one.
pub(super) fn compatible(item: &Item, footprint: &Shaped, parts: &[Shaped], placed: &Placed) -> bool {
    use Kind::*;
    let other = &placed.item;
    match (item.kind, other.kind) {
        (Wall | Clear, Wall) | (Clear, Clear) => true,
        // A new wall must leave doorways, corridors and furniture alone.
        (Wall, _) => !parts.iter().any(|p| near(p, &placed.footprint, 0.0)),
        (_, Wall) => item.seals || !placed.parts.iter().any(|p| near(p, footprint, 0.0)),
        (_, Clear) | (Clear, _) => !near(footprint, &placed.footprint, 0.0),
        (a, b) => {
            if !near(footprint, &placed.footprint, 0.0) {
                return true;
            }
            // A chair under a table or desk top: only the legs must keep apart.
            let under = matches!((a, b), (Seat, Legged) | (Legged, Seat));
            under && !parts.iter().any(|p| placed.parts.iter().any(|q| near(p, q, 0.01)))
        }
    }
}
