//! Room generator: realistic scenario files drawn from `shared/spec/rooms.md`.
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
//! - The mission is `[StartCartography, WaitUntilMapped]`; expectations are the pass criteria of
//!   issue 10 — coverage ≥ 0.98, accuracy ≥ 0.95, no collision, position error ≤ 5 cm, heading
//!   error ≤ 3°, Cute's final cell the true one — and 40 s per m² of floor (about 67 minutes for 10 × 10 m,
//!   at least 5 minutes) as both the finish limit and the run's time limit: Carto needs 2–4 s
//!   per 0.30 m cell today, so the limit catches runs that hang without making speed a hidden
//!   pass criterion.
//! - Beds and sofas are drawn solid: the twin is 2-D and their frames sit at sonar height.
//!
//! ```
//! use sim::generate::{RoomStyle, generate};
//! let room = generate(RoomStyle::Flat, 7)?;
//! let text = room.to_ron();
//! assert_eq!(text, generate(RoomStyle::Flat, 7)?.to_ron());
//! let parsed = sim::scenario::Scenario::from_ron_str(&text, "flat-7.ron")?;
//! assert_eq!(&parsed, room.scenario());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier2d::parry::math::Pose;
use rapier2d::parry::query;
use rapier2d::parry::shape::Shape;
use robot_model::profile::RobotProfile;
use serde::{Deserialize, Serialize};

use crate::grid;
use crate::scenario::{
    Expectations, Heading, LoadedScenario, Obstacle, PhysicsSettings, Scenario, Start, Step, polygon_area,
};
use crate::truth::RobotTruth;

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
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, clap::ValueEnum,
)]
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

/// Arguments of `explobot generate`.
#[derive(clap::Args, Debug, Clone)]
pub struct GenerateArgs {
    /// Kind of room.
    #[arg(long, value_enum)]
    pub style: RoomStyle,
    /// Seed: the same style and seed always give the same file.
    #[arg(long)]
    pub seed: u64,
    /// Output file (default: standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

impl GenerateArgs {
    /// Generates the room, checks it as `explobot check` would, and writes it to `--out` or
    /// standard output.
    pub fn run(&self) -> Result<(), GenerateError> {
        let room = generate(self.style, self.seed)?;
        let text = room.to_ron();
        let label = self.out.as_ref().map_or("<stdout>".to_string(), |p| p.display().to_string());
        LoadedScenario::from_ron_str(&text, &label, Path::new("."))
            .map_err(|e| GenerateError::Invalid(e.to_string()))?;
        let written = match &self.out {
            Some(path) => std::fs::write(path, &text),
            None => std::io::stdout().lock().write_all(text.as_bytes()),
        };
        written.map_err(|e| GenerateError::Write { path: label, message: e.to_string() })
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
            "    expect: (coverage_min: {}, map_accuracy_min: {}, collisions_max: {:?}, finish_within_s: {},",
            fmt_opt(e.coverage_min),
            fmt_opt(e.map_accuracy_min),
            e.collisions_max,
            fmt_opt(e.finish_within_s.map(|v| format!("{v:.1}")))
        );
        let _ = writeln!(
            out,
            "             position_error_max_m: {}, heading_error_max_deg: {}, believed_cell_true: {:?}),",
            fmt_opt(e.position_error_max_m),
            fmt_opt(e.heading_error_max_deg.map(|v| format!("{v:.1}"))),
            e.believed_cell_true
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

// ---------------------------------------------------------------------------------------------
// Geometry helpers.

type Pt = (f32, f32);

fn add(a: Pt, b: Pt) -> Pt {
    (a.0 + b.0, a.1 + b.1)
}

fn sub(a: Pt, b: Pt) -> Pt {
    (a.0 - b.0, a.1 - b.1)
}

fn scale(a: Pt, k: f32) -> Pt {
    (a.0 * k, a.1 * k)
}

fn length(a: Pt) -> f32 {
    a.0.hypot(a.1)
}

fn unit(a: Pt) -> Pt {
    let l = length(a);
    if l > 0.0 { scale(a, 1.0 / l) } else { (1.0, 0.0) }
}

/// `a` turned 90° counter-clockwise.
fn left(a: Pt) -> Pt {
    (-a.1, a.0)
}

fn dir_deg(a: Pt) -> f32 {
    a.1.atan2(a.0).to_degrees()
}

/// The world point at `l` in the frame at `origin` turned `angle_deg`.
fn local(origin: Pt, angle_deg: f32, l: Pt) -> Pt {
    let (s, c) = angle_deg.to_radians().sin_cos();
    (origin.0 + c * l.0 - s * l.1, origin.1 + s * l.0 + c * l.1)
}

/// Rounds to the millimetre (and turns −0 into 0).
fn mm(v: f32) -> f32 {
    (v * 1000.0).round() / 1000.0 + 0.0
}

/// Rounds to a tenth of a degree, in (−180, 180].
fn tenth(v: f32) -> f32 {
    let mut a = v % 360.0;
    if a <= -180.0 {
        a += 360.0;
    } else if a > 180.0 {
        a -= 360.0;
    }
    let a = (a * 10.0).round() / 10.0 + 0.0;
    if a <= -180.0 { 180.0 } else { a }
}

/// A box; its angle is written in (−90°, 90°], as a box turned by 180° is the same box.
fn rect(center: Pt, size: Pt, angle_deg: f32) -> Obstacle {
    let mut angle = tenth(angle_deg);
    if angle > 90.0 {
        angle -= 180.0;
    } else if angle <= -90.0 {
        angle += 180.0;
    }
    Obstacle::Box {
        center: (mm(center.0), mm(center.1)),
        size: (mm(size.0).max(0.001), mm(size.1).max(0.001)),
        angle_deg: tenth(angle),
    }
}

fn disc(center: Pt, radius: f32) -> Obstacle {
    Obstacle::Circle { center: (mm(center.0), mm(center.1)), radius: mm(radius).max(0.001) }
}

fn uniform(rng: &mut ChaCha8Rng, lo: f32, hi: f32) -> f32 {
    if hi > lo { rng.random_range(lo..hi) } else { lo }
}

fn chance(rng: &mut ChaCha8Rng, p: f64) -> bool {
    rng.random_bool(p.clamp(0.0, 1.0))
}

fn sign(rng: &mut ChaCha8Rng) -> f32 {
    if chance(rng, 0.5) { 1.0 } else { -1.0 }
}

fn pick<T: Copy>(rng: &mut ChaCha8Rng, items: &[T]) -> Option<T> {
    if items.is_empty() { None } else { Some(items[rng.random_range(0..items.len())]) }
}

/// The corners of a box obstacle, shrunk by `inset` on every side (its centre for a disc).
fn corners(o: &Obstacle, inset: f32) -> Vec<Pt> {
    match o {
        Obstacle::Box { center, size, angle_deg } => {
            let (hw, hh) = ((size.0 * 0.5 - inset).max(0.0), (size.1 * 0.5 - inset).max(0.0));
            [(-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh)]
                .iter()
                .map(|&l| local(*center, *angle_deg, l))
                .collect()
        }
        Obstacle::Circle { center, .. } => vec![*center],
        Obstacle::Segment { from, to } => vec![*from, *to],
        Obstacle::Polygon { points } => points.clone(),
    }
}

fn rect_outline(x0: f32, y0: f32, x1: f32, y1: f32) -> Vec<Pt> {
    vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
}

/// A parry shape with its placement and bounding box.
struct Shaped {
    pose: Pose,
    shape: Box<dyn Shape>,
    lo: Pt,
    hi: Pt,
}

fn shaped(o: &Obstacle) -> Option<Shaped> {
    let (pose, shape) = o.shape()?;
    let aabb = shape.compute_aabb(&pose);
    Some(Shaped { pose, shape, lo: (aabb.mins.x, aabb.mins.y), hi: (aabb.maxs.x, aabb.maxs.y) })
}

/// Whether `a` and `b` are closer than `margin` (touching counts; an untestable pair counts).
fn near(a: &Shaped, b: &Shaped, margin: f32) -> bool {
    if a.lo.0 > b.hi.0 + margin
        || b.lo.0 > a.hi.0 + margin
        || a.lo.1 > b.hi.1 + margin
        || b.lo.1 > a.hi.1 + margin
    {
        return false;
    }
    if margin > 0.0 {
        query::distance(&a.pose, a.shape.as_ref(), &b.pose, b.shape.as_ref())
            .map_or(true, |d| d.distance < margin)
    } else {
        query::intersection_test(&a.pose, a.shape.as_ref(), &b.pose, b.shape.as_ref())
            .map_or(true, |i| i.intersecting)
    }
}

// ---------------------------------------------------------------------------------------------
// Pieces and the draft room.

/// How a piece meets others.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
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
struct Item {
    label: String,
    kind: Kind,
    footprint: Obstacle,
    parts: Vec<Obstacle>,
    /// Closes against walls on purpose (closet walls, a unit across a corner): wall checks skipped.
    seals: bool,
}

/// Table and desk legs.
#[derive(Debug, Clone, Copy)]
enum Legs {
    /// Four round legs of diameter `d`, `inset` from the top's edges.
    Round { d: f32, inset: f32 },
    /// Four square legs of side `s`.
    Square { s: f32, inset: f32 },
    /// Two side panels `th` thick at the short ends.
    Panels { th: f32, inset: f32 },
}

impl Legs {
    /// Four legs of `lo`–`hi` metres (round or square), or two panels with probability `panels`.
    fn draw(rng: &mut ChaCha8Rng, lo: f32, hi: f32, panels: f64) -> Legs {
        if chance(rng, panels) {
            return Legs::Panels { th: mm(uniform(rng, 0.018, 0.03)), inset: mm(uniform(rng, 0.0, 0.03)) };
        }
        let size = mm(uniform(rng, lo, hi));
        let inset = mm(uniform(rng, 0.01, 0.05));
        if chance(rng, 0.7) { Legs::Round { d: size, inset } } else { Legs::Square { s: size, inset } }
    }

    fn describe(self) -> String {
        match self {
            Legs::Round { d, .. } => format!("four round legs {:.0} mm", d * 1000.0),
            Legs::Square { s, .. } => format!("four square legs {:.0} mm", s * 1000.0),
            Legs::Panels { th, .. } => format!("two side panels {:.0} mm", th * 1000.0),
        }
    }

    fn parts(self, center: Pt, size: Pt, angle: f32) -> Vec<Obstacle> {
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
    fn solid(label: String, center: Pt, size: Pt, angle: f32) -> Item {
        let fp = rect(center, size, angle);
        Item { label, kind: Kind::Solid, parts: vec![fp.clone()], footprint: fp, seals: false }
    }

    fn round(label: String, center: Pt, radius: f32) -> Item {
        let fp = disc(center, radius);
        Item { label, kind: Kind::Solid, parts: vec![fp.clone()], footprint: fp, seals: false }
    }

    fn legged(label: String, kind: Kind, center: Pt, size: Pt, angle: f32, legs: Legs) -> Item {
        let angle = tenth(angle);
        let (center, size) = ((mm(center.0), mm(center.1)), (mm(size.0), mm(size.1)));
        let parts = legs.parts(center, size, angle);
        Item { label, kind, footprint: rect(center, size, angle), parts, seals: false }
    }

    fn clear(footprint: Obstacle) -> Item {
        Item { label: String::new(), kind: Kind::Clear, footprint, parts: Vec::new(), seals: false }
    }
}

struct Placed {
    item: Item,
    footprint: Shaped,
    parts: Vec<Shaped>,
}

/// What a draft room holds, for its description.
#[derive(Debug, Default)]
struct Facts {
    rooms: usize,
    doors: usize,
    pockets: usize,
    pillars: usize,
    furniture: usize,
    racks: usize,
}

/// A room being drawn: its outline and the pieces placed so far.
struct Draft {
    room: Vec<Pt>,
    edges: Vec<Shaped>,
    placed: Vec<Placed>,
    facts: Facts,
    kind_name: &'static str,
}

impl Draft {
    fn new(room: Vec<Pt>, kind_name: &'static str) -> Draft {
        let room: Vec<Pt> = room.iter().map(|&(x, y)| (mm(x), mm(y))).collect();
        let edges = (0..room.len())
            .filter_map(|i| shaped(&Obstacle::Segment { from: room[i], to: room[(i + 1) % room.len()] }))
            .collect();
        Draft { room, edges, placed: Vec::new(), facts: Facts::default(), kind_name }
    }

    /// Places `item` if it is physically plausible there; `region` (a polygon) must hold its
    /// footprint when given.
    fn place(&mut self, item: Item, region: Option<&[Pt]>) -> bool {
        let Some(footprint) = shaped(&item.footprint) else { return false };
        let Some(parts) = item.parts.iter().map(shaped).collect::<Option<Vec<_>>>() else { return false };
        if !self.fits(&item, &footprint, &parts, region) {
            return false;
        }
        self.placed.push(Placed { item, footprint, parts });
        true
    }

    fn fits(&self, item: &Item, footprint: &Shaped, parts: &[Shaped], region: Option<&[Pt]>) -> bool {
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
    fn count_furniture(&mut self) {
        let standing =
            self.placed.iter().filter(|p| !matches!(p.item.kind, Kind::Wall | Kind::Clear)).count();
        self.facts.furniture = standing.saturating_sub(self.facts.pillars + self.facts.racks);
    }
}

/// Whether a new piece can stand beside a placed one.
fn compatible(item: &Item, footprint: &Shaped, parts: &[Shaped], placed: &Placed) -> bool {
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

// ---------------------------------------------------------------------------------------------
// Walls, doors and pockets.

/// Door openings along a wall: (start, width) pairs, sorted, within `from..to`.
fn draw_doors(rng: &mut ChaCha8Rng, from: f32, to: f32, count: usize) -> Vec<(f32, f32)> {
    let mut doors: Vec<(f32, f32)> = Vec::new();
    for _ in 0..count {
        for _ in 0..10 {
            let width = if to - from > 3.0 && chance(rng, 0.1) {
                uniform(rng, 1.2, 1.6)
            } else {
                uniform(rng, 0.70, 0.90)
            };
            let width = mm(width);
            let start = mm(uniform(rng, from + 0.05, to - width - 0.05));
            if start < from + 0.05 || start + width > to - 0.05 {
                continue;
            }
            if doors.iter().all(|&(s, w)| start + width + 0.5 < s || s + w + 0.5 < start) {
                doors.push((start, width));
                break;
            }
        }
    }
    doors.sort_by(|a, b| a.0.total_cmp(&b.0));
    doors
}

/// A straight wall of thickness `t` on the line `x = at` (`vertical`) or `y = at`, from `span.0`
/// to `span.1`, with `doors` left open. Returns the wall item and one clearance zone per door.
fn wall_item(vertical: bool, at: f32, t: f32, span: (f32, f32), doors: &[(f32, f32)]) -> (Item, Vec<Item>) {
    let piece = |a: f32, b: f32| {
        let mid = (a + b) * 0.5;
        if vertical { rect((at, mid), (t, b - a), 0.0) } else { rect((mid, at), (b - a, t), 0.0) }
    };
    let mut parts = Vec::new();
    let mut zones = Vec::new();
    let mut cursor = span.0;
    for &(start, width) in doors {
        if start - cursor > 0.005 {
            parts.push(piece(cursor, start));
        }
        let mid = start + width * 0.5;
        let depth = t + 2.0 * DOOR_CLEARANCE;
        zones.push(Item::clear(if vertical {
            rect((at, mid), (depth, width), 0.0)
        } else {
            rect((mid, at), (width, depth), 0.0)
        }));
        cursor = start + width;
    }
    if span.1 - cursor > 0.005 {
        parts.push(piece(cursor, span.1));
    }
    let doors_text = match doors.len() {
        0 => "no door".to_string(),
        _ => doors.iter().map(|d| format!("{:.2} m", d.1)).collect::<Vec<_>>().join(" and ") + " door",
    };
    let label =
        format!("interior wall {:.0} mm thick, {} m long, {doors_text}", t * 1000.0, mm(span.1 - span.0));
    let item = Item { label, kind: Kind::Wall, footprint: piece(span.0, span.1), parts, seals: false };
    (item, zones)
}

/// Places a wall and its door zones; false (nothing placed) when it would cut a doorway.
fn place_wall(d: &mut Draft, wall: Item, zones: Vec<Item>) -> bool {
    let n = d.placed.len();
    let doors = zones.len();
    if !d.place(wall, None) {
        return false;
    }
    for z in zones {
        if !d.place(z, None) {
            d.placed.truncate(n);
            return false;
        }
    }
    d.facts.doors += doors;
    true
}

/// A convex right-angled corner of a polygon: its point, the unit directions along its two
/// walls (away from the corner, `e2` = `e1` turned left) and the walls' lengths.
#[derive(Debug, Clone, Copy)]
struct Corner {
    at: Pt,
    e1: Pt,
    len1: f32,
    len2: f32,
}

fn right_corners(poly: &[Pt]) -> Vec<Corner> {
    let n = poly.len();
    (0..n)
        .filter_map(|i| {
            let (p, v, q) = (poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]);
            let (din, dout) = (unit(sub(v, p)), unit(sub(q, v)));
            let cross = din.0 * dout.1 - din.1 * dout.0;
            let dot = din.0 * dout.0 + din.1 * dout.1;
            (cross > 0.0 && dot.abs() < 0.02).then(|| Corner {
                at: v,
                e1: dout,
                len1: length(sub(q, v)),
                len2: length(sub(v, p)),
            })
        })
        .collect()
}

/// A closet in a corner with its door shut: two walls, no gap, floor inside kept empty.
fn closet(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) -> bool {
    let Some(c) = pick(rng, &right_corners(region)) else { return false };
    let t = mm(uniform(rng, 0.07, 0.12));
    let a = mm(uniform(rng, 0.6, 1.2).min(c.len1 - 1.0));
    let b = mm(uniform(rng, 0.8, 2.0).min(c.len2 - 1.0));
    if a < 0.5 || b < 0.5 {
        return false;
    }
    let angle = tenth(dir_deg(c.e1));
    let at = |l: Pt| local(c.at, angle, l);
    let probe = Item {
        label: String::new(),
        kind: Kind::Solid,
        footprint: rect(at(((a + t) * 0.5, (b + t) * 0.5)), (a + t, b + t), angle),
        parts: Vec::new(),
        seals: true,
    };
    let Some(fp) = shaped(&probe.footprint) else { return false };
    if !d.fits(&probe, &fp, &[], Some(region)) {
        return false;
    }
    let walls = vec![
        rect(at((a + t * 0.5, (b + t - SEAL) * 0.5)), (t, b + t + SEAL), angle),
        rect(at(((a + t * 0.5 - SEAL) * 0.5, b + t * 0.5)), (a + t * 0.5 + SEAL, t), angle),
    ];
    let label =
        format!("closet {a:.2} x {b:.2} m inside, door shut: walls {:.0} mm, a closed pocket", t * 1000.0);
    let wall =
        Item { label, kind: Kind::Wall, footprint: probe.footprint.clone(), parts: walls, seals: true };
    let inside = Item::clear(rect(at((a * 0.5, b * 0.5)), (a, b), angle));
    if !d.place(wall, None) {
        return false;
    }
    d.place(inside, None);
    d.facts.pockets += 1;
    true
}

/// A wardrobe, shelf or sofa standing across a right-angled corner, touching both walls: the
/// triangle behind it is a closed pocket. A sofa with probability `sofa_odds`.
fn across_corner(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], sofa_odds: f64) -> bool {
    let sofa = chance(rng, sofa_odds);
    let Some(c) = pick(rng, &right_corners(region)) else { return false };
    let (name, width, depth) = if sofa {
        ("sofa", uniform(rng, 1.6, 2.4), uniform(rng, 0.8, 1.0))
    } else {
        ("wardrobe", uniform(rng, 0.8, 2.4), uniform(rng, 0.55, 0.65))
    };
    let phi = uniform(rng, 35.0, 55.0).to_radians();
    let (p, q) = (width * phi.cos(), width * phi.sin());
    if p > c.len1 - 0.3 || q > c.len2 - 0.3 {
        return false;
    }
    let base = dir_deg(c.e1);
    let p1 = local(c.at, base, (p, 0.0));
    let p2 = local(c.at, base, (0.0, q));
    let along = unit(sub(p2, p1));
    let out = scale(left(along), -1.0);
    let center = add(scale(add(p1, p2), 0.5), scale(out, depth * 0.5));
    let mut item = Item::solid(
        format!("{name} {width:.2} x {depth:.2} m across a corner, a closed pocket behind it"),
        center,
        (width + 2.0 * SEAL, depth),
        dir_deg(along),
    );
    item.seals = true;
    if d.place(item, Some(region)) {
        d.facts.pockets += 1;
        return true;
    }
    false
}

// ---------------------------------------------------------------------------------------------
// Furniture placement.

/// Puts a `width` × `depth` piece with its back to a random edge of `region`, `gap` from it;
/// `build(centre, angle)` makes the piece (local x along the wall, local +y into the room).
/// Returns the centre and angle used.
fn against_wall(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    (width, depth): Pt,
    gap: Pt,
    build: &dyn Fn(Pt, f32) -> Item,
) -> Option<(Pt, f32)> {
    let n = region.len();
    let edges: Vec<usize> =
        (0..n).filter(|&i| length(sub(region[(i + 1) % n], region[i])) > width + 0.02).collect();
    for _ in 0..24 {
        let i = pick(rng, &edges)?;
        let (a, b) = (region[i], region[(i + 1) % n]);
        let (len, dir) = (length(sub(b, a)), unit(sub(b, a)));
        let t = uniform(rng, 0.005, len - width - 0.005);
        // Touching counts as overlapping: keep at least 2 mm.
        let g = uniform(rng, gap.0.max(0.002), gap.1);
        let center = add(add(a, scale(dir, t + width * 0.5)), scale(left(dir), g + depth * 0.5));
        let angle = tenth(dir_deg(dir));
        if d.place(build(center, angle), Some(region)) {
            return Some((center, angle));
        }
    }
    None
}

/// Puts a piece anywhere in `region`, turned by `angle(rng)`.
fn free_standing(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    angle: &dyn Fn(&mut ChaCha8Rng) -> f32,
    build: &dyn Fn(Pt, f32) -> Item,
) -> Option<(Pt, f32)> {
    let aabb = grid::room_aabb(region);
    let (x0, y0, x1, y1) = (aabb.mins.x, aabb.mins.y, aabb.maxs.x, aabb.maxs.y);
    for _ in 0..24 {
        let center = (uniform(rng, x0, x1), uniform(rng, y0, y1));
        if !grid::point_in_polygon(region, center.0, center.1) {
            continue;
        }
        let a = tenth(angle(rng));
        if d.place(build(center, a), Some(region)) {
            return Some((center, a));
        }
    }
    None
}

/// Any angle at all.
fn any_angle(rng: &mut ChaCha8Rng) -> f32 {
    uniform(rng, -180.0, 180.0)
}

/// Roughly square to the building: 0°, 90°, 180° or 270°, give or take 5°.
fn squarish(rng: &mut ChaCha8Rng) -> f32 {
    let quarter = rng.random_range(0..4u8);
    f32::from(quarter) * 90.0 + uniform(rng, -5.0, 5.0)
}

/// Half the time square to the building, otherwise any angle.
fn home_angle(rng: &mut ChaCha8Rng) -> f32 {
    if chance(rng, 0.5) { squarish(rng) } else { any_angle(rng) }
}

fn chair_item(rng: &mut ChaCha8Rng, center: Pt, angle: f32) -> Item {
    let size = (0.45, mm(uniform(rng, 0.45, 0.55)));
    let leg = mm(uniform(rng, 0.02, 0.04));
    let inset = mm(uniform(rng, 0.01, 0.03));
    let legs = if chance(rng, 0.8) { Legs::Round { d: leg, inset } } else { Legs::Square { s: leg, inset } };
    let label = format!("chair {:.2} x {:.2} m, {}", size.0, size.1, legs.describe());
    Item::legged(label, Kind::Seat, center, size, angle, legs)
}

/// A chair at side `side` of a table (0: local −y, 1: +y, 2: −x, 3: +x), `along` metres from
/// the middle of that side, pushed in or pulled out, usually turned 10–45°.
#[allow(clippy::too_many_arguments)]
fn chair_at(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    table: Pt,
    size: Pt,
    angle: f32,
    side: u8,
    along: f32,
) -> bool {
    for _ in 0..4 {
        let tuck = uniform(rng, -0.15, 0.25);
        let reach = |half: f32| half + 0.25 - tuck;
        let (l, face) = match side {
            0 => ((along, -reach(size.1 * 0.5)), 0.0),
            1 => ((along, reach(size.1 * 0.5)), 180.0),
            2 => ((-reach(size.0 * 0.5), along), -90.0),
            _ => ((reach(size.0 * 0.5), along), 90.0),
        };
        let turn =
            if chance(rng, 0.8) { sign(rng) * uniform(rng, 10.0, 45.0) } else { uniform(rng, -5.0, 5.0) };
        let item = chair_item(rng, local(table, angle, l), angle + face + turn);
        if d.place(item, Some(region)) {
            return true;
        }
    }
    false
}

/// A dining table (rectangular on four legs, or round on a pedestal) with `chairs` chairs.
fn dining(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], chairs: usize) {
    if chance(rng, 0.3) {
        let diameter = mm(uniform(rng, 0.9, 1.2));
        let base = mm(uniform(rng, 0.4, 0.6));
        let build = |c: Pt, _a: f32| Item {
            label: format!("round table {diameter:.2} m on a pedestal {base:.2} m"),
            kind: Kind::Legged,
            footprint: disc(c, diameter * 0.5),
            parts: vec![disc(c, base * 0.5)],
            seals: false,
        };
        let Some((c, _)) = free_standing(rng, d, region, &any_angle, &build) else { return };
        for k in 0..chairs {
            let a = k as f32 * 360.0 / chairs as f32 + uniform(rng, -20.0, 20.0);
            chair_at(rng, d, region, c, (diameter, diameter), a, 0, 0.0);
        }
        return;
    }
    let size = (mm(uniform(rng, 1.2, 2.0)), mm(uniform(rng, 0.8, 1.0)));
    let legs = Legs::draw(rng, 0.04, 0.08, 0.0);
    let build = |c: Pt, a: f32| {
        let label = format!("dining table {:.2} x {:.2} m, {}", size.0, size.1, legs.describe());
        Item::legged(label, Kind::Legged, c, size, a, legs)
    };
    let Some((c, a)) = free_standing(rng, d, region, &home_angle, &build) else { return };
    for k in 0..chairs {
        let side = [0u8, 1, 0, 1, 2, 3][k % 6];
        let along = if side < 2 { uniform(rng, -0.35, 0.35) * size.0 } else { 0.0 };
        chair_at(rng, d, region, c, size, a, side, along);
    }
}

/// A desk against a wall with a chair in front of it (most of the time).
fn desk_with_chair(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 1.0, 1.6)), mm(uniform(rng, 0.6, 0.8)));
    let legs = Legs::draw(rng, 0.03, 0.06, 0.4);
    let build = |c: Pt, a: f32| {
        let label = format!("desk {:.2} x {:.2} m, {}", size.0, size.1, legs.describe());
        Item::legged(label, Kind::Legged, c, size, a, legs)
    };
    if let Some((c, a)) = against_wall(rng, d, region, size, (0.0, 0.04), &build)
        && chance(rng, 0.85)
    {
        let along = uniform(rng, -0.25, 0.25);
        chair_at(rng, d, region, c, size, a, 1, along);
    }
}

/// Storage against a wall: a wardrobe, cabinet or shelf of real size.
fn storage(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], deep: bool) {
    let (name, width, depth) = match rng.random_range(0..3u8) {
        0 if deep => ("wardrobe", uniform(rng, 0.8, 2.4), uniform(rng, 0.55, 0.65)),
        1 => ("cabinet", uniform(rng, 0.6, 1.6), uniform(rng, 0.4, 0.6)),
        _ => ("shelf", uniform(rng, 0.6, 2.0), uniform(rng, 0.35, 0.45)),
    };
    let size = (mm(width), mm(depth));
    let gap = if chance(rng, 0.7) { (0.0, 0.015) } else { (0.015, 0.06) };
    let build = |c: Pt, a: f32| {
        Item::solid(format!("{name} {:.2} x {:.2} m against a wall", size.0, size.1), c, size, a)
    };
    against_wall(rng, d, region, size, gap, &build);
}

/// A bin, plant pot or floor lamp.
fn small_round(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let name = ["bin", "plant pot", "floor lamp"][rng.random_range(0..3usize)];
    let r = mm(uniform(rng, 0.1, 0.2));
    let build = |c: Pt, _a: f32| Item::round(format!("{name} {:.2} m across", 2.0 * r), c, r);
    free_standing(rng, d, region, &any_angle, &build);
}

fn sofa(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 1.6, 2.4)), mm(uniform(rng, 0.8, 1.0)));
    let build = |c: Pt, a: f32| Item::solid(format!("sofa {:.2} x {:.2} m", size.0, size.1), c, size, a);
    if chance(rng, 0.6) {
        against_wall(rng, d, region, size, (0.0, 0.1), &build);
    } else {
        free_standing(rng, d, region, &home_angle, &build);
    }
}

fn bed(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 0.9, 1.8)), mm(uniform(rng, 1.9, 2.1)));
    let build = |c: Pt, a: f32| {
        Item::solid(format!("bed {:.2} x {:.2} m, head to a wall", size.0, size.1), c, size, a)
    };
    against_wall(rng, d, region, size, (0.0, 0.03), &build);
}

fn counter(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt]) {
    let size = (mm(uniform(rng, 1.2, 3.6)), 0.6);
    let build = |c: Pt, a: f32| Item::solid(format!("kitchen counter {:.2} x 0.60 m", size.0), c, size, a);
    if against_wall(rng, d, region, size, (0.0, 0.01), &build).is_none() {
        let short = (mm(uniform(rng, 1.2, 1.8)), 0.6);
        let build =
            |c: Pt, a: f32| Item::solid(format!("kitchen counter {:.2} x 0.60 m", short.0), c, short, a);
        against_wall(rng, d, region, short, (0.0, 0.01), &build);
    }
}

/// What a room is used for, which decides its furniture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Use {
    Living,
    Bedroom,
    Kitchen,
    Small,
    Hall,
    Studio,
}

fn furnish(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], room_use: Use) {
    let area = polygon_area(region).abs();
    match room_use {
        Use::Living => {
            if chance(rng, 0.2) {
                across_corner(rng, d, region, 0.5);
            }
            sofa(rng, d, region);
            for _ in 0..rng.random_range(1..=2) {
                storage(rng, d, region, false);
            }
            if area >= 9.0 && chance(rng, 0.75) {
                let n = rng.random_range(2..=6);
                dining(rng, d, region, n);
            }
            for _ in 0..rng.random_range(1..=2) {
                small_round(rng, d, region);
            }
        }
        Use::Bedroom => {
            if chance(rng, 0.15) {
                across_corner(rng, d, region, 0.0);
            }
            bed(rng, d, region);
            storage(rng, d, region, true);
            if chance(rng, 0.5) {
                desk_with_chair(rng, d, region);
            }
            if chance(rng, 0.5) {
                small_round(rng, d, region);
            }
        }
        Use::Kitchen => {
            for _ in 0..rng.random_range(1..=2) {
                counter(rng, d, region);
            }
            if area >= 10.0 && chance(rng, 0.25) {
                let size = (mm(uniform(rng, 1.2, 2.4)), mm(uniform(rng, 0.9, 1.2)));
                let build = |c: Pt, a: f32| {
                    Item::solid(format!("kitchen island {:.2} x {:.2} m", size.0, size.1), c, size, a)
                };
                free_standing(rng, d, region, &squarish, &build);
            }
            if area >= 6.0 {
                let n = rng.random_range(2..=4);
                dining(rng, d, region, n);
            }
            small_round(rng, d, region);
        }
        Use::Small => {
            if chance(rng, 0.6) {
                storage(rng, d, region, false);
            }
            if chance(rng, 0.6) {
                small_round(rng, d, region);
            }
        }
        Use::Hall => {
            if chance(rng, 0.3) {
                let size = (mm(uniform(rng, 0.6, 1.2)), mm(uniform(rng, 0.35, 0.4)));
                let build = |c: Pt, a: f32| {
                    Item::solid(format!("hall cabinet {:.2} x {:.2} m", size.0, size.1), c, size, a)
                };
                against_wall(rng, d, region, size, (0.0, 0.02), &build);
            }
        }
        Use::Studio => {
            bed(rng, d, region);
            storage(rng, d, region, true);
            counter(rng, d, region);
            if area >= 12.0 {
                sofa(rng, d, region);
            }
            let n = rng.random_range(1..=3);
            dining(rng, d, region, n);
            if chance(rng, 0.5) {
                small_round(rng, d, region);
            }
        }
    }
}

/// Furnishes a room by its area, as in a flat.
fn furnish_by_area(rng: &mut ChaCha8Rng, d: &mut Draft, region: &[Pt], rank: usize, rooms: usize) {
    let area = polygon_area(region).abs();
    let room_use = if rooms == 1 {
        if area < 5.0 { Use::Small } else { Use::Studio }
    } else if area < 5.0 {
        Use::Small
    } else {
        [Use::Living, Use::Bedroom, Use::Kitchen, Use::Bedroom][rank.min(3)]
    };
    furnish(rng, d, region, room_use);
}

// ---------------------------------------------------------------------------------------------
// Styles.

/// An axis-aligned part of a flat: `outer` runs to the walls' centre lines (or the outline),
/// `inner` to their faces.
#[derive(Debug, Clone, Copy)]
struct Part {
    outer: [f32; 4],
    inner: [f32; 4],
    hall: bool,
}

impl Part {
    fn inner_poly(&self) -> Vec<Pt> {
        let [x0, y0, x1, y1] = self.inner;
        rect_outline(x0, y0, x1, y1)
    }
}

fn flat(rng: &mut ChaCha8Rng) -> Draft {
    let (w, h) = (mm(uniform(rng, 2.0, 10.0)), mm(uniform(rng, 2.0, 8.5)));
    let mut d = Draft::new(rect_outline(0.0, 0.0, w, h), "flat");
    let mut parts = Vec::new();
    let whole = [0.0, 0.0, w, h];
    split(rng, &mut d, Part { outer: whole, inner: whole, hall: false }, 0, &mut parts);
    d.facts.rooms = parts.len();
    if chance(rng, 0.3) {
        let rooms: Vec<usize> = (0..parts.len()).filter(|&i| !parts[i].hall).collect();
        if let Some(i) = pick(rng, &rooms) {
            closet(rng, &mut d, &parts[i].inner_poly());
        }
    }
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by(|&a, &b| {
        let area = |p: &Part| (p.inner[2] - p.inner[0]) * (p.inner[3] - p.inner[1]);
        area(&parts[b]).total_cmp(&area(&parts[a])).then(a.cmp(&b))
    });
    let rooms = parts.iter().filter(|p| !p.hall).count();
    let mut rank = 0;
    for i in order {
        let region = parts[i].inner_poly();
        if parts[i].hall {
            furnish(rng, &mut d, &region, Use::Hall);
        } else {
            furnish_by_area(rng, &mut d, &region, rank, rooms);
            rank += 1;
        }
    }
    d
}

/// Splits a part of a flat with an interior wall (with doors) and recurses, or keeps it as a room.
fn split(rng: &mut ChaCha8Rng, d: &mut Draft, part: Part, depth: u8, out: &mut Vec<Part>) {
    let [ix0, iy0, ix1, iy1] = part.inner;
    let (iw, ih) = (ix1 - ix0, iy1 - iy0);
    let long = iw.max(ih);
    let p = if depth == 0 { 0.85 } else { 0.5 };
    if part.hall || depth >= 2 || long < 4.2 || !chance(rng, p) {
        out.push(part);
        return;
    }
    let t = mm(uniform(rng, 0.07, 0.15));
    let hall = depth == 0 && iw.min(ih) >= 4.0 && chance(rng, 0.3);
    for _ in 0..8 {
        // A wall across the long side (rooms side by side), or along it to cut off a hall.
        let vertical = (iw >= ih) != hall;
        let (lo, hi) = if vertical { (ix0, ix1) } else { (iy0, iy1) };
        let at = if hall {
            let width = uniform(rng, 0.9, 1.2) + t * 0.5;
            if chance(rng, 0.5) { lo + width } else { hi - width }
        } else {
            uniform(rng, lo + 2.0 + t * 0.5, hi - 2.0 - t * 0.5)
        };
        let at = mm(at);
        let [ox0, oy0, ox1, oy1] = part.outer;
        let (span, inner_span) = if vertical { ((oy0, oy1), (iy0, iy1)) } else { ((ox0, ox1), (ix0, ix1)) };
        let inner_len = inner_span.1 - inner_span.0;
        let count = if hall {
            1 + (inner_len / 3.5) as usize
        } else {
            1 + usize::from(inner_len > 4.5 && chance(rng, 0.5))
        };
        let doors = draw_doors(rng, inner_span.0, inner_span.1, count);
        if doors.is_empty() {
            continue;
        }
        let (wall, zones) = wall_item(vertical, at, t, span, &doors);
        if !place_wall(d, wall, zones) {
            continue;
        }
        let (mut a, mut b) = (part, part);
        a.hall = false;
        b.hall = false;
        let (k_outer, k_inner) = if vertical { (2, 0) } else { (3, 1) };
        a.outer[k_outer] = at;
        a.inner[k_outer] = at - t * 0.5;
        b.outer[k_inner] = at;
        b.inner[k_inner] = at + t * 0.5;
        if hall {
            let a_is_hall = (a.inner[k_outer] - a.inner[k_inner]) < (b.inner[k_outer] - b.inner[k_inner]);
            a.hall = a_is_hall;
            b.hall = !a_is_hall;
        }
        split(rng, d, a, depth + 1, out);
        split(rng, d, b, depth + 1, out);
        return;
    }
    out.push(part);
}

fn office(rng: &mut ChaCha8Rng) -> Draft {
    let (w, h) = (mm(uniform(rng, 4.5, 12.5)), mm(uniform(rng, 4.0, 10.5)));
    let mut d = Draft::new(rect_outline(0.0, 0.0, w, h), "office");
    let mut open_top = h;
    // Cellular offices and meeting rooms behind a partition along the top.
    if w >= 6.0 && h >= 6.5 && chance(rng, 0.6) {
        let t = mm(uniform(rng, 0.07, 0.15));
        let at = mm(h - uniform(rng, 2.4, 3.5));
        let n = ((w / uniform(rng, 2.4, 4.0)) as usize).clamp(1, 4);
        let mut xs = vec![0.0];
        for k in 1..n {
            xs.push(mm(k as f32 * w / n as f32 + uniform(rng, -0.3, 0.3)));
        }
        xs.push(w);
        let store = if n >= 2 && chance(rng, 0.15) { Some(rng.random_range(0..n)) } else { None };
        let mut doors = Vec::new();
        for k in 0..n {
            let (a, b) = (
                xs[k] + if k > 0 { t * 0.5 } else { 0.0 },
                xs[k + 1] - if k + 1 < n { t * 0.5 } else { 0.0 },
            );
            if store != Some(k) {
                doors.extend(draw_doors(rng, a, b, 1));
            }
        }
        let (wall, zones) = wall_item(false, at, t, (0.0, w), &doors);
        if place_wall(&mut d, wall, zones) {
            open_top = at - t * 0.5;
            for &x in &xs[1..n] {
                let (wall, zones) = wall_item(true, x, t, (at, h), &[]);
                place_wall(&mut d, wall, zones);
            }
            for k in 0..n {
                let x0 = xs[k] + if k > 0 { t * 0.5 } else { 0.0 };
                let x1 = xs[k + 1] - if k + 1 < n { t * 0.5 } else { 0.0 };
                let region = rect_outline(x0, at + t * 0.5, x1, h);
                if store == Some(k) {
                    d.facts.pockets += 1;
                    for _ in 0..2 {
                        storage(rng, &mut d, &region, false);
                    }
                } else if chance(rng, 0.5) {
                    let n = rng.random_range(3..=6);
                    dining(rng, &mut d, &region, n);
                } else {
                    desk_with_chair(rng, &mut d, &region);
                    storage(rng, &mut d, &region, false);
                }
            }
            d.facts.rooms = n;
        }
    }
    d.facts.rooms += 1;
    // A corridor kept clear along the top of the open area.
    let corridor = mm(uniform(rng, 1.2, 2.0));
    d.place(Item::clear(rect((w * 0.5, open_top - corridor * 0.5), (w, corridor), 0.0)), None);
    let region = rect_outline(0.0, 0.0, w, open_top);
    // One desk model for the whole office.
    let desk = (mm(uniform(rng, 1.0, 1.6)), mm(uniform(rng, 0.6, 0.8)));
    let legs = Legs::draw(rng, 0.03, 0.06, 0.45);
    let aisle = uniform(rng, 1.6, 2.6);
    let mut y = if chance(rng, 0.3) { uniform(rng, 0.02, 0.06) } else { uniform(rng, 1.0, 1.6) };
    let mut first = true;
    loop {
        let double = !(first && y < 0.1) && chance(rng, 0.6);
        let depth = if double { 2.0 * desk.1 } else { desk.1 };
        // Room for the chairs between the last row and the corridor.
        if y + depth + 0.7 > open_top - corridor {
            break;
        }
        desk_row(rng, &mut d, &region, desk, legs, y, double, w, first && y < 0.1);
        y += depth + aisle + uniform(rng, -0.05, 0.05);
        first = false;
    }
    for _ in 0..rng.random_range(2..=4) {
        storage(rng, &mut d, &region, false);
    }
    for _ in 0..rng.random_range(1..=3) {
        small_round(rng, &mut d, &region);
    }
    d
}

/// One row of desk banks along x starting at height `y`: single (chairs above) or back to back.
#[allow(clippy::too_many_arguments)]
fn desk_row(
    rng: &mut ChaCha8Rng,
    d: &mut Draft,
    region: &[Pt],
    desk: Pt,
    legs: Legs,
    y: f32,
    double: bool,
    w: f32,
    against: bool,
) {
    let mut x = uniform(rng, 0.9, 1.8);
    while x + 2.0 * desk.0 < w - 0.9 {
        let n = rng.random_range(2..=4usize);
        for _ in 0..n {
            let cx = x + desk.0 * 0.5;
            if cx + desk.0 * 0.5 > w - 0.9 {
                break;
            }
            for row in 0..(1 + usize::from(double)) {
                let cy = y + desk.1 * (0.5 + row as f32) + if row == 1 { 0.02 } else { 0.0 };
                let label = format!("desk {:.2} x {:.2} m in a bank, {}", desk.0, desk.1, legs.describe());
                let item = Item::legged(label, Kind::Legged, (cx, cy), desk, 0.0, legs);
                if d.place(item, Some(region)) {
                    // Chairs on the open side: below the first row of a pair, above otherwise.
                    let side = if double && row == 0 { 0 } else { 1 };
                    if !(against && side == 0) && chance(rng, 0.9) {
                        let along = uniform(rng, -0.25, 0.25);
                        chair_at(rng, d, region, (mm(cx), mm(cy)), desk, 0.0, side, along);
                    }
                }
            }
            x += desk.0 + uniform(rng, 0.005, 0.03);
        }
        x += uniform(rng, 1.2, 2.0);
    }
}

fn warehouse(rng: &mut ChaCha8Rng) -> Draft {
    // Drawn with racks along x, then transposed half the time.
    let (l, w) = (mm(uniform(rng, 8.0, 14.5)), mm(uniform(rng, 6.0, 12.5)));
    let transpose = chance(rng, 0.5);
    let room = if transpose { rect_outline(0.0, 0.0, w, l) } else { rect_outline(0.0, 0.0, l, w) };
    let mut d = Draft::new(room, "warehouse");
    d.facts.rooms = 1;
    let flip = |p: Pt| if transpose { (p.1, p.0) } else { p };
    let region = d.room.clone();
    let depth = mm(uniform(rng, 0.4, 1.2));
    let aisle = uniform(rng, 1.0, 3.0);
    let cross = uniform(rng, 1.5, 3.0);
    let two_runs = l >= 2.0 * 5.0 + cross + 2.0 && chance(rng, 0.5);
    let (run, cross) = if two_runs {
        (uniform(rng, 5.0, ((l - cross - 2.0) * 0.5).min(10.0)), cross)
    } else {
        (uniform(rng, 5.0, 10.0).min(l - 2.0), 0.0)
    };
    let x_start = uniform(rng, 1.0, (l - run * if two_runs { 2.0 } else { 1.0 } - cross - 1.0).max(1.0));
    // Rows across the room: often a single rack against the first wall, then double or single
    // racks between aisles, and a single rack against the far wall when one fits there.
    let rack_row = |d: &mut Draft, y: f32, depth: f32, double: bool| {
        for k in 0..(1 + usize::from(two_runs)) {
            let x0 = x_start + k as f32 * (run + cross);
            let size = (mm(run), mm(depth));
            let center = flip((x0 + run * 0.5, y + depth * 0.5));
            let size = if transpose { (size.1, size.0) } else { size };
            let kind = if double { "back-to-back racks" } else { "rack" };
            let label = format!("{kind} {:.2} m long, {:.2} m deep", mm(run), mm(depth));
            if d.place(Item::solid(label, center, size, 0.0), Some(region.as_slice())) {
                d.facts.racks += 1;
            }
        }
    };
    let against_first = chance(rng, 0.6);
    let mut y = if against_first { uniform(rng, 0.02, 0.1) } else { aisle + uniform(rng, -0.05, 0.05) };
    let mut first = true;
    loop {
        let double = !(first && against_first) && chance(rng, 0.7);
        let rack_depth = if double { 2.0 * depth + uniform(rng, 0.0, 0.2) } else { depth };
        if y + rack_depth > w - 0.9 {
            break;
        }
        rack_row(&mut d, y, rack_depth, double);
        y += rack_depth + aisle + uniform(rng, -0.05, 0.05);
        first = false;
    }
    // y is now where the next rack would start, one aisle past the last one.
    let far = w - depth - uniform(rng, 0.02, 0.1);
    if far >= y - aisle + 1.0 && chance(rng, 0.6) {
        rack_row(&mut d, far, depth, false);
    }
    for _ in 0..rng.random_range(1..=4) {
        let size = (1.2, 0.8);
        let build = |c: Pt, a: f32| Item::solid("pallet 1.20 x 0.80 m".to_string(), c, size, a);
        free_standing(rng, &mut d, &region, &home_angle, &build);
    }
    for _ in 0..rng.random_range(0..=2) {
        small_round(rng, &mut d, &region);
    }
    d
}

fn pillars(rng: &mut ChaCha8Rng) -> Draft {
    let (w, h) = (mm(uniform(rng, 6.0, 14.0)), mm(uniform(rng, 6.0, 12.0)));
    let mut d = Draft::new(rect_outline(0.0, 0.0, w, h), "hall with pillars");
    d.facts.rooms = 1;
    let region = d.room.clone();
    let round = chance(rng, 0.5);
    let size = if round { mm(uniform(rng, 0.2, 0.5)) } else { mm(uniform(rng, 0.3, 0.6)) };
    let (sx, sy) = (uniform(rng, 5.0, 8.0), uniform(rng, 5.0, 8.0));
    let (ox, oy) = (uniform(rng, 0.8, sx.min(w - 0.8)), uniform(rng, 0.8, sy.min(h - 0.8)));
    let line = |o: f32, s: f32, max: f32| (0..).map(move |k| o + k as f32 * s).take_while(move |&v| v <= max);
    let xs: Vec<f32> = line(ox, sx, w - 0.8).collect();
    let ys: Vec<f32> = line(oy, sy, h - 0.8).collect();
    // Half-pillars engaged in the outer walls, where the structural grid meets them.
    if !round && chance(rng, 0.4) {
        let p = mm(uniform(rng, 0.1, 0.3));
        let mut engaged = Vec::new();
        for &x in &xs {
            engaged.push(((x, p * 0.5 - SEAL), (size, p + 2.0 * SEAL)));
            engaged.push(((x, h - p * 0.5 + SEAL), (size, p + 2.0 * SEAL)));
        }
        for &y in &ys {
            engaged.push(((p * 0.5 - SEAL, y), (p + 2.0 * SEAL, size)));
            engaged.push(((w - p * 0.5 + SEAL, y), (p + 2.0 * SEAL, size)));
        }
        for (c, s) in engaged {
            let fp = rect(c, s, 0.0);
            let label = format!("half-pillar {size:.2} m wide, {p:.2} m out of the wall");
            d.place(
                Item { label, kind: Kind::Wall, parts: vec![fp.clone()], footprint: fp, seals: true },
                None,
            );
        }
    }
    for &y in &ys {
        for &x in &xs {
            let item = if round {
                Item::round(format!("round pillar {size:.2} m across"), (x, y), size * 0.5)
            } else {
                Item::solid(format!("square pillar {size:.2} m"), (x, y), (size, size), 0.0)
            };
            if d.place(item, Some(region.as_slice())) {
                d.facts.pillars += 1;
            }
        }
    }
    if chance(rng, 0.1) {
        across_corner(rng, &mut d, &region, 0.5);
    }
    for _ in 0..rng.random_range(1..=3) {
        storage(rng, &mut d, &region, false);
    }
    if chance(rng, 0.6) {
        let n = rng.random_range(2..=6);
        dining(rng, &mut d, &region, n);
    }
    if chance(rng, 0.5) {
        sofa(rng, &mut d, &region);
    }
    if chance(rng, 0.4) {
        desk_with_chair(rng, &mut d, &region);
    }
    for _ in 0..rng.random_range(0..=3) {
        small_round(rng, &mut d, &region);
    }
    d
}

/// What happens at one corner of an irregular room's rectangle.
#[derive(Debug, Clone, Copy)]
enum CornerCut {
    /// Left square.
    None,
    /// Cut by a straight wall `a` back along the incoming side and `b` along the outgoing one
    /// (a = b: 45°).
    Chamfer(f32, f32),
    /// Moved `by` along the outgoing side: the incoming wall becomes slanted.
    Slant(f32),
    /// An L: a `p` × `q` rectangle cut out.
    Notch(f32, f32),
}

fn irregular_outline(rng: &mut ChaCha8Rng) -> Vec<Pt> {
    for _ in 0..32 {
        let (w, h) = (uniform(rng, 2.0, 7.5), uniform(rng, 2.0, 7.0));
        let corner_pts = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
        // Side i runs from corner i to corner i + 1; its length is w for even i, h for odd i.
        let side_len = |i: usize| if i % 2 == 0 { w } else { h };
        let mut cuts = [CornerCut::None; 4];
        let count = rng.random_range(1..=3usize);
        let mut notched = false;
        for _ in 0..count {
            let i = rng.random_range(0..4usize);
            let (incoming, outgoing) = (side_len((i + 3) % 4), side_len(i));
            let short = incoming.min(outgoing);
            cuts[i] = match rng.random_range(0..4u8) {
                0 => {
                    let a = uniform(rng, 0.3, (0.35 * short).min(1.5));
                    CornerCut::Chamfer(a, a)
                }
                1 => {
                    let a = uniform(rng, 0.3, (0.35 * short).min(1.5));
                    let b = a * uniform(rng, 30.0, 60.0).to_radians().tan();
                    CornerCut::Chamfer(a, b.min(0.4 * outgoing))
                }
                2 => CornerCut::Slant(uniform(rng, 0.3, (0.3 * outgoing).min(1.5))),
                _ if !notched && w >= 3.0 && h >= 3.0 => {
                    notched = true;
                    CornerCut::Notch(uniform(rng, 0.9, incoming - 0.9), uniform(rng, 0.9, outgoing - 0.9))
                }
                _ => CornerCut::Chamfer(0.3, 0.3),
            };
        }
        let bay_side = if chance(rng, 0.35) { Some(rng.random_range(0..4usize)) } else { None };
        let mut poly = Vec::new();
        for i in 0..4 {
            let v = corner_pts[i];
            let din = unit(sub(v, corner_pts[(i + 3) % 4]));
            let dout = unit(sub(corner_pts[(i + 1) % 4], v));
            match cuts[i] {
                CornerCut::None => poly.push(v),
                CornerCut::Chamfer(a, b) => {
                    poly.push(sub(v, scale(din, a)));
                    poly.push(add(v, scale(dout, b)));
                }
                CornerCut::Slant(by) => poly.push(add(v, scale(dout, by))),
                CornerCut::Notch(p, q) => {
                    let inner = sub(v, scale(din, p));
                    poly.push(inner);
                    poly.push(add(inner, scale(dout, q)));
                    poly.push(add(v, scale(dout, q)));
                }
            }
            // A bay window with 45° sides on side i, between plain or chamfered corners.
            let plain = |c: CornerCut| matches!(c, CornerCut::None | CornerCut::Chamfer(..));
            if bay_side == Some(i) && plain(cuts[i]) && plain(cuts[(i + 1) % 4]) {
                let len = side_len(i);
                let used = |c: CornerCut, first: bool| match c {
                    CornerCut::Chamfer(a, b) => {
                        if first {
                            b
                        } else {
                            a
                        }
                    }
                    _ => 0.0,
                };
                let (from, to) = (used(cuts[i], true) + 0.2, len - used(cuts[(i + 1) % 4], false) - 0.2);
                let bw = uniform(rng, 1.2, 2.4);
                let bd = uniform(rng, 0.4, 0.9);
                if to - from > bw && bw > 2.0 * bd + 0.3 {
                    let s = uniform(rng, from, to - bw);
                    let out = scale(left(dout), -1.0);
                    let p0 = add(v, scale(dout, s));
                    poly.push(p0);
                    poly.push(add(add(p0, scale(dout, bd)), scale(out, bd)));
                    poly.push(add(add(p0, scale(dout, bw - bd)), scale(out, bd)));
                    poly.push(add(p0, scale(dout, bw)));
                }
            }
        }
        let aabb = grid::room_aabb(&poly);
        let (x0, y0) = (aabb.mins.x, aabb.mins.y);
        let poly: Vec<Pt> = poly.iter().map(|&(x, y)| (mm(x - x0), mm(y - y0))).collect();
        if is_simple(&poly) {
            return poly;
        }
    }
    rect_outline(0.0, 0.0, 3.0, 3.0)
}

/// Whether a polygon is simple and counter-clockwise: no edge shorter than 5 cm, no edge folding
/// back, no two non-adjacent edges meeting.
fn is_simple(poly: &[Pt]) -> bool {
    let n = poly.len();
    let edge = |i: usize| (poly[i], poly[(i + 1) % n]);
    if (0..n).any(|i| length(sub(edge(i).1, edge(i).0)) < 0.05) || polygon_area(poly) <= 0.0 {
        return false;
    }
    // No wall folds back on the one before it.
    let folds = (0..n).any(|i| {
        let (a, b) = (unit(sub(edge(i).1, edge(i).0)), unit(sub(edge((i + 1) % n).1, edge((i + 1) % n).0)));
        a.0 * b.0 + a.1 * b.1 < -0.99
    });
    if folds {
        return false;
    }
    let cross = |o: Pt, a: Pt, b: Pt| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    for i in 0..n {
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let ((a, b), (c, e)) = (edge(i), edge(j));
            let (d1, d2) = (cross(c, e, a), cross(c, e, b));
            let (d3, d4) = (cross(a, b, c), cross(a, b, e));
            if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
                return false;
            }
        }
    }
    true
}

fn irregular(rng: &mut ChaCha8Rng) -> Draft {
    let outline = irregular_outline(rng);
    let mut d = Draft::new(outline, "irregular room");
    d.facts.rooms = 1;
    let region = d.room.clone();
    if chance(rng, 0.2) {
        closet(rng, &mut d, &region);
    } else if chance(rng, 0.2) {
        across_corner(rng, &mut d, &region, 0.4);
    }
    let area = polygon_area(&region).abs();
    let room_use = if area < 5.0 {
        Use::Small
    } else if area < 12.0 {
        pick(rng, &[Use::Bedroom, Use::Kitchen]).unwrap_or(Use::Bedroom)
    } else {
        pick(rng, &[Use::Living, Use::Studio]).unwrap_or(Use::Living)
    };
    furnish(rng, &mut d, &region, room_use);
    d
}

// ---------------------------------------------------------------------------------------------
// The scenario and its start cell.

fn finish(
    mut d: Draft,
    style: RoomStyle,
    seed: u64,
    sub_seed: u32,
    profile: &RobotProfile,
    rng: &mut ChaCha8Rng,
) -> Option<GeneratedRoom> {
    d.count_furniture();
    let pieces: Vec<Piece> = d
        .placed
        .iter()
        .filter(|p| p.item.kind != Kind::Clear)
        .map(|p| Piece {
            label: p.item.label.clone(),
            footprint: p.item.footprint.clone(),
            parts: p.item.parts.clone(),
        })
        .collect();
    let area = f64::from(polygon_area(&d.room).abs());
    let finish_s = ((SECONDS_PER_M2 * area / 60.0).ceil() * 60.0).max(MIN_FINISH_S);
    let (w, h) = grid::room_extent(&d.room);
    let f = &d.facts;
    let mut what = Vec::new();
    if f.rooms > 1 {
        what.push(format!("{} rooms", f.rooms));
    }
    for (n, one, many) in [
        (f.doors, "door", "doors"),
        (f.racks, "rack run", "rack runs"),
        (f.pillars, "pillar", "pillars"),
        (f.furniture, "piece of furniture", "pieces of furniture"),
        (f.pockets, "closed pocket", "closed pockets"),
    ] {
        match n {
            0 => {}
            1 => what.push(format!("1 {one}")),
            _ => what.push(format!("{n} {many}")),
        }
    }
    let description = format!(
        "Generated {} {w:.2} x {h:.2} m ({area:.1} m2): {}.",
        d.kind_name,
        if what.is_empty() { "empty".to_string() } else { what.join(", ") }
    );
    let mut scenario = Scenario {
        name: format!("gen-{}-{seed}", style.name()),
        description,
        robot: None,
        seed,
        cell: None,
        room: d.room.clone(),
        obstacles: pieces.iter().flat_map(|p| p.parts.iter().cloned()).collect(),
        start: Start { row: 0, col: 0, heading: Heading::East },
        physics: PhysicsSettings { max_sim_s: finish_s as f32, ..PhysicsSettings::default() },
        noise: Default::default(),
        links: Default::default(),
        faults: Vec::new(),
        mission: vec![Step::StartCartography, Step::WaitUntilMapped],
        expect: Expectations {
            coverage_min: Some(0.98),
            map_accuracy_min: Some(0.95),
            collisions_max: Some(0),
            finish_within_s: Some(finish_s),
            reached: None,
            position_error_max_m: Some(0.05),
            heading_error_max_deg: Some(3.0),
            believed_cell_true: Some(true),
        },
    };
    scenario.start = choose_start(&scenario, profile, rng)?;
    Some(GeneratedRoom { style, seed, sub_seed, pieces, scenario })
}

/// Every wall and obstacle of a scenario as parry shapes.
fn scenario_shapes(s: &Scenario) -> Vec<Shaped> {
    let n = s.room.len();
    (0..n)
        .map(|i| Obstacle::Segment { from: s.room[i], to: s.room[(i + 1) % n] })
        .chain(s.obstacles.iter().cloned())
        .filter_map(|o| shaped(&o))
        .collect()
}

/// Whether the robot can turn on the spot at `(x, y)`: its turning disc touches nothing.
fn can_turn(shapes: &[Shaped], profile: &RobotProfile, (x, y): Pt) -> bool {
    let g = &profile.geometry;
    let radius = 0.5 * g.body_length_m.hypot(g.body_width_m);
    let Some(disc) = shaped(&Obstacle::Circle { center: (x, y), radius }) else { return false };
    !shapes.iter().any(|s| near(s, &disc, 0.0))
}

/// Whether the body, facing the way it moves, can drive from `from` to `to` touching nothing.
fn can_drive(shapes: &[Shaped], profile: &RobotProfile, from: Pt, to: Pt) -> bool {
    let g = &profile.geometry;
    let along = length(sub(to, from));
    let swept = Obstacle::Box {
        center: scale(add(from, to), 0.5),
        size: (along + g.body_length_m, g.body_width_m),
        angle_deg: dir_deg(sub(to, from)),
    };
    let Some(swept) = shaped(&swept) else { return false };
    !shapes.iter().any(|s| near(s, &swept, 0.0))
}

/// A start cell where the robot can turn on the spot and drive to a free neighbour, drawn from
/// the largest connected free area first.
fn choose_start(s: &Scenario, profile: &RobotProfile, rng: &mut ChaCha8Rng) -> Option<Start> {
    let grid = RobotTruth::build(
        grid::room_frame(&s.room, s.cell_size(profile)),
        &s.room,
        &s.obstacle_shapes(),
        profile,
    );
    let shapes = scenario_shapes(s);
    let (rows, cols) = (grid.rows, grid.cols);
    let mut label = vec![usize::MAX; rows * cols];
    let mut areas: Vec<Vec<(usize, usize)>> = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            if grid.is_free(r, c) && label[r * cols + c] == usize::MAX {
                let reach = grid.reachable_from((r, c));
                let cells: Vec<(usize, usize)> =
                    (0..rows * cols).filter(|&k| reach[k]).map(|k| (k / cols, k % cols)).collect();
                for &(rr, cc) in &cells {
                    label[rr * cols + cc] = areas.len();
                }
                areas.push(cells);
            }
        }
    }
    let mut order: Vec<usize> = (0..areas.len()).collect();
    order.sort_by(|&a, &b| areas[b].len().cmp(&areas[a].len()).then(a.cmp(&b)));
    for k in order {
        let mut cells = areas[k].clone();
        for i in (1..cells.len()).rev() {
            cells.swap(i, rng.random_range(0..=i));
        }
        for (r, c) in cells {
            let centre = grid.frame.cell_center(r, c);
            if !can_turn(&shapes, profile, centre) {
                continue;
            }
            let neighbours = [(r.wrapping_sub(1), c), (r + 1, c), (r, c.wrapping_sub(1)), (r, c + 1)];
            let moves = neighbours.iter().any(|&(nr, nc)| {
                grid.is_free(nr, nc) && can_drive(&shapes, profile, centre, grid.frame.cell_center(nr, nc))
            });
            if !moves {
                continue;
            }
            let heading = pick(rng, &[Heading::North, Heading::East, Heading::South, Heading::West])?;
            return Some(Start { row: u8::try_from(r).ok()?, col: u8::try_from(c).ok()?, heading });
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// RON text.

fn fmt_pt((x, y): Pt) -> String {
    format!("({x:.3}, {y:.3})")
}

fn fmt_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or("None".to_string(), |v| format!("Some({v})"))
}

fn fmt_obstacle(o: &Obstacle) -> String {
    match o {
        Obstacle::Box { center, size, angle_deg } if *angle_deg == 0.0 => {
            format!("Box(center: {}, size: {})", fmt_pt(*center), fmt_pt(*size))
        }
        Obstacle::Box { center, size, angle_deg } => {
            format!("Box(center: {}, size: {}, angle_deg: {angle_deg:.1})", fmt_pt(*center), fmt_pt(*size))
        }
        Obstacle::Circle { center, radius } => {
            format!("Circle(center: {}, radius: {radius:.3})", fmt_pt(*center))
        }
        Obstacle::Segment { from, to } => format!("Segment(from: {}, to: {})", fmt_pt(*from), fmt_pt(*to)),
        Obstacle::Polygon { points } => {
            let pts: Vec<String> = points.iter().map(|p| fmt_pt(*p)).collect();
            format!("Polygon(points: [{}])", pts.join(", "))
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

    use std::sync::OnceLock;

    use super::*;
    use crate::grid::GridFrame;

    const SEEDS: std::ops::RangeInclusive<u64> = 1..=200;

    struct Sample {
        room: GeneratedRoom,
        text: String,
    }

    /// Every style × seeds 1..=200, generated once (one thread per style).
    fn corpus() -> &'static Vec<Sample> {
        static CORPUS: OnceLock<Vec<Sample>> = OnceLock::new();
        CORPUS.get_or_init(|| {
            std::thread::scope(|scope| {
                let jobs: Vec<_> = RoomStyle::ALL
                    .iter()
                    .map(|&style| {
                        scope.spawn(move || {
                            SEEDS
                                .map(|seed| {
                                    let room = generate(style, seed).unwrap_or_else(|e| panic!("{e}"));
                                    let text = room.to_ron();
                                    Sample { room, text }
                                })
                                .collect::<Vec<_>>()
                        })
                    })
                    .collect();
                jobs.into_iter().flat_map(|j| j.join().unwrap()).collect()
            })
        })
    }

    fn of(style: RoomStyle) -> impl Iterator<Item = &'static Sample> {
        corpus().iter().filter(move |s| s.room.style() == style)
    }

    fn id(s: &Sample) -> String {
        format!("{} seed {}", s.room.style().name(), s.room.seed())
    }

    #[test]
    fn same_style_and_seed_give_the_same_bytes() {
        for s in corpus().iter().filter(|s| s.room.seed() <= 25) {
            assert_eq!(generate(s.room.style(), s.room.seed()).unwrap().to_ron(), s.text, "{}", id(s));
        }
        // Different seeds and styles give different rooms.
        let a = &corpus()[0].text;
        assert!(corpus().iter().skip(1).all(|s| &s.text != a));
    }

    #[test]
    fn every_room_passes_the_check_and_round_trips() {
        for s in corpus() {
            let label = format!("{}.ron", id(s));
            let loaded = LoadedScenario::from_ron_str(&s.text, &label, Path::new("."))
                .unwrap_or_else(|e| panic!("{e}\n{}", s.text));
            assert_eq!(&loaded.scenario, s.room.scenario(), "{label}");
            let sc = s.room.scenario();
            assert_eq!(sc.mission, vec![Step::StartCartography, Step::WaitUntilMapped]);
            assert_eq!(sc.expect.coverage_min, Some(0.98));
            assert_eq!(sc.expect.map_accuracy_min, Some(0.95));
            assert_eq!(sc.expect.collisions_max, Some(0));
            assert_eq!(sc.expect.position_error_max_m, Some(0.05));
            assert_eq!(sc.expect.heading_error_max_deg, Some(3.0));
            assert_eq!(sc.expect.believed_cell_true, Some(true));
            let area = f64::from(polygon_area(&sc.room).abs());
            let limit = sc.expect.finish_within_s.unwrap();
            assert!(
                limit >= MIN_FINISH_S
                    && limit >= SECONDS_PER_M2 * area
                    && limit < SECONDS_PER_M2 * area + MIN_FINISH_S,
                "{label}: {limit} s"
            );
            assert_eq!(f64::from(sc.physics.max_sim_s), limit);
            assert!(s.text.starts_with(&format!(
                "// Generated by `explobot generate --style {} --seed {}`.",
                s.room.style().name(),
                s.room.seed()
            )));
        }
    }

    /// Distance from `p` to an obstacle (0 inside), computed without parry.
    fn distance_to(o: &Obstacle, p: Pt) -> f32 {
        let to_segment = |a: Pt, b: Pt| {
            let ab = sub(b, a);
            let t = ((p.0 - a.0) * ab.0 + (p.1 - a.1) * ab.1) / (ab.0 * ab.0 + ab.1 * ab.1);
            length(sub(p, add(a, scale(ab, t.clamp(0.0, 1.0)))))
        };
        match o {
            Obstacle::Box { center, size, angle_deg } => {
                let l = local((0.0, 0.0), -angle_deg, sub(p, *center));
                let dx = (l.0.abs() - size.0 * 0.5).max(0.0);
                let dy = (l.1.abs() - size.1 * 0.5).max(0.0);
                dx.hypot(dy)
            }
            Obstacle::Circle { center, radius } => (length(sub(p, *center)) - radius).max(0.0),
            Obstacle::Segment { from, to } => to_segment(*from, *to),
            Obstacle::Polygon { .. } => panic!("the generator writes no polygons"),
        }
    }

    fn wall_distance(room: &[Pt], p: Pt) -> f32 {
        (0..room.len())
            .map(|i| distance_to(&Obstacle::Segment { from: room[i], to: room[(i + 1) % room.len()] }, p))
            .fold(f32::MAX, f32::min)
    }

    #[test]
    fn the_robot_can_turn_in_its_start_cell_and_move_to_a_neighbour() {
        let profile = RobotProfile::default();
        let g = &profile.geometry;
        let radius = 0.5 * g.body_length_m.hypot(g.body_width_m);
        assert!((radius - 0.177).abs() < 0.001);
        for s in corpus() {
            let sc = s.room.scenario();
            let grid = RobotTruth::build(
                grid::room_frame(&sc.room, sc.cell_size(&profile)),
                &sc.room,
                &sc.obstacle_shapes(),
                &profile,
            );
            let (r, c) = (usize::from(sc.start.row), usize::from(sc.start.col));
            let centre = grid.frame.cell_center(r, c);
            let clearance = sc.obstacles.iter().map(|o| distance_to(o, centre)).fold(f32::MAX, f32::min);
            assert!(clearance.min(wall_distance(&sc.room, centre)) > radius, "{}", id(s));
            // Necessary for the swept body: its width clears the path to a free neighbour.
            let neighbours = [(r.wrapping_sub(1), c), (r + 1, c), (r, c.wrapping_sub(1)), (r, c + 1)];
            let ok = neighbours.iter().any(|&(nr, nc)| {
                grid.is_free(nr, nc)
                    && (0..=10).all(|k| {
                        let p =
                            add(centre, scale(sub(grid.frame.cell_center(nr, nc), centre), k as f32 / 10.0));
                        let d = sc.obstacles.iter().map(|o| distance_to(o, p)).fold(f32::MAX, f32::min);
                        d.min(wall_distance(&sc.room, p)) > g.body_width_m * 0.5
                    })
            });
            assert!(ok, "{}: no neighbour to move to", id(s));
        }
    }

    #[test]
    fn sizes_span_small_rooms_to_large_halls() {
        let extents: Vec<(RoomStyle, Pt)> =
            corpus().iter().map(|s| (s.room.style(), grid::room_extent(&s.room.scenario().room))).collect();
        assert!(extents.iter().all(|&(_, (w, h))| w >= 2.0 && h >= 2.0));
        let small = extents.iter().filter(|&&(_, (w, h))| w <= 3.0 && h <= 3.0).count();
        let large = extents.iter().filter(|&&(_, (w, h))| w >= 10.0 && h >= 10.0).count();
        assert!(small >= 5, "{small} rooms of 3 x 3 m or less");
        assert!(large >= 20, "{large} rooms of 10 x 10 m or more");
        for (style, lo, hi) in [
            (RoomStyle::Flat, 2.0, 10.0),
            (RoomStyle::Office, 4.0, 12.5),
            (RoomStyle::Warehouse, 6.0, 14.5),
            (RoomStyle::Pillars, 6.0, 14.0),
            (RoomStyle::Irregular, 2.0, 10.0),
        ] {
            for &(_, (w, h)) in extents.iter().filter(|(s, _)| *s == style) {
                assert!(w >= lo && h >= lo && w <= hi && h <= hi, "{style:?}: {w} x {h}");
            }
        }
    }

    /// Whether an obstacle lies on the grid: an axis-aligned box with every edge within 2 mm of
    /// a grid line, or a disc centred within 2 mm of a cell centre or corner.
    fn on_grid(frame: &GridFrame, o: &Obstacle) -> bool {
        let on_line = |v: f32, origin: f32| {
            let k = (v - origin) / frame.cell;
            (k - k.round()).abs() * frame.cell < 0.002
        };
        let on_half = |v: f32, origin: f32| on_line(v, origin) || on_line(v, origin + frame.cell * 0.5);
        match o {
            Obstacle::Box { center, size, angle_deg } => {
                *angle_deg % 90.0 == 0.0
                    && [center.0 - size.0 * 0.5, center.0 + size.0 * 0.5]
                        .iter()
                        .all(|&x| on_line(x, frame.left))
                    && [center.1 - size.1 * 0.5, center.1 + size.1 * 0.5]
                        .iter()
                        .all(|&y| on_line(y, frame.top))
            }
            Obstacle::Circle { center, .. } => {
                on_half(center.0, frame.left)
                    && on_half(center.1, frame.top)
                    && on_line(center.0, frame.left) == on_line(center.1, frame.top)
            }
            _ => false,
        }
    }

    #[test]
    fn nothing_is_aligned_with_the_grid() {
        let (mut total, mut aligned) = (0, 0);
        for s in corpus() {
            let sc = s.room.scenario();
            let frame = grid::room_frame(&sc.room, RobotProfile::default().grid_cell_m);
            let flags: Vec<bool> = sc.obstacles.iter().map(|o| on_grid(&frame, o)).collect();
            assert!(flags.iter().any(|a| !a), "{}: every obstacle is on the grid", id(s));
            total += flags.len();
            aligned += flags.iter().filter(|a| **a).count();
        }
        assert!(aligned * 100 < total, "{aligned} of {total} obstacles on the grid");
    }

    fn turned(o: &Obstacle) -> bool {
        matches!(o, Obstacle::Box { angle_deg, .. } if (angle_deg.rem_euclid(90.0) - 45.0).abs() < 44.0)
    }

    /// The share of `style`'s rooms where `has` holds.
    fn share(style: RoomStyle, has: impl Fn(&Sample) -> bool) -> f64 {
        let (n, yes) = of(style).fold((0, 0), |(n, y), s| (n + 1, y + usize::from(has(s))));
        yes as f64 / n as f64
    }

    #[test]
    fn furniture_is_turned_and_walls_are_slanted_where_rooms_have_them() {
        let chair_turned_10_to_45 = |s: &Sample| {
            s.room.pieces().iter().any(|p| {
                let a = match p.footprint {
                    Obstacle::Box { angle_deg, .. } => angle_deg.rem_euclid(90.0),
                    _ => 0.0,
                };
                p.label.starts_with("chair") && (10.0..=80.0).contains(&a)
            })
        };
        let any_turned = |s: &Sample| s.room.pieces().iter().any(|p| turned(&p.footprint));
        let slanted_wall = |s: &Sample| {
            let room = &s.room.scenario().room;
            (0..room.len()).any(|i| {
                let d = sub(room[(i + 1) % room.len()], room[i]);
                d.0.abs() > 0.01 && d.1.abs() > 0.01
            })
        };
        assert!(share(RoomStyle::Office, chair_turned_10_to_45) > 0.8);
        assert!(share(RoomStyle::Flat, any_turned) > 0.6);
        assert!(share(RoomStyle::Pillars, any_turned) > 0.5);
        assert!(share(RoomStyle::Warehouse, any_turned) > 0.3);
        assert!(share(RoomStyle::Irregular, |s| slanted_wall(s) || any_turned(s)) > 0.9);
        assert!(share(RoomStyle::Irregular, slanted_wall) > 0.6);
        // Never a plain rectangle.
        assert!(share(RoomStyle::Irregular, |s| s.room.scenario().room.len() > 4 || slanted_wall(s)) == 1.0);
        // Every outline feature of the irregular style shows up.
        let outline_has = |angle: f32| {
            share(RoomStyle::Irregular, |s| {
                let room = &s.room.scenario().room;
                (0..room.len()).any(|i| {
                    let d = sub(room[(i + 1) % room.len()], room[i]);
                    (dir_deg(d).rem_euclid(90.0) - angle).abs() < 0.5 && length(d) > 0.2
                })
            })
        };
        assert!(outline_has(45.0) > 0.2, "45 degree chamfers and bays");
        assert!(
            share(RoomStyle::Irregular, |s| s.room.scenario().room.len() >= 6 && !slanted_wall(s)) > 0.03,
            "L shapes"
        );
    }

    #[test]
    fn thin_legs_pillars_and_racks_appear() {
        let thin_leg = |s: &Sample| {
            s.room.scenario().obstacles.iter().any(|o| match o {
                Obstacle::Circle { radius, .. } => *radius <= 0.04,
                Obstacle::Box { size, .. } => size.0.min(size.1) <= 0.08 && size.0.max(size.1) <= 0.08,
                _ => false,
            })
        };
        assert!(share(RoomStyle::Flat, thin_leg) > 0.5);
        assert!(share(RoomStyle::Office, thin_leg) > 0.8);
        assert!(
            share(RoomStyle::Pillars, |s| s.room.pieces().iter().any(|p| p.label.contains("pillar"))) == 1.0
        );
        assert!(
            share(RoomStyle::Warehouse, |s| s
                .room
                .pieces()
                .iter()
                .filter(|p| p.label.contains("rack"))
                .count()
                >= 2)
                > 0.9
        );
        assert!(share(RoomStyle::Flat, |s| s.room.pieces().iter().any(|p| p.label.contains("door"))) > 0.6);
    }

    #[test]
    fn some_rooms_have_closed_pockets() {
        let profile = RobotProfile::default();
        let pocket = |s: &Sample| {
            let sc = s.room.scenario();
            let grid = RobotTruth::build(
                grid::room_frame(&sc.room, sc.cell_size(&profile)),
                &sc.room,
                &sc.obstacle_shapes(),
                &profile,
            );
            let reach = grid.reachable_from((usize::from(sc.start.row), usize::from(sc.start.col)));
            (0..grid.rows).any(|r| (0..grid.cols).any(|c| grid.is_free(r, c) && !reach[r * grid.cols + c]))
        };
        let labelled = |s: &Sample| s.room.pieces().iter().any(|p| p.label.contains("closed pocket"));
        assert!(share(RoomStyle::Flat, labelled) > 0.1);
        assert!(share(RoomStyle::Flat, pocket) > 0.1);
        assert!(share(RoomStyle::Irregular, pocket) > 0.05);
    }

    #[test]
    fn furniture_stands_clear_of_other_furniture_and_inside_the_room() {
        for s in corpus() {
            let sc = s.room.scenario();
            let furniture: Vec<&Piece> = s
                .room
                .pieces()
                .iter()
                .filter(|p| {
                    !p.label.starts_with("interior wall")
                        && !p.label.contains("half-pillar")
                        && !p.label.starts_with("closet")
                })
                .collect();
            for p in &furniture {
                for part in &p.parts {
                    let inside =
                        corners(part, 0.015).iter().all(|&(x, y)| grid::point_in_polygon(&sc.room, x, y));
                    assert!(inside, "{}: {} pokes out of the room", id(s), p.label);
                }
            }
            for (i, a) in furniture.iter().enumerate() {
                for b in &furniture[i + 1..] {
                    let (fa, fb) = (shaped(&a.footprint).unwrap(), shaped(&b.footprint).unwrap());
                    let chair_under = [(a, b), (b, a)]
                        .iter()
                        .any(|(x, y)| x.label.starts_with("chair") && !y.label.starts_with("chair"));
                    if chair_under {
                        let parts =
                            |p: &Piece| p.parts.iter().map(|o| shaped(o).unwrap()).collect::<Vec<_>>();
                        let (pa, pb) = (parts(a), parts(b));
                        assert!(
                            !pa.iter().any(|x| pb.iter().any(|y| near(x, y, 0.0))),
                            "{}: {} / {}",
                            id(s),
                            a.label,
                            b.label
                        );
                    } else {
                        assert!(!near(&fa, &fb, 0.0), "{}: {} overlaps {}", id(s), a.label, b.label);
                    }
                }
            }
        }
    }

    #[test]
    fn doors_are_passable_by_a_person() {
        for s in of(RoomStyle::Flat).chain(of(RoomStyle::Office)) {
            for p in s.room.pieces().iter().filter(|p| p.label.starts_with("interior wall")) {
                // Every wall of a flat has a door: its rooms connect.
                assert!(
                    s.room.style() != RoomStyle::Flat || !p.label.ends_with("no door"),
                    "{}: {}",
                    id(s),
                    p.label
                );
                for part in p.label.split(", ").last().unwrap().split(" and ") {
                    if let Some(width) = part.strip_suffix(" m door").or_else(|| part.strip_suffix(" m")) {
                        let w: f32 = width.parse().unwrap();
                        assert!(
                            (0.70..=0.90).contains(&w) || (1.2..=1.6).contains(&w),
                            "{}: {}",
                            id(s),
                            p.label
                        );
                    }
                }
            }
        }
    }
}
