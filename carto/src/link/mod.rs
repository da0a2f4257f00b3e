//! Carto's links: the wire to Cute and to the two boards, and what the boards last said.
//!
//! - [`wire`]: the only module that touches `protocol`.
//! - [`sensors`]: the sensor and motor boards' latest readings, with extrapolation, the IMU
//!   heading smoothed with the wheels' and its drift estimate, serial-line time stamps and the
//!   keep-state session.
//! - [`runtime`]: the IO loop around the sans-IO [`crate::Carto`] (TCP client, serial ports).
//! - [`recording`], [`ratelimit`], [`backoff`]: `--record`, log rate limits, port retry delays.

pub mod backoff;
pub mod ratelimit;
pub mod recording;
pub mod runtime;
pub mod sensors;
pub mod wire;
