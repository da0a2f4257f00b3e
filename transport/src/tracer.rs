//! A wrapper that records every byte through a [`Link`], like smoltcp's `Tracer`: the raw
//! material for recordings (`links.rec`), replays and determinism hashes.
//!
//! Invariants:
//! - Every byte a `read` returned and every byte a `write` took is recorded exactly once, in call
//!   order, with the [`Clock`] time of the call and its [`Direction`]; calls that move no bytes
//!   and errors are not recorded.
//! - Consecutive calls in the same direction at the same time are merged into one record, so a
//!   trace does not depend on how reads happened to be chunked within one instant.
//! - Records stay until taken ([`Tracer::take_records`] or a [`TraceHandle`]).
//!
//! ```
//! use robot_model::time::Instant;
//! use transport::{Direction, Link, MemLink, MockClock, Tracer, TraceRecord};
//! let clock = MockClock::new();
//! let (a, mut b) = MemLink::pair(None, clock.clone());
//! let mut a = Tracer::new(a, clock.clone());
//! let recording = a.handle(); // can be kept by the runner after `a` is handed over
//! clock.set(Instant::from_micros(1_500));
//! a.write(b"go")?;
//! assert_eq!(
//!     recording.take(),
//!     vec![TraceRecord { at: Instant::from_micros(1_500), direction: Direction::Written, bytes: b"go".to_vec() }]
//! );
//! # Ok::<(), transport::Error>(())
//! ```

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use crate::clock::Clock;
use robot_model::time::Instant;

use crate::link::Link;

/// Which way bytes went through a traced link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub enum Direction {
    /// Returned by `read`: bytes that came in.
    Read,
    /// Taken by `write`: bytes that went out.
    Written,
}

/// Bytes that went one way through a link at one time.
#[derive(Debug, Clone, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct TraceRecord {
    /// Clock time of the call.
    pub at: Instant,
    /// In or out.
    pub direction: Direction,
    /// The bytes, in order.
    pub bytes: Vec<u8>,
}

/// Bytes that went through a traced link since it was made, per direction (taking the records
/// does not reset them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TraceTotals {
    /// Bytes returned by `read`.
    pub read: u64,
    /// Bytes taken by `write`.
    pub written: u64,
}

#[derive(Debug, Default)]
struct Shared {
    records: Vec<TraceRecord>,
    totals: TraceTotals,
}

type Records = Arc<Mutex<Shared>>;

fn lock(records: &Records) -> MutexGuard<'_, Shared> {
    records.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A cloneable handle on a [`Tracer`]'s records, for whoever writes the recording. The default
/// handle has no tracer yet: give it to [`Tracer::with_handle`].
#[derive(Debug, Clone, Default)]
pub struct TraceHandle {
    records: Records,
}

impl TraceHandle {
    /// Takes every record so far, leaving none.
    pub fn take(&self) -> Vec<TraceRecord> {
        std::mem::take(&mut lock(&self.records).records)
    }

    /// Calls `f` with the records waiting, oldest first, leaving them in place.
    pub fn peek<R>(&self, f: impl FnOnce(&[TraceRecord]) -> R) -> R {
        f(&lock(&self.records).records)
    }

    /// How many records are waiting.
    pub fn len(&self) -> usize {
        lock(&self.records).records.len()
    }

    /// Bytes read and written so far, counted as they went through.
    pub fn totals(&self) -> TraceTotals {
        lock(&self.records).totals
    }

    /// Whether no records are waiting.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether this handle is all that is left: no tracer and no other handle can add records.
    pub fn is_last(&self) -> bool {
        Arc::strong_count(&self.records) == 1
    }
}

/// A link that records its traffic (see the [module docs](self)).
pub struct Tracer<L> {
    inner: L,
    clock: Arc<dyn Clock>,
    records: Records,
}

impl<L> std::fmt::Debug for Tracer<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tracer").field("records", &lock(&self.records).records.len()).finish_non_exhaustive()
    }
}

impl<L: Link> Tracer<L> {
    /// Wraps `inner`, stamping records with `clock`.
    pub fn new(inner: L, clock: impl Clock + 'static) -> Self {
        Tracer { inner, clock: Arc::new(clock), records: Arc::default() }
    }

    /// Wraps `inner`, adding to the records of `handle`: a link that is reopened carries on the
    /// same trace (totals included).
    pub fn with_handle(inner: L, clock: impl Clock + 'static, handle: &TraceHandle) -> Self {
        Tracer { inner, clock: Arc::new(clock), records: Arc::clone(&handle.records) }
    }

    /// Takes every record so far, leaving none.
    pub fn take_records(&mut self) -> Vec<TraceRecord> {
        std::mem::take(&mut lock(&self.records).records)
    }

    /// Bytes read and written so far.
    pub fn totals(&self) -> TraceTotals {
        lock(&self.records).totals
    }

    /// A handle that can take the records from elsewhere.
    pub fn handle(&self) -> TraceHandle {
        TraceHandle { records: Arc::clone(&self.records) }
    }

    /// The wrapped link.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    /// The wrapped link, mutably (bytes moved through it directly are not recorded).
    pub fn inner_mut(&mut self) -> &mut L {
        &mut self.inner
    }

    /// Unwraps, giving back the link (records stay reachable through handles).
    pub fn into_inner(self) -> L {
        self.inner
    }

    fn record(&self, direction: Direction, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let at = self.clock.now();
        let mut shared = lock(&self.records);
        match direction {
            Direction::Read => shared.totals.read += bytes.len() as u64,
            Direction::Written => shared.totals.written += bytes.len() as u64,
        }
        let records = &mut shared.records;
        match records.last_mut() {
            Some(last) if last.at == at && last.direction == direction => {
                last.bytes.extend_from_slice(bytes);
            }
            _ => records.push(TraceRecord { at, direction, bytes: bytes.to_vec() }),
        }
    }
}

impl<L: Link> Link for Tracer<L> {
    type Error = L::Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, L::Error> {
        let n = self.inner.read(buf)?;
        self.record(Direction::Read, &buf[..n]);
        Ok(n)
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, L::Error> {
        let n = self.inner.write(buf)?;
        self.record(Direction::Written, &buf[..n]);
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::MockClock;
    use crate::mem::{MemLink, MemLinkConfig};

    fn rec(micros: u64, direction: Direction, bytes: &[u8]) -> TraceRecord {
        TraceRecord { at: Instant::from_micros(micros), direction, bytes: bytes.to_vec() }
    }

    #[test]
    fn records_reads_and_writes_with_time_and_direction() {
        let clock = MockClock::new();
        let (a, mut b) = MemLink::pair(None, clock.clone());
        let mut a = Tracer::new(a, clock.clone());
        clock.set(Instant::from_micros(10));
        a.write(b"ping").unwrap();
        clock.set(Instant::from_micros(20));
        b.write(b"pong").unwrap();
        let mut buf = [0u8; 2];
        assert_eq!(a.read(&mut buf).unwrap(), 2);
        clock.set(Instant::from_micros(30));
        assert_eq!(a.read(&mut buf).unwrap(), 2);
        assert_eq!(a.read(&mut buf).unwrap(), 0);
        assert_eq!(
            a.take_records(),
            vec![
                rec(10, Direction::Written, b"ping"),
                rec(20, Direction::Read, b"po"),
                rec(30, Direction::Read, b"ng"),
            ]
        );
        assert!(a.take_records().is_empty());
        // Taking the records leaves the totals.
        assert_eq!(a.totals(), TraceTotals { read: 4, written: 4 });
        assert_eq!(a.handle().totals(), a.totals());
    }

    #[test]
    fn records_only_what_a_partial_write_took() {
        let clock = MockClock::new();
        let config = MemLinkConfig { baud: None, capacity: 3 };
        let (a, _b) = MemLink::pair_with(config, clock.clone());
        let mut a = Tracer::new(a, clock);
        assert_eq!(a.write(b"abcdef").unwrap(), 3);
        assert_eq!(a.write(b"def").unwrap(), 0);
        assert_eq!(a.take_records(), vec![rec(0, Direction::Written, b"abc")]);
    }

    #[test]
    fn same_instant_same_direction_is_merged() {
        let clock = MockClock::new();
        let (mut a, b) = MemLink::pair(None, clock.clone());
        let mut b = Tracer::new(b, clock.clone());
        a.write(b"abcdef").unwrap();
        let mut buf = [0u8; 1];
        for _ in 0..6 {
            b.read(&mut buf).unwrap();
        }
        b.write(b"x").unwrap();
        b.write(b"y").unwrap();
        assert_eq!(
            b.take_records(),
            vec![rec(0, Direction::Read, b"abcdef"), rec(0, Direction::Written, b"xy")]
        );
    }

    #[test]
    fn handle_outlives_the_tracer_and_errors_are_not_recorded() {
        let clock = MockClock::new();
        let (a, b) = MemLink::pair(None, clock.clone());
        let mut a = Tracer::new(a, clock);
        let handle = a.handle();
        a.write(b"1").unwrap();
        drop(b);
        assert!(a.write(b"2").is_err());
        assert!(a.read(&mut [0u8; 1]).is_err());
        drop(a);
        assert_eq!(handle.len(), 1);
        assert_eq!(handle.take(), vec![rec(0, Direction::Written, b"1")]);
        assert!(handle.is_empty());
    }

    #[test]
    fn a_reopened_link_continues_the_trace_of_its_handle() {
        let clock = MockClock::new();
        let (a, _b) = MemLink::pair(None, clock.clone());
        let mut first = Tracer::new(a, clock.clone());
        let handle = first.handle();
        first.write(b"1").unwrap();
        drop(first);
        assert!(handle.is_last());
        let (a, _b) = MemLink::pair(None, clock.clone());
        let mut second = Tracer::with_handle(a, clock.clone(), &handle);
        assert!(!handle.is_last());
        clock.set(Instant::from_micros(7));
        second.write(b"2").unwrap();
        assert_eq!(handle.take(), vec![rec(0, Direction::Written, b"1"), rec(7, Direction::Written, b"2")]);
        assert_eq!(handle.totals().written, 2);
    }

    #[test]
    fn peek_leaves_the_records_for_take() {
        let clock = MockClock::new();
        let (a, _b) = MemLink::pair(None, clock.clone());
        let mut a = Tracer::new(a, clock);
        let handle = a.handle();
        a.write(b"hi").unwrap();
        assert_eq!(handle.peek(|r| r.to_vec()), vec![rec(0, Direction::Written, b"hi")]);
        assert_eq!(handle.take(), vec![rec(0, Direction::Written, b"hi")]);
        assert_eq!(handle.peek(<[TraceRecord]>::len), 0);
    }
}
