#![doc = include_str!("../README.md")]

pub mod app;
pub mod pacing;
pub mod plugin;
#[cfg(feature = "window")]
pub mod window;
