#![doc = include_str!("../README.md")]

pub mod app;
pub mod bench;
pub mod body;
pub mod drive;
pub mod grid;
pub mod mapimg;
pub mod record;
pub mod report;
pub mod runner;
pub mod scenario;
pub mod serve;
pub mod twin;
#[cfg(feature = "window")]
pub mod window;
pub mod wiretool;
pub mod world;
