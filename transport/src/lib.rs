#![doc = include_str!("../README.md")]

pub mod clock;
pub mod link;

pub use clock::{Clock, MockClock, WallClock};
pub use link::{Connector, DynLink, Error, ErrorKind, Link, LinkError, Listener};
