#![doc = include_str!("../README.md")]

pub mod boards;
pub mod files;
pub mod grid;
pub mod kinematics;
pub mod motor;
pub mod pose;
pub mod profile;
pub mod sensors;
pub mod time;
