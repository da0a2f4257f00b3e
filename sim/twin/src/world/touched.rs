//! What a fixed shape of the room is, as the sonar meets it ([`Touched`]): what the robot
//! touched, told apart by size and by the angle of its sides from the grid.

use crate::scenario::Obstacle;

/// A disc or box no wider than this either way is a leg, metres (`rooms.md`: legs are 2–8 cm).
pub const LEG_MAX_M: f32 = 0.08;
/// A box no thicker than this and at least [`WALL_MIN_LENGTH_M`] long is a wall or a panel,
/// metres (`rooms.md`: interior walls are 7–15 cm thick; a desk's side panel is thinner).
pub const WALL_MAX_THICKNESS_M: f32 = 0.16;
/// See [`WALL_MAX_THICKNESS_M`], metres.
pub const WALL_MIN_LENGTH_M: f32 = 0.5;

/// What a fixed shape of the room is, as the sonar meets it: what the robot touched.
///
/// `off_grid_deg` is how far a straight side turns from the grid's lines, 0–45°. The twin's sonar
/// hears a flat surface only within the profile's incidence limit (22.5° by default) of its
/// normal, so from a robot facing a grid heading a side turned further gives no echo head-on.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Touched {
    /// An edge of the room's outline.
    RoomWall {
        /// Degrees from the grid's lines, 0–45.
        off_grid_deg: f32,
    },
    /// A wall inside the room: a `Segment` obstacle, or a box no thicker than
    /// [`WALL_MAX_THICKNESS_M`] and at least [`WALL_MIN_LENGTH_M`] long (also a desk's panel).
    Wall {
        /// Degrees from the grid's lines, 0–45.
        off_grid_deg: f32,
    },
    /// A disc or box no wider than [`LEG_MAX_M`] either way.
    Leg {
        /// The widest side or the diameter, metres.
        width_m: f32,
    },
    /// A disc wider than a leg (a pillar, a bin, a round table's pedestal).
    Disc {
        /// Metres.
        diameter_m: f32,
    },
    /// A box wider than a leg.
    Box {
        /// Degrees from the grid's lines, 0–45.
        off_grid_deg: f32,
    },
    /// A convex polygon.
    Polygon,
}

/// How far a direction `deg` turns from the nearest grid line, 0–45°.
fn off_grid(deg: f32) -> f32 {
    let a = deg.rem_euclid(90.0);
    a.min(90.0 - a)
}

pub(super) fn segment_off_grid(from: (f32, f32), to: (f32, f32)) -> f32 {
    off_grid((to.1 - from.1).atan2(to.0 - from.0).to_degrees())
}

impl Touched {
    /// What `o` is (see [`Touched`]).
    pub fn of(o: &Obstacle) -> Touched {
        match *o {
            Obstacle::Box { size, .. } if size.0.max(size.1) <= LEG_MAX_M => {
                Touched::Leg { width_m: size.0.max(size.1) }
            }
            Obstacle::Box { size, angle_deg, .. }
                if size.0.min(size.1) <= WALL_MAX_THICKNESS_M && size.0.max(size.1) >= WALL_MIN_LENGTH_M =>
            {
                Touched::Wall { off_grid_deg: off_grid(angle_deg) }
            }
            Obstacle::Box { angle_deg, .. } => Touched::Box { off_grid_deg: off_grid(angle_deg) },
            Obstacle::Circle { radius, .. } if 2.0 * radius <= LEG_MAX_M => {
                Touched::Leg { width_m: 2.0 * radius }
            }
            Obstacle::Circle { radius, .. } => Touched::Disc { diameter_m: 2.0 * radius },
            Obstacle::Segment { from, to } => Touched::Wall { off_grid_deg: segment_off_grid(from, to) },
            Obstacle::Polygon { .. } => Touched::Polygon,
        }
    }

    /// One line for a report: the class and its size or angle.
    pub fn describe(&self) -> String {
        match *self {
            Touched::RoomWall { off_grid_deg } => format!("room wall, {off_grid_deg:.0}° from the grid"),
            Touched::Wall { off_grid_deg } => format!("wall or panel, {off_grid_deg:.0}° from the grid"),
            Touched::Leg { width_m } => format!("leg, {:.0} cm wide", width_m * 100.0),
            Touched::Disc { diameter_m } => format!("disc, {:.0} cm across", diameter_m * 100.0),
            Touched::Box { off_grid_deg } => format!("box, {off_grid_deg:.0}° from the grid"),
            Touched::Polygon => "polygon".to_string(),
        }
    }

    /// The class a sweep counts it in, in words.
    pub fn class(&self) -> &'static str {
        let past = |deg: f32| deg > INCIDENCE_CLASS_DEG;
        match *self {
            Touched::RoomWall { off_grid_deg } if past(off_grid_deg) => {
                "room wall turned past 22.5° from the grid"
            }
            Touched::RoomWall { .. } => "room wall",
            Touched::Wall { off_grid_deg } if past(off_grid_deg) => {
                "wall or panel turned past 22.5° from the grid"
            }
            Touched::Wall { .. } => "wall or panel inside the room",
            Touched::Leg { .. } => "leg (8 cm or thinner)",
            Touched::Disc { .. } => "disc wider than a leg (pillar, bin)",
            Touched::Box { off_grid_deg } if past(off_grid_deg) => "box turned past 22.5° from the grid",
            Touched::Box { off_grid_deg } if off_grid_deg >= 1.0 => "box turned 1–22.5° from the grid",
            Touched::Box { .. } => "box square to the grid (within 1°)",
            Touched::Polygon => "polygon",
        }
    }
}

/// Sides turned further than this from the grid give the default sonar no echo head-on, degrees
/// (the default profile's incidence limit); [`Touched::class`] splits there.
const INCIDENCE_CLASS_DEG: f32 = 22.5;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_told_apart_by_size_and_angle_from_the_grid() {
        let b = |w: f32, h: f32, angle_deg: f32| {
            Touched::of(&Obstacle::Box { center: (0.0, 0.0), size: (w, h), angle_deg })
        };
        assert_eq!(b(0.05, 0.08, 33.0), Touched::Leg { width_m: 0.08 });
        assert_eq!(b(0.05, 0.09, 0.0), Touched::Box { off_grid_deg: 0.0 });
        // an interior wall 12 cm thick, and a piece of one too short to tell from a box
        assert_eq!(b(2.0, 0.12, 90.0), Touched::Wall { off_grid_deg: 0.0 });
        assert_eq!(b(0.3, 0.12, 0.0), Touched::Box { off_grid_deg: 0.0 });
        assert_eq!(b(0.6, 0.35, 0.0), Touched::Box { off_grid_deg: 0.0 });
        for (angle, off) in [(100.0, 10.0), (-30.0, 30.0), (45.0, 45.0), (270.0, 0.0), (-95.0, 5.0)] {
            assert!(
                matches!(b(0.6, 0.4, angle), Touched::Box { off_grid_deg } if (off_grid_deg - off).abs() < 1e-3),
                "{angle}"
            );
        }
        let disc = |radius: f32| Touched::of(&Obstacle::Circle { center: (0.0, 0.0), radius });
        assert_eq!(disc(0.04), Touched::Leg { width_m: 0.08 });
        assert_eq!(disc(0.2), Touched::Disc { diameter_m: 0.4 });
        let wall = Touched::of(&Obstacle::Segment { from: (0.0, 0.0), to: (-1.0, -1.0) });
        assert!(matches!(wall, Touched::Wall { off_grid_deg } if (off_grid_deg - 45.0).abs() < 1e-3));
        // the class splits at the default sonar's incidence limit
        assert_eq!(Touched::Box { off_grid_deg: 22.5 }.class(), "box turned 1–22.5° from the grid");
        assert_eq!(Touched::Box { off_grid_deg: 22.6 }.class(), "box turned past 22.5° from the grid");
        assert_eq!(Touched::Box { off_grid_deg: 0.5 }.class(), "box square to the grid (within 1°)");
        assert_eq!(
            Touched::Wall { off_grid_deg: 45.0 }.class(),
            "wall or panel turned past 22.5° from the grid"
        );
    }
}
