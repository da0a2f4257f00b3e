#![doc = include_str!("../README.md")]

pub mod args;
pub mod bench;
pub mod calibrate;
pub mod output;
pub mod runlog;
pub mod serve;
pub mod sink;
pub mod sweep;
pub mod wiretool;
