//! Recordings: every byte on every link of a run, with its time, in one bincode file (the twin's
//! `runs/NAME/links.rec`, `carto --record FILE` on the robot), plus what is needed to run the same
//! scenario again.
//!
//! The format lives here, beside [`Tracer`](crate::Tracer) whose records it stores, because both
//! writers need it and neither may depend on the other: the twin (`sim/twin`) links Carto, and
//! Carto must not link the twin (no Bevy, no rapier on the Pi). `twin::record` re-exports it.
//!
//! A file is one [`Recording`], encoded with bincode's standard configuration; its first field is
//! [`FORMAT_VERSION`]. A recording made on the robot has no scenario (`scenario_ron` is empty):
//! it can be read and compared, not re-run. `explobot replay FILE` re-runs a twin recording with
//! its seed and profile and reports the first place where the new byte log differs
//! ([`first_divergence`]). A run is deterministic, so a divergence means the code changed
//! behaviour (or the recording is from another version).
//!
//! Invariant: [`Recording::load`] never panics and never allocates more than the file's size on
//! a damaged, truncated or foreign file; it says what is wrong in words.
//!
//! ```
//! use transport::recording::{EndpointLog, FORMAT_VERSION, Oracle, Recording};
//! let rec = Recording {
//!     version: FORMAT_VERSION,
//!     scenario_label: "carto on the robot".into(),
//!     scenario_ron: String::new(),
//!     profile_ron: "()".into(),
//!     seed: 0,
//!     logs: vec![EndpointLog { link: "motor".into(), endpoint: "carto".into(), chunks: vec![] }],
//!     oracle: Oracle::None,
//! };
//! let path = std::env::temp_dir().join(format!("doc-{}.rec", std::process::id()));
//! rec.save(&path)?;
//! assert_eq!(Recording::load(&path)?, rec);
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), transport::recording::RecordingError>(())
//! ```

use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// What a run gave Carto beyond its own sensors (the twin's `--known-room`, `--known-echoes`;
/// `twin::oracle` explains them). Anything but [`Oracle::None`] is an analysis, never the robot's
/// result. Stored in recordings by variant index: keep the order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Oracle {
    /// Nothing: what the robot achieves.
    #[default]
    None,
    /// Every surface of the room, before the run (`--known-room`).
    Room,
    /// Every point the sonar has heard so far, where it really lies, never forgotten
    /// (`--known-echoes`).
    Echoes,
}

/// The largest recording `load` reads (2 GiB − 1).
pub const MAX_RECORDING_BYTES: u64 = (1 << 31) - 1;

/// Recording format version; bumped when the layout changes (2: `known_room`; 3: `oracle`, which
/// replaced it).
pub const FORMAT_VERSION: u32 = 3;

/// Which way bytes went, seen from the endpoint that recorded them (the tracer's type).
pub use crate::tracer::Direction as Dir;
/// One burst of bytes at one time: the tracer's record, stored as it is.
pub use crate::tracer::TraceRecord as Chunk;

/// All traffic at one endpoint of one link (e.g. `motor` at `carto`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct EndpointLog {
    /// The link: `motor`, `sensor` or `gui`.
    pub link: String,
    /// The endpoint: `carto`, `board` or `cute`.
    pub endpoint: String,
    /// Its traffic in time order.
    pub chunks: Vec<Chunk>,
}

/// A whole run's byte log and how to reproduce it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Recording {
    /// [`FORMAT_VERSION`] at the time of writing.
    pub version: u32,
    /// Where the scenario came from (for messages).
    pub scenario_label: String,
    /// The scenario file's text.
    pub scenario_ron: String,
    /// The robot profile actually used (after the scenario's overrides), as RON.
    pub profile_ron: String,
    /// The seed used.
    pub seed: u64,
    /// Every endpoint's traffic.
    pub logs: Vec<EndpointLog>,
    /// What Carto was given beyond its sensors (`--known-room`, `--known-echoes`); a replay
    /// gives it again.
    pub oracle: Oracle,
}

/// A recording that could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// File system error.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// Not a recording, or a damaged one.
    #[error("{path}: not a valid recording: {message}")]
    Decode {
        /// The file.
        path: String,
        /// What the decoder said.
        message: String,
    },
    /// A recording of another format version.
    #[error("{path}: recording format {found}, this build reads {FORMAT_VERSION}")]
    Version {
        /// The file.
        path: String,
        /// The version in the file.
        found: u32,
    },
}

/// A decoding error in words (bincode's own `Display` is its debug form, e.g.
/// `UnexpectedEnd { additional: 1 }`).
fn decode_message(e: &bincode::error::DecodeError) -> String {
    use bincode::error::DecodeError as E;
    match e {
        E::UnexpectedEnd { additional } => {
            format!("the file ends {additional} byte(s) too early: truncated or not a recording")
        }
        E::LimitExceeded => "a length inside the file claims more than the file holds".to_string(),
        E::UnexpectedVariant { found, .. } => format!("an unknown tag {found}: damaged or not a recording"),
        E::Utf8 { .. } => "a name is not valid UTF-8: damaged or not a recording".to_string(),
        E::InvalidBooleanValue(v) => format!("a flag holds {v}, neither 0 nor 1: damaged or not a recording"),
        E::InvalidIntegerType { .. } | E::InvalidCharEncoding(_) | E::NonZeroTypeIsZero { .. } => {
            "a value cannot be read: damaged or not a recording".to_string()
        }
        other => format!("cannot be read as a recording ({other})"),
    }
}

impl Recording {
    /// Writes the recording to `path`.
    pub fn save(&self, path: &Path) -> Result<(), RecordingError> {
        let bytes = bincode::serde::encode_to_vec(self, bincode::config::standard()).map_err(|e| {
            RecordingError::Decode { path: path.display().to_string(), message: e.to_string() }
        })?;
        std::fs::write(path, bytes)
            .map_err(|source| RecordingError::Io { path: path.display().to_string(), source })
    }

    /// Reads a recording from `path`. The format version (the first field) is checked before
    /// the rest is decoded, and decoding is bounded by the file's size, so a damaged or foreign
    /// file is an error, never an abort.
    pub fn load(path: &Path) -> Result<Recording, RecordingError> {
        let label = path.display().to_string();
        let bytes = robot_model::files::read_bounded(path, MAX_RECORDING_BYTES)
            .map_err(|source| RecordingError::Io { path: label.clone(), source })?;
        let decode_error = |e: bincode::error::DecodeError| RecordingError::Decode {
            path: label.clone(),
            message: decode_message(&e),
        };
        let (version, _): (u32, usize) =
            bincode::serde::decode_from_slice(&bytes, bincode::config::standard()).map_err(decode_error)?;
        if version != FORMAT_VERSION {
            return Err(RecordingError::Version { path: label, found: version });
        }
        // No length prefix inside the file can claim more than the file holds.
        let config = bincode::config::standard().with_limit::<{ MAX_RECORDING_BYTES as usize }>();
        let (rec, used): (Recording, usize) =
            bincode::serde::decode_from_slice(&bytes, config).map_err(decode_error)?;
        // A recording ends where its content ends: bytes after it mean a damaged or spliced file.
        if used != bytes.len() {
            return Err(RecordingError::Decode {
                path: label,
                message: format!("{} bytes after the end of the recording", bytes.len() - used),
            });
        }
        Ok(rec)
    }

    /// SHA-256 over every chunk of every endpoint (names, times, directions and bytes).
    pub fn link_hash(&self) -> String {
        hash_logs(&self.logs)
    }
}

/// SHA-256 over a set of endpoint logs, hex.
pub fn hash_logs(logs: &[EndpointLog]) -> String {
    let mut h = Sha256::new();
    for log in logs {
        h.update(log.link.as_bytes());
        h.update([0]);
        h.update(log.endpoint.as_bytes());
        h.update([0]);
        for c in &log.chunks {
            h.update(c.at.total_micros().to_le_bytes());
            h.update([matches!(c.direction, Dir::Written) as u8]);
            h.update((c.bytes.len() as u64).to_le_bytes());
            h.update(&c.bytes);
        }
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Where two byte logs first differ.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Divergence {
    /// Link and endpoint, e.g. `motor@carto`.
    pub endpoint: String,
    /// Direction at that endpoint.
    pub dir: Dir,
    /// Offset in that direction's byte stream.
    pub offset: u64,
    /// Time of the recorded byte (µs), if there was one.
    pub recorded_micros: Option<u64>,
    /// Time of the replayed byte (µs), if there was one.
    pub replayed_micros: Option<u64>,
    /// The recorded byte, if any.
    pub recorded: Option<u8>,
    /// The replayed byte, if any.
    pub replayed: Option<u8>,
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = |m: Option<u64>| m.map_or("-".to_string(), |m| format!("{:.6} s", m as f64 * 1e-6));
        let b = |v: Option<u8>| v.map_or("end of stream".to_string(), |v| format!("0x{v:02X}"));
        write!(
            f,
            "{} {:?} byte {}: recorded {} at {}, replayed {} at {}",
            self.endpoint,
            self.dir,
            self.offset,
            b(self.recorded),
            t(self.recorded_micros),
            b(self.replayed),
            t(self.replayed_micros)
        )
    }
}

/// The earliest (by time) first difference between `recorded` and `replayed`, comparing each
/// endpoint's read and write streams byte by byte, with the time each byte was moved.
pub fn first_divergence(recorded: &[EndpointLog], replayed: &[EndpointLog]) -> Option<Divergence> {
    let mut found: Vec<Divergence> = Vec::new();
    let names =
        |logs: &[EndpointLog]| logs.iter().map(|l| (l.link.clone(), l.endpoint.clone())).collect::<Vec<_>>();
    let mut all = names(recorded);
    for n in names(replayed) {
        if !all.contains(&n) {
            all.push(n);
        }
    }
    let empty = Vec::new();
    for (link, endpoint) in all {
        let a = chunks_of(recorded, &link, &endpoint).unwrap_or(&empty);
        let b = chunks_of(replayed, &link, &endpoint).unwrap_or(&empty);
        for dir in [Dir::Read, Dir::Written] {
            let sa = flatten(a, dir);
            let sb = flatten(b, dir);
            let n = sa.len().max(sb.len());
            if let Some(i) = (0..n).find(|&i| sa.get(i) != sb.get(i)) {
                found.push(Divergence {
                    endpoint: format!("{link}@{endpoint}"),
                    dir,
                    offset: i as u64,
                    recorded_micros: sa.get(i).map(|x| x.0),
                    replayed_micros: sb.get(i).map(|x| x.0),
                    recorded: sa.get(i).map(|x| x.1),
                    replayed: sb.get(i).map(|x| x.1),
                });
            }
        }
    }
    // Rank by the earliest time present: a stream that ended early diverges at its other side's
    // time, not "never".
    let key = |d: &Divergence| match (d.recorded_micros, d.replayed_micros) {
        (Some(a), Some(b)) => a.min(b),
        (Some(t), None) | (None, Some(t)) => t,
        (None, None) => u64::MAX,
    };
    found.into_iter().min_by_key(key)
}

fn chunks_of<'a>(logs: &'a [EndpointLog], link: &str, endpoint: &str) -> Option<&'a Vec<Chunk>> {
    logs.iter().find(|l| l.link == link && l.endpoint == endpoint).map(|l| &l.chunks)
}

fn flatten(chunks: &[Chunk], dir: Dir) -> Vec<(u64, u8)> {
    chunks
        .iter()
        .filter(|c| c.direction == dir)
        .flat_map(|c| c.bytes.iter().map(move |&b| (c.at.total_micros(), b)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log(chunks: Vec<(u64, Dir, &[u8])>) -> Vec<EndpointLog> {
        vec![EndpointLog {
            link: "motor".into(),
            endpoint: "carto".into(),
            chunks: chunks
                .into_iter()
                .map(|(micros, direction, b)| Chunk {
                    at: robot_model::time::Instant::from_micros(micros),
                    direction,
                    bytes: b.to_vec(),
                })
                .collect(),
        }]
    }

    #[test]
    fn identical_logs_do_not_diverge_and_hash_equal() {
        let a = log(vec![(0, Dir::Written, &[0xAA, 0x01]), (500, Dir::Read, &[1, 2, 3])]);
        assert_eq!(first_divergence(&a, &a.clone()), None);
        assert_eq!(hash_logs(&a), hash_logs(&a.clone()));
    }

    #[test]
    fn a_changed_byte_is_found_at_its_offset_even_when_chunked_differently() {
        let a = log(vec![(0, Dir::Written, &[1, 2]), (10, Dir::Written, &[3, 4])]);
        let b = log(vec![(0, Dir::Written, &[1, 2]), (10, Dir::Written, &[3, 9])]);
        let d = first_divergence(&a, &b).unwrap();
        assert_eq!((d.offset, d.recorded, d.replayed, d.dir), (3, Some(4), Some(9), Dir::Written));
        assert_ne!(hash_logs(&a), hash_logs(&b));
    }

    #[test]
    fn a_shorter_replay_diverges_at_end_of_stream() {
        let a = log(vec![(0, Dir::Read, &[1, 2, 3])]);
        let b = log(vec![(0, Dir::Read, &[1, 2])]);
        let d = first_divergence(&a, &b).unwrap();
        assert_eq!((d.offset, d.replayed), (2, None));
        assert!(d.to_string().contains("end of stream"));
    }

    #[test]
    fn an_early_end_of_stream_ranks_by_its_time() {
        // Stream A ends at 1 s on replay; stream B differs at 100 s. A comes first.
        let a = log(vec![(1_000_000, Dir::Read, &[1, 2]), (100_000_000, Dir::Written, &[7])]);
        let mut b = a.clone();
        b[0].chunks[0].bytes.truncate(1);
        b[0].chunks[1].bytes[0] = 8;
        let d = first_divergence(&a, &b).unwrap();
        assert_eq!((d.dir, d.replayed), (Dir::Read, None));
    }

    #[test]
    fn save_and_load_round_trip_and_bad_files_are_errors() {
        let dir = std::env::temp_dir().join(format!("explobot-rec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rec = Recording {
            version: FORMAT_VERSION,
            scenario_label: "x".into(),
            scenario_ron: "Scenario()".into(),
            profile_ron: "()".into(),
            seed: 3,
            logs: log(vec![(7, Dir::Written, &[0xAA])]),
            oracle: Oracle::Echoes,
        };
        let path = dir.join("a.rec");
        rec.save(&path).unwrap();
        assert_eq!(Recording::load(&path).unwrap(), rec);
        // issue 15: garbage appended to a good recording is an error, not "identical".
        let mut spliced = std::fs::read(&path).unwrap();
        spliced.extend_from_slice(b"garbage");
        std::fs::write(&path, &spliced).unwrap();
        match Recording::load(&path) {
            Err(RecordingError::Decode { message, .. }) => {
                assert!(message.contains("7 bytes after"), "{message}")
            }
            other => panic!("{other:?}"),
        }
        // A truncated recording says so in words, not in bincode's debug form.
        std::fs::write(&path, &spliced[..spliced.len() / 2]).unwrap();
        match Recording::load(&path) {
            Err(RecordingError::Decode { message, .. }) => {
                assert!(message.contains("too early") && !message.contains('{'), "{message}")
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(Recording::load(Path::new("/dev/zero")), Err(RecordingError::Io { .. })));
        let version = FORMAT_VERSION as u8;
        std::fs::write(&path, [&[version, 2][..], b"garbage"].concat()).unwrap();
        assert!(matches!(Recording::load(&path), Err(RecordingError::Decode { .. })));
        // a recording of format 1 (before `known_room`) is named as such
        std::fs::write(&path, b"\x01\x02garbage").unwrap();
        assert!(matches!(Recording::load(&path), Err(RecordingError::Version { found: 1, .. })));
        // The version, then a string claiming an enormous length: an error, not an allocation abort.
        std::fs::write(&path, [version, 0xFD, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F]).unwrap();
        assert!(matches!(Recording::load(&path), Err(RecordingError::Decode { .. })));
        std::fs::write(&path, [7u8, 0, 0]).unwrap();
        assert!(matches!(Recording::load(&path), Err(RecordingError::Version { found: 7, .. })));
        assert!(matches!(Recording::load(&dir.join("missing.rec")), Err(RecordingError::Io { .. })));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
