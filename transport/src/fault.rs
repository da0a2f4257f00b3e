//! A seeded fault-injecting wrapper around any [`Link`], like smoltcp's `FaultInjector`.
//!
//! Each byte that passes is, in this order: dropped with `drop_rate`; otherwise one random bit is
//! flipped with `flip_rate`; then it is sent twice with `duplicate_rate`. Rates are per byte and
//! set per direction ([`ByteFaults`] for reads and for writes). Received bytes can also be held
//! back a fixed delay, and the whole link can be cut at a given time: from then on every call
//! fails with `Disconnected` and the wrapped link is dropped, so its peer sees the disconnect too.
//!
//! Invariants:
//! - Deterministic: each direction draws from its own ChaCha8 stream of the seed (stream 0 for
//!   reads, 1 for writes), a fixed number of draws per byte given the decisions, so the same seed
//!   and the same byte sequence give the same output and counters, however the bytes are chunked
//!   and however reads and writes interleave.
//! - Rates are clamped to `[0, 1]` (NaN counts as 0).
//! - A write reports input bytes as taken once they have been through the faults; if the wrapped
//!   link takes only part of the result, the rest (at most [`WRITE_CHUNK`]·2 bytes) is held and
//!   sent first on the next read or write.
//! - Time (delay, disconnect) comes only from the [`Clock`] given at construction.
//!
//! ```
//! use robot_model::time::Instant;
//! use transport::{ByteFaults, FaultInjector, Link, MemLink, MockClock};
//! let clock = MockClock::new();
//! let (a, mut b) = MemLink::pair(None, clock.clone());
//! let mut a = FaultInjector::new(a, 42, clock.clone())
//!     .tx_faults(ByteFaults { drop_rate: 0.5, ..ByteFaults::NONE })
//!     .disconnect_at(Instant::from_millis(1));
//! a.write(&[0u8; 1000])?;
//! let dropped = a.counters().tx.dropped;
//! assert!((400..600).contains(&dropped));
//! assert_eq!(b.read(&mut [0u8; 1000])?, 1000 - dropped as usize);
//! clock.set(Instant::from_millis(1));
//! assert!(a.write(b"x").unwrap_err().is_disconnected());
//! assert!(b.read(&mut [0u8; 1]).unwrap_err().is_disconnected());
//! # Ok::<(), transport::Error>(())
//! ```

use std::collections::VecDeque;
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot_model::time::{Duration, Instant};

use crate::clock::Clock;
use crate::link::{Error, Link};

/// Input bytes put through the faults per step of a write.
pub const WRITE_CHUNK: usize = 256;

/// Per-byte fault rates for one direction, each in `[0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ByteFaults {
    /// Probability that a byte is lost.
    pub drop_rate: f64,
    /// Probability that one random bit of a (kept) byte is inverted.
    pub flip_rate: f64,
    /// Probability that a (kept) byte is delivered twice.
    pub duplicate_rate: f64,
}

impl ByteFaults {
    /// No faults.
    pub const NONE: ByteFaults = ByteFaults { drop_rate: 0.0, flip_rate: 0.0, duplicate_rate: 0.0 };

    fn clamped(self) -> ByteFaults {
        fn clamp(r: f64) -> f64 {
            if r.is_nan() { 0.0 } else { r.clamp(0.0, 1.0) }
        }
        ByteFaults {
            drop_rate: clamp(self.drop_rate),
            flip_rate: clamp(self.flip_rate),
            duplicate_rate: clamp(self.duplicate_rate),
        }
    }

    fn is_none(&self) -> bool {
        self.drop_rate == 0.0 && self.flip_rate == 0.0 && self.duplicate_rate == 0.0
    }
}

/// Everything a [`FaultInjector`] does, changeable while it runs ([`FaultInjector::set_config`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FaultConfig {
    /// Faults on bytes read from the wrapped link.
    pub rx: ByteFaults,
    /// Faults on bytes written to the wrapped link.
    pub tx: ByteFaults,
    /// Received bytes become readable this long after they were read from the wrapped link.
    pub rx_delay: Duration,
    /// From this time on, the link is cut.
    pub disconnect_at: Option<Instant>,
}

/// What the injector did to one direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DirectionCounters {
    /// Bytes that entered the faults.
    pub bytes_in: u64,
    /// Bytes that came out (after drops and duplicates).
    pub bytes_out: u64,
    /// Bytes dropped.
    pub dropped: u64,
    /// Bytes with a bit flipped.
    pub flipped: u64,
    /// Bytes duplicated.
    pub duplicated: u64,
}

/// What the injector did, per direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FaultCounters {
    /// On reads.
    pub rx: DirectionCounters,
    /// On writes.
    pub tx: DirectionCounters,
    /// Whether the link has been cut.
    pub disconnected: bool,
}

/// A seeded fault-injecting wrapper (see the [module docs](self)).
pub struct FaultInjector<L> {
    inner: Option<L>,
    config: FaultConfig,
    clock: Arc<dyn Clock>,
    rx_rng: ChaCha8Rng,
    tx_rng: ChaCha8Rng,
    /// Received bytes and the time they become readable.
    rx_queue: VecDeque<(Instant, u8)>,
    rx_scratch: Vec<u8>,
    /// An error from the wrapped link, reported once the delayed bytes are out.
    rx_error: Option<Error>,
    tx_pending: VecDeque<u8>,
    counters: FaultCounters,
}

impl<L> std::fmt::Debug for FaultInjector<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaultInjector")
            .field("config", &self.config)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

fn cut_error() -> Error {
    Error::disconnected("fault injector: link cut at the scheduled time")
}

/// Puts one byte through `faults`, appending what comes out to `out`.
fn apply(
    byte: u8,
    faults: &ByteFaults,
    rng: &mut ChaCha8Rng,
    counters: &mut DirectionCounters,
    mut out: impl FnMut(u8),
) {
    counters.bytes_in += 1;
    if rng.random::<f64>() < faults.drop_rate {
        counters.dropped += 1;
        return;
    }
    let mut b = byte;
    if rng.random::<f64>() < faults.flip_rate {
        b ^= 1 << rng.random_range(0..8u32);
        counters.flipped += 1;
    }
    out(b);
    counters.bytes_out += 1;
    if rng.random::<f64>() < faults.duplicate_rate {
        out(b);
        counters.bytes_out += 1;
        counters.duplicated += 1;
    }
}

impl<L: Link> FaultInjector<L> {
    /// Wraps `inner` with no faults yet; `seed` fixes every random decision, `clock` gives time.
    pub fn new(inner: L, seed: u64, clock: impl Clock + 'static) -> Self {
        let rx_rng = ChaCha8Rng::seed_from_u64(seed);
        let mut tx_rng = ChaCha8Rng::seed_from_u64(seed);
        tx_rng.set_stream(1);
        FaultInjector {
            inner: Some(inner),
            config: FaultConfig::default(),
            clock: Arc::new(clock),
            rx_rng,
            tx_rng,
            rx_queue: VecDeque::new(),
            rx_scratch: Vec::new(),
            rx_error: None,
            tx_pending: VecDeque::new(),
            counters: FaultCounters::default(),
        }
    }

    /// The same injector with the whole configuration replaced.
    pub fn with_config(mut self, config: FaultConfig) -> Self {
        self.set_config(config);
        self
    }

    /// The same injector with these faults on received bytes.
    pub fn rx_faults(mut self, faults: ByteFaults) -> Self {
        self.config.rx = faults.clamped();
        self
    }

    /// The same injector with these faults on written bytes.
    pub fn tx_faults(mut self, faults: ByteFaults) -> Self {
        self.config.tx = faults.clamped();
        self
    }

    /// The same injector holding received bytes back by `delay`.
    pub fn rx_delay(mut self, delay: Duration) -> Self {
        self.config.rx_delay = delay;
        self
    }

    /// The same injector cutting the link at `at`.
    pub fn disconnect_at(mut self, at: Instant) -> Self {
        self.config.disconnect_at = Some(at);
        self
    }

    /// Changes the faults from now on (a scenario's fault injection at a given time).
    pub fn set_config(&mut self, config: FaultConfig) {
        self.config = FaultConfig { rx: config.rx.clamped(), tx: config.tx.clamped(), ..config };
    }

    /// The faults in force.
    pub fn config(&self) -> FaultConfig {
        self.config
    }

    /// What has been done so far.
    pub fn counters(&self) -> FaultCounters {
        self.counters
    }

    /// Cuts the link now, as if the disconnect time had come.
    pub fn disconnect_now(&mut self) {
        self.inner = None;
        self.rx_queue.clear();
        self.tx_pending.clear();
        self.counters.disconnected = true;
    }

    /// The wrapped link, unless the link has been cut.
    pub fn inner(&self) -> Option<&L> {
        self.inner.as_ref()
    }

    /// The wrapped link, mutably, unless the link has been cut.
    pub fn inner_mut(&mut self) -> Option<&mut L> {
        self.inner.as_mut()
    }

    /// Unwraps, giving back the wrapped link unless it has been cut.
    pub fn into_inner(self) -> Option<L> {
        self.inner
    }

    /// Cuts the link when its time has come; `Disconnected` once it is cut.
    fn check_live(&mut self, now: Instant) -> Result<(), Error> {
        if self.config.disconnect_at.is_some_and(|at| now >= at) && self.inner.is_some() {
            tracing::debug!(%now, "fault injector: cutting the link");
            self.disconnect_now();
        }
        if self.inner.is_some() { Ok(()) } else { Err(cut_error()) }
    }

    /// Sends held-back written bytes; `Ok(true)` when none are left.
    fn flush_tx(&mut self, now: Instant) -> Result<bool, Error> {
        self.check_live(now)?;
        while !self.tx_pending.is_empty() {
            let inner = self.inner.as_mut().ok_or_else(cut_error)?;
            let n = inner.write(self.tx_pending.make_contiguous()).map_err(|e| Error::from_link_error(&e))?;
            if n == 0 {
                return Ok(false);
            }
            self.tx_pending.drain(..n);
        }
        Ok(true)
    }
}

impl<L: Link> Link for FaultInjector<L> {
    type Error = Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        let now = self.clock.now();
        self.check_live(now)?;
        // Written bytes held back must not wait for the next write; their errors show there.
        let _ = self.flush_tx(now);
        if !buf.is_empty() && self.rx_error.is_none() {
            self.rx_scratch.resize(buf.len(), 0);
            let inner = self.inner.as_mut().ok_or_else(cut_error)?;
            match inner.read(&mut self.rx_scratch) {
                Ok(n) => {
                    let release = now + self.config.rx_delay;
                    let faults = self.config.rx;
                    for &byte in &self.rx_scratch[..n] {
                        if faults.is_none() {
                            self.counters.rx.bytes_in += 1;
                            self.counters.rx.bytes_out += 1;
                            self.rx_queue.push_back((release, byte));
                        } else {
                            let queue = &mut self.rx_queue;
                            apply(byte, &faults, &mut self.rx_rng, &mut self.counters.rx, |b| {
                                queue.push_back((release, b))
                            });
                        }
                    }
                }
                Err(e) => self.rx_error = Some(Error::from_link_error(&e)),
            }
        }
        let mut n = 0;
        while n < buf.len() {
            match self.rx_queue.front() {
                Some(&(release, byte)) if release <= now => {
                    buf[n] = byte;
                    n += 1;
                    self.rx_queue.pop_front();
                }
                _ => break,
            }
        }
        if n == 0
            && self.rx_queue.is_empty()
            && let Some(e) = self.rx_error.take()
        {
            return Err(e);
        }
        Ok(n)
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        let now = self.clock.now();
        self.check_live(now)?;
        let mut taken = 0;
        loop {
            match self.flush_tx(now) {
                Ok(true) => {}
                Ok(false) => return Ok(taken),
                // A gone peer is reported at once (what was taken cannot arrive anyway); another
                // error after taking bytes shows on the next call, so nothing is sent twice.
                Err(e) if taken == 0 || e.is_disconnected() => return Err(e),
                Err(_) => return Ok(taken),
            }
            if taken == buf.len() {
                return Ok(taken);
            }
            let end = buf.len().min(taken + WRITE_CHUNK);
            let faults = self.config.tx;
            for &byte in &buf[taken..end] {
                let pending = &mut self.tx_pending;
                apply(byte, &faults, &mut self.tx_rng, &mut self.counters.tx, |b| pending.push_back(b));
            }
            taken = end;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::MockClock;
    use crate::link::ErrorKind;
    use crate::mem::{MemLink, MemLinkConfig};

    const N: usize = 100_000;

    fn pattern(n: usize) -> Vec<u8> {
        (0..n).map(|i| (i * 7 + i / 251) as u8).collect()
    }

    /// Sends `input` through a mem pair whose receiving end injects `faults`, reading in
    /// `chunk`-byte pieces; returns what came out and the counters.
    fn run_rx(seed: u64, faults: ByteFaults, input: &[u8], chunk: usize) -> (Vec<u8>, FaultCounters) {
        let clock = MockClock::new();
        let config = MemLinkConfig { baud: None, capacity: input.len() };
        let (mut a, b) = MemLink::pair_with(config, clock.clone());
        let mut b = FaultInjector::new(b, seed, clock).rx_faults(faults);
        assert_eq!(a.write(input).unwrap(), input.len());
        let mut out = Vec::new();
        let mut buf = vec![0u8; chunk];
        // A read may return nothing because every byte it got was dropped: stop only when the
        // whole input has been through the faults and nothing more comes out.
        loop {
            let n = b.read(&mut buf).unwrap();
            out.extend_from_slice(&buf[..n]);
            if n == 0 && b.counters().rx.bytes_in == input.len() as u64 {
                break;
            }
        }
        (out, b.counters())
    }

    const NOISY: ByteFaults = ByteFaults { drop_rate: 0.05, flip_rate: 0.05, duplicate_rate: 0.05 };

    #[test]
    fn same_seed_same_output() {
        let input = pattern(10_000);
        let (out1, c1) = run_rx(7, NOISY, &input, 64);
        let (out2, c2) = run_rx(7, NOISY, &input, 64);
        assert_eq!(out1, out2);
        assert_eq!(c1, c2);
        assert_ne!(out1, input);
    }

    #[test]
    fn different_seed_different_output() {
        let input = pattern(10_000);
        let (out1, _) = run_rx(7, NOISY, &input, 64);
        let (out2, _) = run_rx(8, NOISY, &input, 64);
        assert_ne!(out1, out2);
    }

    #[test]
    fn output_does_not_depend_on_chunking() {
        let input = pattern(10_000);
        let (out1, c1) = run_rx(3, NOISY, &input, 1);
        let (out2, c2) = run_rx(3, NOISY, &input, 4096);
        assert_eq!(out1, out2);
        assert_eq!(c1, c2);
    }

    #[test]
    fn no_faults_passes_everything() {
        let input = pattern(5_000);
        let (out, c) = run_rx(1, ByteFaults::NONE, &input, 100);
        assert_eq!(out, input);
        assert_eq!((c.rx.bytes_in, c.rx.bytes_out), (5_000, 5_000));
    }

    #[test]
    fn drop_rate_roughly_as_configured() {
        let input = pattern(N);
        let faults = ByteFaults { drop_rate: 0.1, ..ByteFaults::NONE };
        let (out, c) = run_rx(11, faults, &input, 1024);
        // Expected 10,000, standard deviation ~95: the band is > 10 sigma wide.
        assert!((9_000..11_000).contains(&c.rx.dropped), "{c:?}");
        assert_eq!(out.len() as u64, N as u64 - c.rx.dropped);
        assert_eq!((c.rx.flipped, c.rx.duplicated), (0, 0));
        // Kept bytes are unchanged and in order: the output is a subsequence of the input.
        let mut it = input.iter();
        assert!(out.iter().all(|b| it.any(|x| x == b)));
    }

    #[test]
    fn flip_rate_roughly_as_configured_one_bit_each() {
        let input = pattern(N);
        let faults = ByteFaults { flip_rate: 0.02, ..ByteFaults::NONE };
        let (out, c) = run_rx(12, faults, &input, 1024);
        assert!((1_600..2_400).contains(&c.rx.flipped), "{c:?}");
        assert_eq!(out.len(), N);
        let diffs: Vec<u32> =
            input.iter().zip(&out).map(|(a, b)| (a ^ b).count_ones()).filter(|&d| d > 0).collect();
        assert_eq!(diffs.len() as u64, c.rx.flipped);
        assert!(diffs.iter().all(|&d| d == 1));
    }

    #[test]
    fn duplicate_rate_roughly_as_configured() {
        let input = pattern(N);
        let faults = ByteFaults { duplicate_rate: 0.01, ..ByteFaults::NONE };
        let (out, c) = run_rx(13, faults, &input, 1024);
        assert!((800..1_200).contains(&c.rx.duplicated), "{c:?}");
        assert_eq!(out.len() as u64, N as u64 + c.rx.duplicated);
        assert_eq!(c.rx.bytes_out, out.len() as u64);
    }

    #[test]
    fn rates_are_clamped() {
        let input = pattern(100);
        let faults = ByteFaults { drop_rate: 7.0, flip_rate: f64::NAN, duplicate_rate: -1.0 };
        let (out, c) = run_rx(1, faults, &input, 100);
        assert!(out.is_empty());
        assert_eq!(c.rx.dropped, 100);
    }

    #[test]
    fn tx_faults_apply_to_writes_and_partial_writes_keep_every_byte() {
        let clock = MockClock::new();
        let config = MemLinkConfig { baud: None, capacity: 100 };
        let (a, mut b) = MemLink::pair_with(config, clock.clone());
        let faults = ByteFaults { duplicate_rate: 0.5, ..ByteFaults::NONE };
        let mut a = FaultInjector::new(a, 5, clock).tx_faults(faults);
        let input = pattern(2_000);
        let (mut sent, mut out) = (0, Vec::new());
        let mut buf = [0u8; 37];
        for _ in 0..10_000 {
            // Once everything is taken, the empty write only pushes out what is held back.
            sent += a.write(&input[sent..]).unwrap();
            let n = b.read(&mut buf).unwrap();
            out.extend_from_slice(&buf[..n]);
            if sent == input.len() && out.len() as u64 == a.counters().tx.bytes_out {
                break;
            }
        }
        let c = a.counters().tx;
        assert_eq!(c.bytes_in, 2_000);
        assert!((800..1_200).contains(&c.duplicated), "{c:?}");
        assert_eq!(out.len() as u64, 2_000 + c.duplicated);
        let mut dedup = out.clone();
        dedup.dedup();
        let mut expect = input.clone();
        expect.dedup();
        assert_eq!(dedup, expect);
    }

    #[test]
    fn rx_and_tx_streams_are_independent() {
        // The read side's output must not change when writes interleave with reads.
        let input = pattern(3_000);
        let (plain, _) = run_rx(9, NOISY, &input, 64);
        let clock = MockClock::new();
        let config = MemLinkConfig { baud: None, capacity: input.len() };
        let (mut a, b) = MemLink::pair_with(config, clock.clone());
        let mut b = FaultInjector::new(b, 9, clock).rx_faults(NOISY).tx_faults(NOISY);
        a.write(&input).unwrap();
        let mut out = Vec::new();
        let mut buf = [0u8; 64];
        loop {
            b.write(b"noise").unwrap();
            let n = b.read(&mut buf).unwrap();
            out.extend_from_slice(&buf[..n]);
            if n == 0 && b.counters().rx.bytes_in == input.len() as u64 {
                break;
            }
        }
        assert_eq!(out, plain);
    }

    #[test]
    fn fixed_delay_holds_bytes_back() {
        let clock = MockClock::new();
        let (mut a, b) = MemLink::pair(None, clock.clone());
        let mut b = FaultInjector::new(b, 0, clock.clone()).rx_delay(Duration::from_micros(5_000));
        clock.set(Instant::from_micros(1_000));
        a.write(b"late").unwrap();
        let mut buf = [0u8; 8];
        assert_eq!(b.read(&mut buf).unwrap(), 0);
        clock.set(Instant::from_micros(5_999));
        assert_eq!(b.read(&mut buf).unwrap(), 0);
        clock.set(Instant::from_micros(6_000));
        assert_eq!(b.read(&mut buf).unwrap(), 4);
        assert_eq!(&buf[..4], b"late");
    }

    #[test]
    fn delayed_bytes_come_before_the_disconnect() {
        let clock = MockClock::new();
        let (mut a, b) = MemLink::pair(None, clock.clone());
        let mut b = FaultInjector::new(b, 0, clock.clone()).rx_delay(Duration::from_micros(1_000));
        a.write(b"end").unwrap();
        drop(a);
        let mut buf = [0u8; 8];
        assert_eq!(b.read(&mut buf).unwrap(), 0);
        clock.set(Instant::from_micros(1_000));
        assert_eq!(b.read(&mut buf).unwrap(), 3);
        assert!(b.read(&mut buf).unwrap_err().is_disconnected());
    }

    #[test]
    fn disconnect_at_time_cuts_both_sides() {
        let clock = MockClock::new();
        let (a, mut b) = MemLink::pair(None, clock.clone());
        let mut a = FaultInjector::new(a, 0, clock.clone()).disconnect_at(Instant::from_micros(10_000));
        clock.set(Instant::from_micros(9_999));
        assert_eq!(a.write(b"ok").unwrap(), 2);
        assert!(!a.counters().disconnected);
        clock.set(Instant::from_micros(10_000));
        assert_eq!(a.read(&mut [0u8; 4]).unwrap_err().kind(), ErrorKind::Disconnected);
        assert!(a.write(b"no").unwrap_err().is_disconnected());
        assert!(a.counters().disconnected);
        assert!(a.inner().is_none());
        // The peer gets what was sent before the cut, then the disconnect.
        let mut buf = [0u8; 4];
        assert_eq!(b.read(&mut buf).unwrap(), 2);
        assert!(b.read(&mut buf).unwrap_err().is_disconnected());
    }

    #[test]
    fn inner_errors_pass_through_with_their_kind() {
        let clock = MockClock::new();
        let (a, b) = MemLink::pair(None, clock.clone());
        let mut a = FaultInjector::new(a, 0, clock);
        drop(b);
        let err = a.write(b"x").unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Disconnected);
        assert_eq!(err.context(), "mem link: the peer closed");
    }
}
