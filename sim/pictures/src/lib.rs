#![doc = include_str!("../README.md")]

pub mod mapimg;
pub mod picture;
pub mod truthimg;
