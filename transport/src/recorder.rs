//! A recording kept on disk while a program runs (`carto --record FILE`): the records of any
//! number of [`Tracer`](crate::Tracer)s gathered into one [`Recording`], bounded in size, flushed
//! periodically by a background thread.
//!
//! Contract:
//! - **Safe to leave on.** Every `flush_every` the thread takes what the tracers recorded and, if
//!   anything is new, rewrites the file: the whole recording goes to `FILE.tmp`, is synced, then
//!   renamed over `FILE`. `FILE` is therefore always a complete recording that
//!   [`Recording::load`] reads; a power cut loses at most the last `flush_every` (plus what the
//!   disk had not yet written).
//! - **Bounded.** Once the recording would pass `max_bytes` (counted as the encoded size, an
//!   upper bound), later bytes are not recorded: logged once, and the tracers are still emptied,
//!   so memory stays bounded too. Each flush rewrites up to `max_bytes`: keep the cap in
//!   proportion to the disk (on an SD card, megabytes, not gigabytes).
//! - **Never in the way.** The program's own loop only appends to the tracers' memory; all file
//!   work happens on the recorder's thread. A write that fails is logged once (and its recovery
//!   once) and retried at the next flush; the program carries on.
//!
//! ```no_run
//! use transport::recorder::{Recorder, RecorderConfig};
//! use transport::recording::{FORMAT_VERSION, Oracle, Recording};
//! use transport::{MemLink, Tracer, WallClock};
//! let clock = WallClock::start();
//! let header = Recording {
//!     version: FORMAT_VERSION, scenario_label: "carto".into(), scenario_ron: String::new(),
//!     profile_ron: "()".into(), seed: 0, logs: vec![], oracle: Oracle::None,
//! };
//! let recorder = Recorder::start("robot.rec".into(), header, RecorderConfig::default())?;
//! let (a, _b) = MemLink::pair(None, clock);
//! let motor = Tracer::new(a, clock);
//! recorder.add("motor", "carto", motor.handle());
//! // … run …
//! recorder.finish();
//! # Ok::<(), transport::recording::RecordingError>(())
//! ```

use std::path::PathBuf;
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::recording::{EndpointLog, Recording, RecordingError};
use crate::tracer::{TraceHandle, TraceRecord};

/// Upper bound of the bytes one chunk adds besides its payload: its time and length (varints of
/// at most 9 bytes each) and its direction (1 byte).
const CHUNK_OVERHEAD: u64 = 19;

/// How a [`Recorder`] bounds and flushes its file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecorderConfig {
    /// Largest file, bytes; later bytes are not recorded.
    pub max_bytes: u64,
    /// Time between two rewrites of the file.
    pub flush_every: Duration,
}

impl Default for RecorderConfig {
    /// 16 MiB (about 1.5 hours of Carto's three links), flushed every 10 s.
    fn default() -> Self {
        RecorderConfig { max_bytes: 16 << 20, flush_every: Duration::from_secs(10) }
    }
}

/// What a recorder did, for the last log line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RecorderTotals {
    /// Payload bytes in the recording.
    pub recorded: u64,
    /// Payload bytes left out after the cap was reached.
    pub dropped: u64,
    /// Rewrites of the file that succeeded.
    pub writes: u64,
    /// Rewrites that failed.
    pub failed_writes: u64,
}

/// One tracer's records and where they go.
struct Source {
    link: String,
    endpoint: String,
    handle: TraceHandle,
}

/// The recording being built, with its size bound: the recorder's thread owns it.
struct Book {
    path: PathBuf,
    rec: Recording,
    size: u64,
    max: u64,
    full: bool,
    changed: bool,
    failing: bool,
    totals: RecorderTotals,
}

impl Book {
    fn absorb(&mut self, link: &str, endpoint: &str, records: Vec<TraceRecord>) {
        for r in records {
            let n = r.bytes.len() as u64;
            let cost = n + CHUNK_OVERHEAD;
            if self.full || self.size + cost > self.max {
                if !self.full {
                    self.full = true;
                    tracing::warn!(
                        file = %self.path.display(),
                        max_bytes = self.max,
                        at_s = r.at.as_secs_f64(),
                        "recording reached its size cap: later bytes are not recorded"
                    );
                }
                self.totals.dropped += n;
                continue;
            }
            let log = match self.rec.logs.iter().position(|l| l.link == link && l.endpoint == endpoint) {
                Some(i) => &mut self.rec.logs[i],
                None => {
                    self.size += (link.len() + endpoint.len() + 3 * 9) as u64;
                    self.rec.logs.push(EndpointLog {
                        link: link.to_string(),
                        endpoint: endpoint.to_string(),
                        chunks: Vec::new(),
                    });
                    let last = self.rec.logs.len() - 1;
                    &mut self.rec.logs[last]
                }
            };
            log.chunks.push(r);
            self.size += cost;
            self.totals.recorded += n;
            self.changed = true;
        }
    }

    /// Rewrites the file if anything changed (see the module docs); logs a failure once.
    fn flush(&mut self) {
        if !self.changed {
            return;
        }
        match save_atomically(&self.rec, &self.path) {
            Ok(()) => {
                self.changed = false;
                self.totals.writes += 1;
                if self.failing {
                    self.failing = false;
                    tracing::info!(file = %self.path.display(), "recording written again");
                }
            }
            Err(e) => {
                self.totals.failed_writes += 1;
                if !self.failing {
                    self.failing = true;
                    tracing::warn!("cannot write the recording ({e}): carrying on, retrying at each flush");
                }
            }
        }
    }
}

/// Writes `rec` to `path.tmp`, syncs it and renames it over `path`.
fn save_atomically(rec: &Recording, path: &std::path::Path) -> Result<(), RecordingError> {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    let tmp = path.with_file_name(name);
    let io = |source| RecordingError::Io { path: path.display().to_string(), source };
    rec.save(&tmp)?;
    std::fs::File::open(&tmp).and_then(|f| f.sync_all()).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

type Sources = Arc<Mutex<Vec<Source>>>;

/// Adds tracers to a [`Recorder`]; cloneable, usable after the recorder has finished (then
/// nothing more is recorded).
#[derive(Clone)]
pub struct RecorderFeed {
    sources: Sources,
}

impl std::fmt::Debug for RecorderFeed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecorderFeed").finish_non_exhaustive()
    }
}

impl RecorderFeed {
    /// As [`Recorder::add`].
    pub fn add(&self, link: &str, endpoint: &str, handle: TraceHandle) {
        let source = Source { link: link.to_string(), endpoint: endpoint.to_string(), handle };
        self.sources.lock().unwrap_or_else(PoisonError::into_inner).push(source);
    }
}

/// A recording on disk fed by tracers (see the [module docs](self)).
pub struct Recorder {
    sources: Sources,
    stop: mpsc::Sender<()>,
    thread: Option<JoinHandle<RecorderTotals>>,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder").finish_non_exhaustive()
    }
}

impl Recorder {
    /// Writes `header` (its `logs` are kept as the start of the recording) to `path` at once, so
    /// a path that cannot be written is an error here, then starts the flushing thread.
    pub fn start(
        path: PathBuf,
        header: Recording,
        config: RecorderConfig,
    ) -> Result<Recorder, RecordingError> {
        let encoded = bincode::serde::encode_to_vec(&header, bincode::config::standard()).map_err(|e| {
            RecordingError::Decode { path: path.display().to_string(), message: e.to_string() }
        })?;
        save_atomically(&header, &path)?;
        let mut book = Book {
            path,
            rec: header,
            size: encoded.len() as u64,
            max: config.max_bytes,
            full: false,
            changed: false,
            failing: false,
            totals: RecorderTotals::default(),
        };
        let sources: Sources = Arc::default();
        let (stop, stopped) = mpsc::channel::<()>();
        let shared = Arc::clone(&sources);
        let gather = move |book: &mut Book| {
            let mut sources = shared.lock().unwrap_or_else(PoisonError::into_inner);
            for s in sources.iter() {
                book.absorb(&s.link, &s.endpoint, s.handle.take());
            }
            // A tracer gone for good (a client that left) has nothing more to give.
            sources.retain(|s| !s.handle.is_last());
        };
        let thread = std::thread::Builder::new()
            .name("recorder".into())
            .spawn(move || {
                loop {
                    let last =
                        !matches!(stopped.recv_timeout(config.flush_every), Err(RecvTimeoutError::Timeout));
                    gather(&mut book);
                    book.flush();
                    if last {
                        return book.totals;
                    }
                }
            })
            .map_err(|source| RecordingError::Io { path: "recorder thread".into(), source })?;
        Ok(Recorder { sources, stop, thread: Some(thread) })
    }

    /// Records `handle`'s tracer as the endpoint `endpoint` of `link` (e.g. `motor`, `carto`).
    /// A link that is reopened keeps its handle ([`Tracer::with_handle`](crate::Tracer::with_handle)).
    pub fn add(&self, link: &str, endpoint: &str, handle: TraceHandle) {
        self.feed().add(link, endpoint, handle);
    }

    /// A cloneable way to add tracers from elsewhere (e.g. a listener tracing each client).
    pub fn feed(&self) -> RecorderFeed {
        RecorderFeed { sources: Arc::clone(&self.sources) }
    }

    /// Takes the last records, writes the file a last time and stops the thread.
    pub fn finish(mut self) -> RecorderTotals {
        self.stop_thread()
    }

    fn stop_thread(&mut self) -> RecorderTotals {
        let _ = self.stop.send(());
        self.thread.take().and_then(|t| t.join().ok()).unwrap_or_default()
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.thread.is_some() {
            self.stop_thread();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::MockClock;
    use crate::link::Link;
    use crate::mem::MemLink;
    use crate::recording::{FORMAT_VERSION, Oracle};
    use crate::tracer::Tracer;
    use robot_model::time::Instant;
    use std::path::Path;

    fn header() -> Recording {
        Recording {
            version: FORMAT_VERSION,
            scenario_label: "test".into(),
            scenario_ron: String::new(),
            profile_ron: "()".into(),
            seed: 0,
            logs: vec![],
            oracle: Oracle::None,
        }
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("transport-recorder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn records_every_tracer_and_flushes_while_running() {
        let dir = scratch("flush");
        let path = dir.join("a.rec");
        let config = RecorderConfig { max_bytes: 1 << 20, flush_every: Duration::from_millis(20) };
        let recorder = Recorder::start(path.clone(), header(), config).unwrap();
        assert_eq!(Recording::load(&path).unwrap().logs, vec![]);
        let clock = MockClock::new();
        let (a, mut b) = MemLink::pair(None, clock.clone());
        let mut a = Tracer::new(a, clock.clone());
        recorder.add("motor", "carto", a.handle());
        clock.set(Instant::from_micros(5));
        a.write(b"go").unwrap();
        b.write(b"ok").unwrap();
        a.read(&mut [0u8; 4]).unwrap();
        // Without finishing, the file on disk catches up within a few flushes.
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        loop {
            let rec = Recording::load(&path).unwrap();
            if rec.logs.first().is_some_and(|l| l.chunks.len() == 2) {
                assert_eq!((rec.logs[0].link.as_str(), rec.logs[0].endpoint.as_str()), ("motor", "carto"));
                break;
            }
            assert!(std::time::Instant::now() < deadline, "never flushed");
            std::thread::sleep(Duration::from_millis(10));
        }
        let totals = recorder.finish();
        assert_eq!(totals.recorded, 4);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stops_recording_at_the_cap_and_keeps_emptying_the_tracers() {
        let dir = scratch("cap");
        let path = dir.join("a.rec");
        let config = RecorderConfig { max_bytes: 400, flush_every: Duration::from_secs(3600) };
        let recorder = Recorder::start(path.clone(), header(), config).unwrap();
        let clock = MockClock::new();
        let (a, _b) = MemLink::pair(None, clock.clone());
        let mut a = Tracer::new(a, clock.clone());
        let handle = a.handle();
        recorder.add("gui", "carto#1", a.handle());
        for i in 0..100u64 {
            clock.set(Instant::from_micros(i));
            a.write(&[0x55; 10]).unwrap();
        }
        let totals = recorder.finish();
        assert!(handle.is_empty());
        assert_eq!(totals.recorded + totals.dropped, 1000);
        assert!(totals.dropped > 0 && totals.recorded > 0, "{totals:?}");
        let len = std::fs::metadata(&path).unwrap().len();
        assert!(len <= 400, "{len} bytes");
        let rec = Recording::load(&path).unwrap();
        assert_eq!(rec.logs[0].chunks.iter().map(|c| c.bytes.len() as u64).sum::<u64>(), totals.recorded);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_unwritable_path_is_an_error_at_start_and_a_failing_disk_does_not_stop_the_writer() {
        let missing = Path::new("/nonexistent-explobot-dir/a.rec").to_path_buf();
        let err = Recorder::start(missing, header(), RecorderConfig::default()).unwrap_err();
        assert!(err.to_string().contains("/nonexistent-explobot-dir"), "{err}");

        let dir = scratch("failing");
        let path = dir.join("a.rec");
        let config = RecorderConfig { max_bytes: 1 << 20, flush_every: Duration::from_millis(5) };
        let recorder = Recorder::start(path.clone(), header(), config).unwrap();
        // The folder goes away: every flush fails, the recorder keeps taking records.
        std::fs::remove_dir_all(&dir).unwrap();
        let clock = MockClock::new();
        let (a, _b) = MemLink::pair(None, clock.clone());
        let mut a = Tracer::new(a, clock);
        recorder.add("motor", "carto", a.handle());
        a.write(b"x").unwrap();
        std::thread::sleep(Duration::from_millis(50));
        let totals = recorder.finish();
        assert!(totals.failed_writes >= 1 && totals.writes == 0, "{totals:?}");
        assert_eq!(totals.recorded, 1);
    }
}
