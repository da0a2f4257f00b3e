#![doc = include_str!("../README.md")]
#![warn(missing_docs)]

#[macro_use]
mod macros;

pub mod decoder;
pub mod link;
pub mod motor;
pub mod resync;
pub mod sensor;

pub use decoder::Decoder;

/// A byte range inside a frame (start inclusive, end exclusive).
pub type Field = core::ops::Range<usize>;
/// The byte range from an offset to the end of a frame's buffer.
pub type Rest = core::ops::RangeFrom<usize>;
