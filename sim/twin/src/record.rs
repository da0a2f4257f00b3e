//! Recordings: every byte on every link of a run, with its time (`runs/NAME/links.rec`).
//!
//! The format is [`transport::recording`], shared with `carto --record` on the robot; this
//! module re-exports it under the twin's names. `explobot replay` re-runs a recording
//! ([`crate::replay`]).

pub use transport::recording::{
    Chunk, Dir, Divergence, EndpointLog, FORMAT_VERSION, MAX_RECORDING_BYTES, Recording, RecordingError,
    first_divergence, hash_logs,
};
