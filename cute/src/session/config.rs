//! What a session is set up with: the map, the start pose, which Carto is on the other end
//! ([`Compat`]), the move timeout, and why a session or an action can be refused ([`CuteError`]).
//!
//! Concept: [`Compat`] is the one place that knows how the original 2024 Carto differs — the
//! `Msg` byte order ([`Compat::msg_order`]) and the largest trajectory batch
//! ([`Compat::max_batch`]). Its names (`default`, alias `none`, and `explobot-2024`) come from one
//! table, the [`clap::ValueEnum`] derive, which also serves [`FromStr`].
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

use clap::ValueEnum;
use protocol::link::{self, MsgOrder};
use robot_model::grid::Heading;
use robot_model::time::Duration;
use thiserror::Error;

use super::Status;
use crate::cartography::CartoError;
use crate::map::MapError;

/// Largest trajectory batch on the wire (`n_total` is one byte).
pub const MAX_BATCH: usize = 255;
/// Largest batch the original Carto accepts (`--compat explobot-2024`).
pub const MAX_BATCH_COMPAT: usize = 50;

/// Which Carto the session talks to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum Compat {
    /// Our Carto: big-endian `Msg`, the full protocol.
    #[default]
    #[value(name = "default", alias = "none")]
    Default,
    /// The original 2024 Carto: little-endian `Msg`, trajectories only, batches ≤ 50.
    #[value(name = "explobot-2024")]
    Explobot2024,
}

impl Compat {
    /// The byte order of the `Msg` field this Carto speaks.
    pub fn msg_order(self) -> MsgOrder {
        match self {
            Compat::Default => MsgOrder::BigEndian,
            Compat::Explobot2024 => MsgOrder::LittleEndian,
        }
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
    /// Parses the names clap accepts (case-sensitive): `default`, `none`, `explobot-2024`.
    fn from_str(s: &str) -> Result<Compat, CuteError> {
        <Compat as ValueEnum>::from_str(s, false)
            .map_err(|_| CuteError::UnknownCompat { name: s.to_string() })
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
    /// batch).
    pub move_timeout: Duration,
    /// Largest incoming `Size` accepted.
    pub max_frame: usize,
}

impl Default for CuteConfig {
    fn default() -> Self {
        CuteConfig {
            rows: 20,
            cols: 20,
            start: (0, 0),
            heading: Heading::East,
            compat: Compat::Default,
            move_timeout: Duration::from_secs(5),
            max_frame: link::DEFAULT_MAX_FRAME,
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

    #[test]
    fn every_compat_has_one_name_that_parses_back() {
        for c in Compat::value_variants() {
            let name = c.to_possible_value().unwrap();
            assert_eq!(name.get_name().parse::<Compat>(), Ok(*c));
        }
        assert_eq!(
            "Explobot-2024".parse::<Compat>(),
            Err(CuteError::UnknownCompat { name: "Explobot-2024".into() })
        );
    }

    #[test]
    fn batches_always_fit_the_one_byte_count() {
        for c in Compat::value_variants() {
            assert!(c.max_batch() <= MAX_BATCH && MAX_BATCH <= usize::from(u8::MAX));
        }
    }
}
