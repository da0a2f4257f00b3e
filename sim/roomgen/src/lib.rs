#![doc = include_str!("../README.md")]

//! Room generator: realistic scenario files, sizes drawn from measured rooms (walls, doors, furniture, legs).
//!
//! `explobot generate --style STYLE --seed N [--out FILE]` writes one scenario. The room is what a
//! user would measure in their home or workplace and write down: sizes come from the ranges of
//! `rooms.md`, every wall and piece of furniture sits at any offset (millimetre resolution) and
//! nothing is snapped to, aligned with or kept away from the robot's grid. The generator never
//! looks at how Carto or Cute fare in a room; rooms are not filtered by difficulty.
//!
//! # Styles and the `rooms.md` rows they draw from
//! - [`RoomStyle::Flat`]: a furnished flat 2.0–10.0 × 2.0–8.5 m, split by interior walls
//!   (0.07–0.15 m thick, *interior wall*) into up to four rooms of 2.0 m or more (*room side*),
//!   sometimes with a 0.9–1.2 m hall (*corridor*). Every wall has one or two doors of 0.70–0.90 m,
//!   now and then a double door of 1.2–1.6 m (*door opening*), anywhere along it from 5 cm from a
//!   corner. The largest room is the living room (sofa, storage, dining table on four 4–8 cm legs
//!   or a pedestal, chairs), then bedrooms (bed, wardrobe, desk on legs or panels with a chair),
//!   a kitchen (0.60 m counters, island, table), small rooms (a cabinet, a bin). Sometimes a
//!   closet with its door shut (walls, no gap) or a wardrobe or sofa across a corner leaves a
//!   closed pocket.
//! - [`RoomStyle::Office`]: 4.5–12.5 × 4.0–10.5 m. Banks of desks (*desk*: 0.6–0.8 × 1.0–1.6 on
//!   four 3–6 cm legs or two side panels, one model per office), single or back to back, with
//!   chairs (*chair*: four 2–4 cm legs) pushed in or pulled out and mostly turned 10–45°; a 1.2–2.0 m
//!   corridor kept clear along the top; often a row of cellular offices and meeting rooms behind a
//!   partition with doors, now and then a store room with its door shut; cabinets, plants, bins.
//! - [`RoomStyle::Warehouse`]: 8.0–14.5 × 6.0–12.5 m. Parallel rack runs (*warehouse aisle*: racks
//!   0.4–1.2 m deep, single or back to back, runs of 5–10 m, one or two runs in line with a cross
//!   aisle) separated by aisles of 1.0–3.0 m; racks along x or along y. Pallets (1.2 × 0.8 m, any
//!   angle) and bins in the free end.
//! - [`RoomStyle::Pillars`]: 6.0–14.0 × 6.0–12.0 m open hall whose pillars (*pillar*: round
//!   0.2–0.5 m or square 0.3–0.6 m) stand on a 5–8 m structural grid laid at a random offset (the
//!   building's grid, unrelated to ours); often half-pillars engaged in the outer walls; a few
//!   pieces of furniture (storage, a table with chairs, a sofa, plants).
//! - [`RoomStyle::Irregular`]: a 2.0–7.5 × 2.0–7.0 m room whose outline (*outline*) has one to
//!   three of: an L cut, a 45° chamfer, a corner cut at 30–60°, a slanted wall, and a bay window
//!   with 45° sides. Furnished like a flat's room of its area; furniture against a slanted wall
//!   is rotated with it.
//!
//! # Invariants
//! - Same style and seed → byte-identical text ([`GeneratedRoom::to_ron`]); the only randomness
//!   is a [`ChaCha8Rng`] seeded with the seed, on a stream chosen by style and sub-seed.
//! - The only filters are physical plausibility: furniture overlaps no other furniture (a chair
//!   may stand under a table top, its legs clear of the table's), does not poke through walls and
//!   keeps doorways passable; the outline is a simple polygon.
//! - The start cell is one where the robot can turn on the spot: a disc of half the footprint's
//!   diagonal around the cell centre touches no wall or obstacle, and the body can drive to a
//!   free neighbouring cell without touching anything. The start is drawn among such cells of
//!   the largest connected free area (where a user puts the robot down, not inside a closet).
//!   When a draw has none, the next sub-seed is drawn.
//! - The mission is `[StartCartography, WaitUntilMapped]`; expectations are the robot's pass
//!   criteria (the profile's `scoring.pass`, `docs/explanation/scoring.md`) and 40 s per m² of floor (about 67 minutes for 10 × 10 m,
//!   at least 5 minutes) as both the finish limit and the run's time limit: Carto needs 2–4 s
//!   per 0.30 m cell today, so the limit catches runs that hang without making speed a hidden
//!   pass criterion.
//! - Beds and sofas are drawn solid: the twin is 2-D and their frames sit at sonar height.
//!
//! ```
//! use twin_roomgen::{RoomStyle, generate};
//! let room = generate(RoomStyle::Flat, 7)?;
//! let text = room.to_ron();
//! assert_eq!(text, generate(RoomStyle::Flat, 7)?.to_ron());
//! let parsed = twin::scenario::Scenario::from_ron_str(&text, "flat-7.ron")?;
//! assert_eq!(&parsed, room.scenario());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt::Write as _;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier2d::parry::math::Pose;
use rapier2d::parry::query;
use rapier2d::parry::shape::Shape;
use robot_model::profile::RobotProfile;
use serde::{Deserialize, Serialize};

use twin::grid;
use twin::scenario::{Expectations, Heading, Obstacle, PhysicsSettings, Scenario, Start, Step, polygon_area};

mod draft;
mod finish;
mod furniture;
mod geometry;
mod styles;
#[cfg(test)]
mod tests;
mod walls;

use self::{finish::*, styles::*};

/// Sub-seeds tried for one (style, seed) before giving up.
const MAX_SUB_SEEDS: u32 = 64;
/// Mission time allowed per square metre of floor: about 67 minutes for a 10 × 10 m room. Carto
/// needs 2–4 s per 0.30 m cell today (0.09 m²), so this is a limit for runs that hang, not a
/// criterion a sound mission has to race against.
const SECONDS_PER_M2: f64 = 40.0;
/// The shortest mission time limit, seconds.
const MIN_FINISH_S: f64 = 300.0;
/// Depth kept clear on each side of a doorway so a person can walk through, metres.
const DOOR_CLEARANCE: f32 = 0.6;
/// How far a sealing wall or corner unit reaches into the wall it closes against, metres.
const SEAL: f32 = 0.01;

/// A kind of room to generate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum RoomStyle {
    /// A furnished flat: interior walls with doors, beds, sofas, wardrobes, tables, chairs.
    Flat,
    /// An office: desk banks on legs, turned chairs, a corridor, cellular offices.
    Office,
    /// Warehouse racks in long parallel runs with 1.0–3.0 m aisles.
    Warehouse,
    /// An open hall with pillars on a 5–8 m structural grid.
    Pillars,
    /// An irregular outline: L cuts, chamfers, slanted walls, bay windows.
    Irregular,
}

impl RoomStyle {
    /// Every style, in CLI order.
    pub const ALL: [RoomStyle; 5] =
        [RoomStyle::Flat, RoomStyle::Office, RoomStyle::Warehouse, RoomStyle::Pillars, RoomStyle::Irregular];

    /// The style's CLI name (`flat`, `office`, …).
    pub fn name(self) -> &'static str {
        match self {
            RoomStyle::Flat => "flat",
            RoomStyle::Office => "office",
            RoomStyle::Warehouse => "warehouse",
            RoomStyle::Pillars => "pillars",
            RoomStyle::Irregular => "irregular",
        }
    }

    fn stream(self) -> u64 {
        match self {
            RoomStyle::Flat => 1,
            RoomStyle::Office => 2,
            RoomStyle::Warehouse => 3,
            RoomStyle::Pillars => 4,
            RoomStyle::Irregular => 5,
        }
    }
}

/// Why no room was generated or written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GenerateError {
    /// No draw had a cell where the robot can turn on the spot.
    #[error("no start cell where the robot can turn in {tries} draws of style {style:?}, seed {seed}")]
    NoStartCell {
        /// The style asked for.
        style: RoomStyle,
        /// The seed asked for.
        seed: u64,
        /// Sub-seeds tried.
        tries: u32,
    },
    /// The generated text failed scenario validation (a generator bug).
    #[error("generated room does not pass validation: {0}")]
    Invalid(String),
    /// The output could not be written.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The output.
        path: String,
        /// The system's reason.
        message: String,
    },
}

/// One piece of a generated room: a wall, a pillar or a piece of furniture, and its obstacles.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// What it is, with its size (`"wardrobe 1.62 x 0.58 m"`).
    pub label: String,
    /// Its outline on the floor (the whole wall for a wall with doors, the top for a table).
    pub footprint: Obstacle,
    /// The obstacles it puts in the scenario, in file order.
    pub parts: Vec<Obstacle>,
}

/// A generated room: the scenario and how it was drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratedRoom {
    style: RoomStyle,
    seed: u64,
    sub_seed: u32,
    pieces: Vec<Piece>,
    scenario: Scenario,
}

impl GeneratedRoom {
    /// The scenario (its obstacles are the pieces' parts, in order).
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The style it was drawn in.
    pub fn style(&self) -> RoomStyle {
        self.style
    }

    /// The seed asked for.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Which draw for this seed gave the room (0 unless earlier draws had no start cell).
    pub fn sub_seed(&self) -> u32 {
        self.sub_seed
    }

    /// The walls, pillars and furniture, in file order.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// The scenario file: a header comment, then the scenario with one comment per piece.
    pub fn to_ron(&self) -> String {
        let s = &self.scenario;
        let mut out = String::new();
        let style = self.style.name();
        let _ = writeln!(out, "// Generated by `explobot generate --style {style} --seed {}`.", self.seed);
        let _ = writeln!(
            out,
            "// Style {style}, seed {}, sub-seed {}; sizes from shared/spec/rooms.md, nothing aligned with the grid.",
            self.seed, self.sub_seed
        );
        let _ = writeln!(
            out,
            "// The start cell is one where the robot can turn on the spot and reach a neighbouring cell."
        );
        let _ = writeln!(out, "Scenario(");
        let _ = writeln!(out, "    name: {:?},", s.name);
        let _ = writeln!(out, "    description: {:?},", s.description);
        let _ = writeln!(out, "    robot: None, // the built-in default, equal to robots/mecanum-4wd.ron");
        let _ = writeln!(out, "    seed: {},", s.seed);
        let _ = writeln!(out, "    room: [");
        for p in &s.room {
            let _ = writeln!(out, "        {},", fmt_pt(*p));
        }
        let _ = writeln!(out, "    ],");
        let _ = writeln!(out, "    obstacles: [");
        for piece in &self.pieces {
            let _ = writeln!(out, "        // {}", piece.label);
            for part in &piece.parts {
                let _ = writeln!(out, "        {},", fmt_obstacle(part));
            }
        }
        let _ = writeln!(out, "    ],");
        let _ = writeln!(
            out,
            "    start: (row: {}, col: {}, heading: {:?}),",
            s.start.row, s.start.col, s.start.heading
        );
        let _ = writeln!(out, "    physics: (max_sim_s: {:.1}),", s.physics.max_sim_s);
        let _ = writeln!(out, "    mission: [StartCartography, WaitUntilMapped],");
        let e = &s.expect;
        let _ = writeln!(
            out,
            "    // The robot's pass criteria (its profile's scoring.pass) and this room's time limit."
        );
        let _ = writeln!(
            out,
            "    expect: (coverage_min: {:?}, map_accuracy_min: {:?}, finish_within_s: {}, believed_cell_true: {:?},",
            e.coverage_min,
            e.map_accuracy_min,
            fmt_opt(e.finish_within_s.map(|v| format!("{v:.1}"))),
            e.believed_cell_true
        );
        let _ = writeln!(
            out,
            "             touches_max: {:?}, hard_collisions_max: {:?}, touches_per_100_moves_max: {:?},",
            e.touches_max, e.hard_collisions_max, e.touches_per_100_moves_max
        );
        let _ = writeln!(
            out,
            "             belief_error_max_m: {:?}, belief_error_p95_max_m: {:?}, belief_heading_error_max_deg: {:?}),",
            e.belief_error_max_m, e.belief_error_p95_max_m, e.belief_heading_error_max_deg
        );
        let _ = writeln!(out, ")");
        out
    }
}

/// Generates a room of `style` for the default robot.
pub fn generate(style: RoomStyle, seed: u64) -> Result<GeneratedRoom, GenerateError> {
    generate_for(style, seed, &RobotProfile::default())
}

/// Generates a room of `style`, choosing the start cell for `profile`'s footprint and cell size.
pub fn generate_for(
    style: RoomStyle,
    seed: u64,
    profile: &RobotProfile,
) -> Result<GeneratedRoom, GenerateError> {
    for sub_seed in 0..MAX_SUB_SEEDS {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream((style.stream() << 32) | u64::from(sub_seed));
        let draft = match style {
            RoomStyle::Flat => flat(&mut rng),
            RoomStyle::Office => office(&mut rng),
            RoomStyle::Warehouse => warehouse(&mut rng),
            RoomStyle::Pillars => pillars(&mut rng),
            RoomStyle::Irregular => irregular(&mut rng),
        };
        if let Some(room) = finish(draft, style, seed, sub_seed, profile, &mut rng) {
            return Ok(room);
        }
    }
    Err(GenerateError::NoStartCell { style, seed, tries: MAX_SUB_SEEDS })
}
