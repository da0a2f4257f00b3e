//! In-memory links for the lockstep runner: a [`MemLink`] pair with serial byte timing on a
//! virtual clock, and a connection-oriented [`MemListener`] / [`MemConnector`] pair.
//!
//! A pair has one pipe per direction. With a baud rate a byte is on the wire for 10 bit times
//! (8N1: start, 8 data, stop): a byte written at `t` onto an idle line becomes readable at
//! `t + 10·10⁶/baud` µs, and bytes are serialised one after another, so writing faster than the
//! line carries shows up as a growing [`MemLinkStats::backlog`]. Without a baud rate bytes
//! are readable as soon as they are written.
//!
//! Invariants:
//! - Bytes arrive in the order written, never duplicated or lost (faults are a wrapper's job:
//!   [`FaultInjector`](crate::FaultInjector)).
//! - Byte `k` (from 1) of a busy stretch that started at `s` µs is readable at
//!   `ceil(s + k·10·10⁶/baud)` µs; times are kept exactly (µs × baud), so there is no drift.
//! - Each direction holds at most `capacity` bytes written and not yet read by the peer (in
//!   flight plus delivered-but-unread); `write` takes what fits and returns how many.
//! - After one end is dropped or [`MemLink::close`]d, the other end reads the bytes still queued
//!   (in flight ones when they are due), then gets [`ErrorKind::Disconnected`](crate::ErrorKind)
//!   on every read and write.
//!
//! ```
//! use robot_model::time::Duration;
//! use transport::{Link, MemLink, MockClock};
//! let clock = MockClock::new();
//! let (mut carto, mut board) = MemLink::pair(Some(9600), clock.clone());
//! assert_eq!(carto.write(b"0123456789")?, 10);
//! let mut buf = [0u8; 16];
//! assert_eq!(board.read(&mut buf)?, 0); // nothing has crossed the wire yet
//! clock.advance(Duration::from_micros(10_417)); // 10 bytes × 10 bits at 9600 baud = 10.4167 ms
//! assert_eq!(board.read(&mut buf)?, 10);
//! drop(carto);
//! assert!(board.read(&mut buf).unwrap_err().is_disconnected());
//! # Ok::<(), transport::Error>(())
//! ```

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use robot_model::time::{BITS_PER_BYTE, Duration, Instant};

use crate::clock::Clock;
use crate::link::{Connector, Error, Link, Listener};

/// The default bound of each direction's queue, in bytes.
pub const DEFAULT_CAPACITY: usize = 4096;

/// One bit time × baud in our exact time unit (µs × baud): a byte takes this many units.
const BYTE_UNITS: u128 = BITS_PER_BYTE as u128 * 1_000_000;

/// How a [`MemLink`] pair behaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemLinkConfig {
    /// Serial line rate in baud (10 bits per byte); `None` (or `Some(0)`) delivers instantly.
    pub baud: Option<u32>,
    /// Bytes each direction holds, written and not yet read by the peer.
    pub capacity: usize,
}

impl Default for MemLinkConfig {
    fn default() -> Self {
        MemLinkConfig { baud: None, capacity: DEFAULT_CAPACITY }
    }
}

impl MemLinkConfig {
    /// A configuration with this baud rate and the default capacity.
    pub fn with_baud(baud: Option<u32>) -> Self {
        MemLinkConfig { baud, ..Self::default() }
    }

    fn effective_baud(&self) -> Option<u128> {
        match self.baud {
            Some(b) if b > 0 => Some(u128::from(b)),
            _ => None,
        }
    }
}

/// What one end of a [`MemLink`] sees of its link right now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MemLinkStats {
    /// Bytes this end wrote that the peer has not read yet (in flight + delivered).
    pub queued: usize,
    /// Of those, bytes still on the wire (not yet readable by the peer).
    pub in_flight: usize,
    /// How long until the last byte this end wrote is readable by the peer, in µs: the extra
    /// latency a byte written now would see before its own byte time.
    pub backlog: Duration,
    /// Bytes a `read` on this end would return now.
    pub readable: usize,
    /// Bytes this end has written since the pair was made.
    pub written_total: u64,
    /// Bytes this end has read since the pair was made.
    pub read_total: u64,
}

/// A run of bytes sent back to back: the first completes at `first_end` (µs × baud), each next
/// one a byte time later.
#[derive(Debug, Clone, Copy)]
struct Segment {
    first_end: u128,
    len: usize,
}

/// One direction of a pair.
#[derive(Debug, Default)]
struct Pipe {
    /// Every byte written and not yet read, in order.
    bytes: VecDeque<u8>,
    /// Timing of `bytes` (baud mode only), covering them in order.
    segments: VecDeque<Segment>,
    /// When the line finishes sending the last byte, in µs × baud.
    line_free: u128,
    written_total: u64,
    read_total: u64,
}

impl Pipe {
    /// Bytes readable at `now_units` (µs × baud); everything when `baud` is `None`.
    fn readable(&self, now_units: Option<u128>) -> usize {
        let Some(now) = now_units else {
            return self.bytes.len();
        };
        let mut n = 0;
        for seg in &self.segments {
            if now < seg.first_end {
                break;
            }
            let due = (now - seg.first_end) / BYTE_UNITS + 1;
            if due >= seg.len as u128 {
                n += seg.len;
            } else {
                // `due < seg.len`, so it fits in usize.
                n += usize::try_from(due).unwrap_or(seg.len);
                break;
            }
        }
        n
    }

    fn push(&mut self, data: &[u8], now_units: Option<u128>) {
        self.bytes.extend(data.iter().copied());
        self.written_total += data.len() as u64;
        let Some(now) = now_units else {
            return;
        };
        let start = self.line_free.max(now);
        let first_end = start + BYTE_UNITS;
        self.line_free = start + BYTE_UNITS * data.len() as u128;
        match self.segments.back_mut() {
            Some(last) if last.first_end + BYTE_UNITS * last.len as u128 == first_end => {
                last.len += data.len();
            }
            _ => self.segments.push_back(Segment { first_end, len: data.len() }),
        }
    }

    fn pop(&mut self, buf: &mut [u8]) {
        let n = buf.len();
        for (dst, src) in buf.iter_mut().zip(self.bytes.drain(..n)) {
            *dst = src;
        }
        self.read_total += buf.len() as u64;
        let mut left = buf.len();
        while left > 0 {
            let Some(seg) = self.segments.front_mut() else {
                break;
            };
            if seg.len <= left {
                left -= seg.len;
                self.segments.pop_front();
            } else {
                seg.len -= left;
                seg.first_end += BYTE_UNITS * left as u128;
                left = 0;
            }
        }
    }
}

#[derive(Debug, Default)]
struct Shared {
    /// `pipes[i]` carries what end `i` writes.
    pipes: [Pipe; 2],
    closed: [bool; 2],
}

/// One end of an in-memory byte link (see the [module docs](self)).
pub struct MemLink {
    side: usize,
    shared: Arc<Mutex<Shared>>,
    config: MemLinkConfig,
    clock: Arc<dyn Clock>,
}

impl std::fmt::Debug for MemLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MemLink")
            .field("side", &self.side)
            .field("config", &self.config)
            .field("now", &self.clock.now())
            .finish_non_exhaustive()
    }
}

impl MemLink {
    /// Two connected ends; with `baud`, bytes take their serial byte time on `clock`.
    pub fn pair(baud: Option<u32>, clock: impl Clock + 'static) -> (MemLink, MemLink) {
        Self::pair_with(MemLinkConfig::with_baud(baud), clock)
    }

    /// Two connected ends with a full configuration (baud rate and queue capacity).
    pub fn pair_with(config: MemLinkConfig, clock: impl Clock + 'static) -> (MemLink, MemLink) {
        let shared = Arc::new(Mutex::new(Shared::default()));
        let clock: Arc<dyn Clock> = Arc::new(clock);
        let a = MemLink { side: 0, shared: Arc::clone(&shared), config, clock: Arc::clone(&clock) };
        let b = MemLink { side: 1, shared, config, clock };
        (a, b)
    }

    /// This pair's configuration.
    pub fn config(&self) -> MemLinkConfig {
        self.config
    }

    /// Closes this end: the peer reads what is still queued, then gets `Disconnected`.
    pub fn close(&mut self) {
        let mut shared = self.lock();
        shared.closed[self.side] = true;
        // Nobody will read what was coming to us.
        let inbound = &mut shared.pipes[1 - self.side];
        inbound.bytes.clear();
        inbound.segments.clear();
    }

    /// Whether either end has been closed.
    pub fn is_closed(&self) -> bool {
        let shared = self.lock();
        shared.closed[0] || shared.closed[1]
    }

    /// Queue depth and latency seen from this end now.
    pub fn stats(&self) -> MemLinkStats {
        let now = self.clock.now();
        let now_units = self.now_units(now);
        let shared = self.lock();
        let out = &shared.pipes[self.side];
        let inbound = &shared.pipes[1 - self.side];
        let backlog = match self.config.effective_baud() {
            Some(baud) => {
                let free_at = out.line_free.div_ceil(baud);
                Instant::from_micros(u64::try_from(free_at).unwrap_or(u64::MAX)) - now
            }
            None => Duration::ZERO,
        };
        MemLinkStats {
            queued: out.bytes.len(),
            in_flight: out.bytes.len() - out.readable(now_units),
            backlog,
            readable: inbound.readable(now_units),
            written_total: out.written_total,
            read_total: inbound.read_total,
        }
    }

    fn now_units(&self, now: Instant) -> Option<u128> {
        self.config.effective_baud().map(|b| u128::from(now.total_micros()) * b)
    }

    fn lock(&self) -> MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl Drop for MemLink {
    fn drop(&mut self) {
        self.close();
    }
}

impl Link for MemLink {
    type Error = Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        let now_units = self.now_units(self.clock.now());
        let side = self.side;
        let mut shared = self.lock();
        if shared.closed[side] {
            return Err(Error::disconnected("mem link: this end was closed"));
        }
        let peer_closed = shared.closed[1 - side];
        let pipe = &mut shared.pipes[1 - side];
        let n = pipe.readable(now_units).min(buf.len());
        if n > 0 {
            pipe.pop(&mut buf[..n]);
            return Ok(n);
        }
        if peer_closed && pipe.bytes.is_empty() {
            return Err(Error::disconnected("mem link: the peer closed"));
        }
        Ok(0)
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        let now_units = self.now_units(self.clock.now());
        let side = self.side;
        let capacity = self.config.capacity;
        let mut shared = self.lock();
        if shared.closed[side] {
            return Err(Error::disconnected("mem link: this end was closed"));
        }
        if shared.closed[1 - side] {
            return Err(Error::disconnected("mem link: the peer closed"));
        }
        let pipe = &mut shared.pipes[side];
        let n = capacity.saturating_sub(pipe.bytes.len()).min(buf.len());
        if n > 0 {
            pipe.push(&buf[..n], now_units);
        }
        Ok(n)
    }
}

#[derive(Debug, Default)]
struct ListenerShared {
    pending: VecDeque<(MemLink, String)>,
    listening: bool,
    connections: u64,
}

/// The server side of an in-memory connection-oriented link (Carto's link port in lockstep).
#[derive(Debug)]
pub struct MemListener {
    shared: Arc<Mutex<ListenerShared>>,
}

/// The client side of an in-memory connection-oriented link: each `connect` makes a new
/// [`MemLink`] pair and queues the server end for [`MemListener::accept`](Listener::accept).
#[derive(Clone)]
pub struct MemConnector {
    shared: Arc<Mutex<ListenerShared>>,
    config: MemLinkConfig,
    clock: Arc<dyn Clock>,
}

impl std::fmt::Debug for MemConnector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MemConnector").field("config", &self.config).finish_non_exhaustive()
    }
}

/// A listener and a connector for in-memory connections with this baud rate on `clock`.
pub fn mem_listener(baud: Option<u32>, clock: impl Clock + 'static) -> (MemListener, MemConnector) {
    mem_listener_with(MemLinkConfig::with_baud(baud), clock)
}

/// Like [`mem_listener`], with a full [`MemLinkConfig`] for every connection.
pub fn mem_listener_with(config: MemLinkConfig, clock: impl Clock + 'static) -> (MemListener, MemConnector) {
    let shared = Arc::new(Mutex::new(ListenerShared { listening: true, ..Default::default() }));
    let listener = MemListener { shared: Arc::clone(&shared) };
    let connector = MemConnector { shared, config, clock: Arc::new(clock) };
    (listener, connector)
}

fn lock_listener(shared: &Mutex<ListenerShared>) -> MutexGuard<'_, ListenerShared> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

impl MemListener {
    /// Stops listening: later connects fail, and connections not yet accepted are closed.
    pub fn close(&mut self) {
        let mut shared = lock_listener(&self.shared);
        shared.listening = false;
        shared.pending.clear();
    }

    /// Connections made so far (accepted or not).
    pub fn connections(&self) -> u64 {
        lock_listener(&self.shared).connections
    }
}

impl Drop for MemListener {
    fn drop(&mut self) {
        self.close();
    }
}

impl Listener for MemListener {
    type Link = MemLink;
    type Error = Error;

    fn accept(&mut self) -> Result<Option<(MemLink, String)>, Error> {
        Ok(lock_listener(&self.shared).pending.pop_front())
    }

    fn has_pending(&mut self) -> bool {
        !lock_listener(&self.shared).pending.is_empty()
    }
}

impl Connector for MemConnector {
    type Link = MemLink;
    type Error = Error;

    fn connect(&mut self) -> Result<MemLink, Error> {
        let mut shared = lock_listener(&self.shared);
        if !shared.listening {
            return Err(Error::disconnected("mem connector: nobody listens"));
        }
        shared.connections += 1;
        let name = format!("mem:{}", shared.connections);
        let (client, server) = MemLink::pair_with(self.config, Arc::clone(&self.clock));
        shared.pending.push_back((server, name));
        Ok(client)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::MockClock;
    use crate::link::ErrorKind;

    fn readable(link: &MemLink) -> usize {
        link.stats().readable
    }

    #[test]
    fn baud_9600_ten_bytes_take_10_4_ms() {
        let clock = MockClock::new();
        let (mut a, b) = MemLink::pair(Some(9600), clock.clone());
        assert_eq!(a.write(b"0123456789").unwrap(), 10);
        assert_eq!(readable(&b), 0);
        clock.set(Instant::from_micros(1_041)); // one byte = 1041.67 µs
        assert_eq!(readable(&b), 0);
        clock.set(Instant::from_micros(1_042));
        assert_eq!(readable(&b), 1);
        clock.set(Instant::from_micros(10_416));
        assert_eq!(readable(&b), 9);
        clock.set(Instant::from_micros(10_417));
        assert_eq!(readable(&b), 10);
    }

    #[test]
    fn baud_timing_reads_match_readable_and_keep_order() {
        let clock = MockClock::new();
        let (mut a, mut b) = MemLink::pair(Some(115_200), clock.clone());
        let data: Vec<u8> = (0..=255).collect();
        assert_eq!(a.write(&data).unwrap(), 256);
        let mut got = Vec::new();
        let mut buf = [0u8; 7];
        let mut steps = 0;
        while got.len() < data.len() && steps < 10_000 {
            clock.advance(Duration::from_micros(50));
            let n = b.read(&mut buf).unwrap();
            got.extend_from_slice(&buf[..n]);
            steps += 1;
        }
        assert_eq!(got, data);
        // 256 bytes at 115200 baud: 22222.2 µs, so about 445 steps of 50 µs.
        assert_eq!(clock.now(), Instant::from_micros(22_250));
    }

    #[test]
    fn instant_mode_delivers_immediately() {
        let clock = MockClock::new();
        let (mut a, mut b) = MemLink::pair(None, clock);
        assert_eq!(a.write(b"hello").unwrap(), 5);
        let mut buf = [0u8; 8];
        assert_eq!(b.read(&mut buf).unwrap(), 5);
        assert_eq!(&buf[..5], b"hello");
        assert_eq!(a.stats().backlog, Duration::ZERO);
    }

    #[test]
    fn baud_zero_is_instant() {
        let (mut a, mut b) = MemLink::pair(Some(0), MockClock::new());
        a.write(b"x").unwrap();
        assert_eq!(b.read(&mut [0u8; 1]).unwrap(), 1);
    }

    #[test]
    fn queue_is_bounded_and_write_takes_what_fits() {
        let config = MemLinkConfig { baud: None, capacity: 100 };
        let (mut a, mut b) = MemLink::pair_with(config, MockClock::new());
        assert_eq!(a.write(&[7u8; 150]).unwrap(), 100);
        assert_eq!(a.write(&[7u8; 10]).unwrap(), 0);
        assert_eq!(a.stats().queued, 100);
        assert_eq!(b.read(&mut [0u8; 40]).unwrap(), 40);
        assert_eq!(a.write(&[7u8; 50]).unwrap(), 40);
        // The other direction has its own bound.
        assert_eq!(b.write(&[1u8; 100]).unwrap(), 100);
    }

    #[test]
    fn default_capacity_is_4096() {
        let (mut a, _b) = MemLink::pair(Some(9600), MockClock::new());
        assert_eq!(a.write(&[0u8; 5000]).unwrap(), DEFAULT_CAPACITY);
    }

    #[test]
    fn overfull_link_shows_growing_latency() {
        let clock = MockClock::new();
        let (mut a, mut b) = MemLink::pair(Some(9600), clock.clone());
        let mut backlog = Vec::new();
        for _ in 0..20 {
            // 20 bytes per ms, the line carries 0.96.
            assert_eq!(a.write(&[0x55; 20]).unwrap(), 20);
            clock.advance(Duration::from_micros(1_000));
            b.read(&mut [0u8; 64]).unwrap();
            backlog.push(a.stats().backlog.total_micros());
        }
        assert!(backlog.windows(2).all(|w| w[1] > w[0]), "{backlog:?}");
        // 400 bytes written take 416.7 ms on the line; 20 ms have passed.
        assert_eq!(backlog[19], 416_667 - 20_000);
        assert_eq!(a.stats().in_flight, 400 - 19);
    }

    #[test]
    fn idle_line_does_not_accumulate_credit() {
        let clock = MockClock::new();
        let (mut a, b) = MemLink::pair(Some(9600), clock.clone());
        clock.set(Instant::from_micros(1_000_000));
        a.write(b"ab").unwrap();
        clock.set(Instant::from_micros(1_001_041));
        assert_eq!(readable(&b), 0);
        clock.set(Instant::from_micros(1_001_042));
        assert_eq!(readable(&b), 1);
    }

    #[test]
    fn drop_delivers_remaining_bytes_then_disconnects() {
        let clock = MockClock::new();
        let (mut a, mut b) = MemLink::pair(Some(9600), clock.clone());
        a.write(b"bye").unwrap();
        drop(a);
        let mut buf = [0u8; 8];
        assert_eq!(b.read(&mut buf).unwrap(), 0, "still on the wire");
        clock.advance(Duration::from_micros(3_200));
        assert_eq!(b.read(&mut buf).unwrap(), 3);
        assert_eq!(b.read(&mut buf).unwrap_err().kind(), ErrorKind::Disconnected);
        assert_eq!(b.read(&mut buf).unwrap_err().kind(), ErrorKind::Disconnected);
        assert_eq!(b.write(b"x").unwrap_err().kind(), ErrorKind::Disconnected);
    }

    #[test]
    fn close_fails_both_ends() {
        let (mut a, mut b) = MemLink::pair(None, MockClock::new());
        b.write(b"unread").unwrap();
        a.close();
        assert!(a.is_closed() && b.is_closed());
        assert!(a.read(&mut [0u8; 4]).unwrap_err().is_disconnected());
        assert!(a.write(b"x").unwrap_err().is_disconnected());
        assert!(b.read(&mut [0u8; 4]).unwrap_err().is_disconnected());
    }

    #[test]
    fn connect_without_listener_is_disconnected() {
        let (listener, mut connector) = mem_listener(None, MockClock::new());
        drop(listener);
        assert_eq!(connector.connect().unwrap_err().kind(), ErrorKind::Disconnected);
    }

    #[test]
    fn listener_sees_each_connection_once() {
        let clock = MockClock::new();
        let (mut listener, mut connector) = mem_listener(Some(115_200), clock.clone());
        assert!(listener.accept().unwrap().is_none());
        let mut c1 = connector.connect().unwrap();
        let _c2 = connector.connect().unwrap();
        let (mut s1, n1) = listener.accept().unwrap().unwrap();
        let (_s2, n2) = listener.accept().unwrap().unwrap();
        assert!(listener.accept().unwrap().is_none());
        assert_eq!((n1.as_str(), n2.as_str()), ("mem:1", "mem:2"));
        assert_eq!(listener.connections(), 2);
        // The accepted end talks to the first client, with the listener's baud rate.
        assert_eq!(s1.config().baud, Some(115_200));
        assert_eq!(c1.write(b"hi").unwrap(), 2);
        let mut buf = [0u8; 4];
        assert_eq!(s1.read(&mut buf).unwrap(), 0, "bytes still on the wire");
        clock.advance(Duration::from_micros(174)); // 2 × 86.8 µs
        assert_eq!(s1.read(&mut buf).unwrap(), 2);
        assert_eq!(&buf[..2], b"hi");
    }

    #[test]
    fn closing_listener_closes_unaccepted_connections() {
        let (mut listener, mut connector) = mem_listener(None, MockClock::new());
        let mut client = connector.connect().unwrap();
        listener.close();
        assert!(client.read(&mut [0u8; 4]).unwrap_err().is_disconnected());
        assert!(connector.connect().unwrap_err().is_disconnected());
    }
}
