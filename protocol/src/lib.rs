#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

#[macro_use]
mod macros;

pub mod link;
pub mod motor;
pub mod sensor;

/// A byte range inside a frame (start inclusive, end exclusive).
pub type Field = core::ops::Range<usize>;
/// The byte range from an offset to the end of a frame's buffer.
pub type Rest = core::ops::RangeFrom<usize>;
