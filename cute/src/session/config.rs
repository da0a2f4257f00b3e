//! What a session is set up with: the map, the start pose, which Carto is on the other end
//! ([`Compat`]), the move timeout, and why a session or an action can be refused ([`CuteError`]).
//!
//! Concept: [`Compat`] is the one place that knows how the original 2024 Carto differs — the
//! `Msg` byte order ([`Compat::msg_order`]) and the largest trajectory batch
//! ([`Compat::max_batch`]). Its names (`default`, alias `none`, and `explobot-2024`) are
//! [`Compat::NAMES`], which [`FromStr`] reads; with the feature `cli` clap's `ValueEnum` derive
//! gives the command line the same names (a test checks that they agree).
//!
//! [`CuteConfig::map`] is a known map to start from (`--map FILE`, [`crate::map_file`]);
//! [`CuteConfig::with_map`] takes its size and robot cell.
//!
//! `--compat explobot-2024` in short (details in [`super`] and [`super::quirks`]): `Msg`
//! little-endian; no SEND_ROBOT_POSITION nor SEND_MOVE_CARTOGRAPHY (they crash the original);
//! batches of at most 50 commands, fire-and-forget (the original answers nothing); a click plans
//! through unknown cells as if free, with a warning; after a STOP the original drops the next
//! batch, so Cute keeps the robot where it was and warns when it sends that batch.
//!
//! Invariants: `Compat::max_batch() <= MAX_BATCH`, so a batch length always fits the one-byte
//! `n_total`.
//!
//! ```
//! use cute::session::{Compat, MAX_BATCH_COMPAT};
//! use protocol::link::MsgOrder;
//! assert_eq!("explobot-2024".parse::<Compat>(), Ok(Compat::Explobot2024));
//! assert_eq!("none".parse::<Compat>(), Ok(Compat::Default));
//! assert!("explobot-2023".parse::<Compat>().is_err());
//! assert_eq!(Compat::Explobot2024.msg_order(), MsgOrder::LittleEndian);
//! assert_eq!(Compat::Explobot2024.max_batch(), MAX_BATCH_COMPAT);
//! ```

use std::str::FromStr;

use protocol::link::{self, MsgOrder};
use robot_model::grid::Heading;
use robot_model::time::Duration;
use thiserror::Error;

use super::Status;
use crate::cartography::CartoError;
use crate::map::{Map, MapError};

/// Largest trajectory batch on the wire (`n_total` is one byte).
pub const MAX_BATCH: usize = 255;
/// Largest batch the original Carto accepts (`--compat explobot-2024`).
pub const MAX_BATCH_COMPAT: usize = 50;

/// Which Carto the session talks to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Compat {
    /// Our Carto: big-endian `Msg`, the full protocol.
    #[default]
    #[cfg_attr(feature = "cli", value(name = "default", alias = "none"))]
    Default,
    /// The original 2024 Carto: little-endian `Msg`, trajectories only, batches ≤ 50, clicks
    /// planned through unknown cells, the batch after a STOP dropped.
    #[cfg_attr(feature = "cli", value(name = "explobot-2024"))]
    Explobot2024,
}

impl Compat {
    /// Every name a compat mode is given by, with its mode (the first for each is its own).
    pub const NAMES: [(&'static str, Compat); 3] =
        [("default", Compat::Default), ("none", Compat::Default), ("explobot-2024", Compat::Explobot2024)];

    /// The byte order of the `Msg` field this Carto speaks.
    pub fn msg_order(self) -> MsgOrder {
        match self {
            Compat::Default => MsgOrder::BigEndian,
            Compat::Explobot2024 => MsgOrder::LittleEndian,
        }
    }

    /// True if a click plans through unknown cells as if they were free: the original Carto cannot
    /// map, so with it the map is unknown unless `--map` loads one.
    pub fn plans_through_unknown(self) -> bool {
        self == Compat::Explobot2024
    }

    /// The largest trajectory batch this Carto accepts.
    pub fn max_batch(self) -> usize {
        match self {
            Compat::Default => MAX_BATCH,
            Compat::Explobot2024 => MAX_BATCH_COMPAT,
        }
    }
}

impl FromStr for Compat {
    type Err = CuteError;
    /// Parses [`Compat::NAMES`] (case-sensitive): `default`, `none`, `explobot-2024`.
    fn from_str(s: &str) -> Result<Compat, CuteError> {
        Compat::NAMES
            .iter()
            .find(|(name, _)| *name == s)
            .map(|&(_, compat)| compat)
            .ok_or_else(|| CuteError::UnknownCompat { name: s.to_string() })
    }
}

/// Session settings.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CuteConfig {
    /// Map rows (1..=256).
    pub rows: usize,
    /// Map columns (1..=256).
    pub cols: usize,
    /// The robot's starting cell `(x, y)`.
    pub start: (u8, u8),
    /// The robot's starting heading.
    pub heading: Heading,
    /// Which Carto is on the other end.
    pub compat: Compat,
    /// How long one move may take before [`super::CuteEvent::MoveTimeout`] (per command in a
    /// batch). The default, 50 s, is above the longest move our Carto can make: a mapping turn
    /// may be six motions before its MOVE_DONE (facing the grid heading again after a cut
    /// rotation, a shift clear of an echo, the turn, and either the turn back when it fails or,
    /// made off the centre, the look past it, the look back and the drive back to the centre),
    /// each ended by Carto's own 8 s limit (`CartoConfig.motion.move_timeout`). With 5 s, a shift and a
    /// turn whose settle nudges repeat over a slow, lossy motor link ran out while Carto was
    /// still within its limits, and Cute stopped a mapping that would have finished.
    pub move_timeout: Duration,
    /// How long ROBOT_POSITION_RECEIVED may take before the position is sent again (5 s).
    pub ack_timeout: Duration,
    /// Largest incoming `Size` accepted.
    pub max_frame: usize,
    /// A known map to start from instead of an all-unknown one; it must be `rows × cols`
    /// (waypoints and the destination are read as free, the robot is put at `start`).
    pub map: Option<Map>,
}

impl CuteConfig {
    /// Starts from the known `map`: its size, and its robot cell (5) as the start if it marks
    /// one. `start` is the start the user gave, if any: it is used when the map marks no robot,
    /// and must agree with the map's robot cell otherwise.
    pub fn with_map(self, map: Map, start: Option<(u8, u8)>) -> Result<CuteConfig, CuteError> {
        let start = match (map.robot(), start) {
            (Some(on_map), Some(given)) if on_map != given => {
                return Err(CuteError::StartConflict { on_map, given });
            }
            (Some(on_map), _) => on_map,
            (None, given) => given.unwrap_or(self.start),
        };
        Ok(CuteConfig { rows: map.rows(), cols: map.cols(), start, map: Some(map), ..self })
    }
}

impl Default for CuteConfig {
    fn default() -> Self {
        CuteConfig {
            rows: 20,
            cols: 20,
            start: (0, 0),
            heading: Heading::East,
            compat: Compat::Default,
            move_timeout: Duration::from_secs(50),
            ack_timeout: Duration::from_secs(5),
            max_frame: link::DEFAULT_MAX_FRAME,
            map: None,
        }
    }
}

/// Why a session action was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum CuteError {
    /// The map size is invalid.
    #[error("bad map: {0}")]
    Map(#[from] MapError),
    /// The start cell is outside the map.
    #[error("bad start: {0}")]
    Start(#[from] CartoError),
    /// The known map's size differs from `rows × cols`.
    #[error("the map is {map_rows}x{map_cols}, the session {rows}x{cols}")]
    MapSize {
        /// Session rows.
        rows: usize,
        /// Session columns.
        cols: usize,
        /// Map rows.
        map_rows: usize,
        /// Map columns.
        map_cols: usize,
    },
    /// The start cell is an obstacle on the known map.
    #[error("the start cell ({x}, {y}) is an obstacle on the map")]
    StartBlocked {
        /// Row.
        x: u8,
        /// Column.
        y: u8,
    },
    /// The map marks the robot (5) in another cell than the start given.
    #[error("the map puts the robot at {on_map:?}, the start given is {given:?}")]
    StartConflict {
        /// The map's robot cell.
        on_map: (u8, u8),
        /// The start given.
        given: (u8, u8),
    },
    /// The action is not possible with the original Carto.
    #[error("{what} is not supported with --compat explobot-2024")]
    Unsupported {
        /// The refused action.
        what: &'static str,
    },
    /// Another mission is running; stop it first.
    #[error("busy: {status:?}")]
    Busy {
        /// The current status.
        status: Status,
    },
    /// A compatibility mode name that does not exist.
    #[error("unknown compat mode {name:?} (expected default, none or explobot-2024)")]
    UnknownCompat {
        /// The name given.
        name: String,
    },
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[cfg(feature = "cli")]
    #[test]
    fn the_command_line_and_from_str_know_the_same_compat_names() {
        use clap::ValueEnum;
        for (name, compat) in Compat::NAMES {
            assert_eq!(<Compat as ValueEnum>::from_str(name, false), Ok(compat), "{name}");
            assert_eq!(name.parse::<Compat>().ok(), Some(compat), "{name}");
        }
        for compat in Compat::value_variants() {
            let names = compat.to_possible_value().unwrap();
            for name in names.get_name_and_aliases() {
                assert_eq!(name.parse::<Compat>().ok(), Some(*compat), "{name}");
            }
        }
    }

    #[test]
    fn every_compat_has_one_name_that_parses_back() {
        for c in [Compat::Default, Compat::Explobot2024] {
            let (name, _) = Compat::NAMES.iter().find(|(_, m)| *m == c).unwrap();
            assert_eq!(name.parse::<Compat>(), Ok(c));
        }
        assert_eq!(
            "Explobot-2024".parse::<Compat>(),
            Err(CuteError::UnknownCompat { name: "Explobot-2024".into() })
        );
    }

    #[test]
    fn issue_14_a_known_map_gives_size_and_start() {
        let map = Map::parse("111\n150\n").unwrap();
        let c = CuteConfig::default().with_map(map.clone(), None).unwrap();
        assert_eq!((c.rows, c.cols, c.start, c.map.as_ref()), (2, 3, (1, 1), Some(&map)));
        assert_eq!(CuteConfig::default().with_map(map.clone(), Some((1, 1))).unwrap().start, (1, 1));
        assert_eq!(
            CuteConfig::default().with_map(map, Some((0, 0))),
            Err(CuteError::StartConflict { on_map: (1, 1), given: (0, 0) })
        );
        let unmarked = Map::parse("111\n110\n").unwrap();
        assert_eq!(CuteConfig::default().with_map(unmarked.clone(), Some((0, 2))).unwrap().start, (0, 2));
        assert_eq!(CuteConfig::default().with_map(unmarked, None).unwrap().start, (0, 0));
    }

    #[test]
    fn batches_always_fit_the_one_byte_count() {
        for (_, c) in Compat::NAMES {
            assert!(c.max_batch() <= MAX_BATCH && MAX_BATCH <= usize::from(u8::MAX));
        }
    }
}
