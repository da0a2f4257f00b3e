//! `resync`: the one streaming engine of the formats that can lose sync (motor, sensor).
//!
//! **Concept.** A [`Framing`] says two things about the bytes at the head of the stream: how long
//! the frame starting there is, as far as its first bytes tell ([`Framing::head`]), and whether a
//! whole candidate is a valid frame ([`Framing::parse`]). [`Resync`] does everything else, the same
//! way for every format, in the shape of ublox's parser and postcard's accumulator:
//!
//! - it decodes straight from the caller's slice, and copies only a trailing partial frame into
//!   its buffer;
//! - [`Head::Skip`] drops bytes that cannot start a frame, silently (e.g. up to the next `0xAA`);
//! - [`Head::Reject`], or a whole candidate that [`Framing::parse`] refuses, drops **one** byte and
//!   scans again from the next, so a good frame hidden inside a rejected one is still found;
//! - rejections are reported as `Err` items according to [`Framing::REPORT`].
//!
//! **Invariants.**
//! - The buffer never holds more than [`Framing::MAX_FRAME_LEN`] bytes, and only ever a prefix
//!   that [`Framing::head`] called [`Head::Partial`].
//! - Every byte fed is counted once: `bytes == bytes_in_frames + bytes_skipped + buffered()`.
//! - The output does not depend on how the stream is split into `feed` calls, as long as
//!   [`Framing::head`] judges a prefix by its first bytes only (a longer prefix never changes a
//!   verdict other than `Partial`).
//! - No input makes it panic. A framing that breaks its own contract (a `Partial` that asks for
//!   no more bytes, or for more than `MAX_FRAME_LEN`; a `Complete` longer than what it was shown)
//!   costs one skipped byte, never a stall, an overgrown buffer or a panic.
//!
//! ```
//! use protocol::resync::{Framing, Head, Report, Resync};
//!
//! /// A toy format: `7E · LEN · PAYLOAD`; an empty payload is an error.
//! struct Tiny;
//!
//! impl Framing for Tiny {
//!     type Frame = Vec<u8>;
//!     type Error = &'static str;
//!     const MAX_FRAME_LEN: usize = 2 + 255;
//!     const REPORT: Report = Report::EveryRejection;
//!
//!     fn head(&self, bytes: &[u8]) -> Head<&'static str> {
//!         match bytes {
//!             [0x7E] => Head::Partial { need: 2 },
//!             [0x7E, len, ..] => match 2 + usize::from(*len) {
//!                 total if bytes.len() >= total => Head::Complete(total),
//!                 total => Head::Partial { need: total },
//!             },
//!             _ => Head::Skip(bytes.iter().position(|b| *b == 0x7E).unwrap_or(bytes.len())),
//!         }
//!     }
//!
//!     fn parse(&self, frame: &[u8]) -> Result<Vec<u8>, &'static str> {
//!         match frame.get(2..) {
//!             Some(payload) if !payload.is_empty() => Ok(payload.to_vec()),
//!             _ => Err("empty frame"),
//!         }
//!     }
//! }
//!
//! let mut decoder = Resync::new(Tiny);
//! // Noise, an empty frame (rejected: its 7E is dropped, then 00 is skipped), half a frame.
//! assert_eq!(decoder.feed(&[0x55, 0x7E, 0x00, 0x7E, 0x02, 0xAB]), vec![Err("empty frame")]);
//! assert_eq!(decoder.buffered(), 3);
//! assert_eq!(decoder.feed(&[0xCD]), vec![Ok(vec![0xAB, 0xCD])]);
//! let stats = decoder.stats();
//! assert_eq!((stats.frames, stats.errors, stats.bytes_skipped, stats.bytes_in_frames), (1, 1, 3, 4));
//! ```

use crate::decoder::Decoder;

/// What the first bytes of a candidate say about the frame starting there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Head<E> {
    /// Consistent so far; judge again once the candidate holds `need` bytes (more than now, at
    /// most [`Framing::MAX_FRAME_LEN`]).
    Partial {
        /// The candidate length at which the verdict can change.
        need: usize,
    },
    /// A whole candidate of this many bytes (at most the bytes shown): hand it to
    /// [`Framing::parse`].
    Complete(usize),
    /// This many bytes (at least 1) cannot start a frame: drop them without a report.
    Skip(usize),
    /// The first byte cannot start a frame, for this reason: drop it and report.
    Reject(E),
}

/// Which rejections become `Err` items.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Report {
    /// Every rejected candidate (a format with a sync byte and a checksum: each is evidence).
    EveryRejection,
    /// Only the first rejection after an accepted frame (or the start): one `Err` per loss of
    /// sync, for a format where a lost frame rejects many positions in a row.
    OncePerLossOfSync,
}

/// How one wire format is framed: the small part of a streaming decoder that differs per format.
pub trait Framing {
    /// What a valid frame parses to.
    type Frame;
    /// Why a candidate was rejected.
    type Error;
    /// The longest valid frame: the engine's whole buffer.
    const MAX_FRAME_LEN: usize;
    /// Which rejections are reported.
    const REPORT: Report;

    /// Judges the candidate starting at `bytes[0]` (never called with no bytes).
    ///
    /// The verdict must depend only on the bytes it needs: once it is not `Partial`, showing more
    /// bytes must not change it.
    fn head(&self, bytes: &[u8]) -> Head<Self::Error>;

    /// Parses a whole candidate, exactly the length `head` gave in [`Head::Complete`].
    fn parse(&self, frame: &[u8]) -> Result<Self::Frame, Self::Error>;
}

/// Counters kept by a [`Resync`] since it was made.
///
/// Every byte fed ends up in exactly one place: a decoded frame (`bytes_in_frames`), a dropped
/// byte (`bytes_skipped`) or the pending buffer ([`Resync::buffered`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ResyncStats {
    /// Frames decoded (`Ok` items).
    pub frames: u64,
    /// Rejections reported (`Err` items); see [`Report`].
    pub errors: u64,
    /// Bytes dropped: skipped while looking for a frame start, and the first byte of each
    /// rejected candidate.
    pub bytes_skipped: u64,
    /// Bytes decoded as part of accepted frames.
    pub bytes_in_frames: u64,
    /// Bytes fed in total.
    pub bytes: u64,
}

/// The sans-IO resynchronising decoder, generic over a [`Framing`]. See the module doc.
#[derive(Debug, Clone)]
pub struct Resync<F> {
    framing: F,
    /// A partial candidate; empty, or a prefix judged `Partial { need }` with `need > len`.
    buffer: Vec<u8>,
    need: usize,
    /// No byte dropped since the last accepted frame (or the start, or `reset`).
    in_sync: bool,
    stats: ResyncStats,
}

impl<F: Framing + Default> Default for Resync<F> {
    fn default() -> Self {
        Resync::new(F::default())
    }
}

type Items<F> = Vec<Result<<F as Framing>::Frame, <F as Framing>::Error>>;

impl<F: Framing> Resync<F> {
    /// A decoder for `framing` that assumes the stream starts on a frame boundary.
    pub fn new(framing: F) -> Self {
        Resync {
            framing,
            buffer: Vec::with_capacity(F::MAX_FRAME_LEN),
            need: 0,
            in_sync: true,
            stats: ResyncStats::default(),
        }
    }

    /// The framing.
    pub fn framing(&self) -> &F {
        &self.framing
    }

    /// Consumes all of `bytes` and returns every frame they complete and every reported
    /// rejection, in stream order.
    pub fn feed(&mut self, bytes: &[u8]) -> Items<F> {
        let mut out = Vec::new();
        self.stats.bytes += bytes.len() as u64;
        let mut input = bytes;
        while !input.is_empty() {
            if self.buffer.is_empty() {
                self.scan(input, &mut out);
                break;
            }
            // Grow the pending candidate to the length its framing asked for, then judge it again.
            let take = self.need.saturating_sub(self.buffer.len()).min(input.len());
            let (head, rest) = input.split_at(take);
            self.buffer.extend_from_slice(head);
            input = rest;
            if self.buffer.len() < self.need {
                continue;
            }
            if let Head::Partial { need } = Self::judge(&self.framing, &self.buffer) {
                self.need = need;
                continue;
            }
            let pending = core::mem::take(&mut self.buffer);
            self.scan(&pending, &mut out);
            if self.buffer.is_empty() {
                // Keep the allocation.
                self.buffer = pending;
                self.buffer.clear();
            }
        }
        out
    }

    /// Counters since creation (not cleared by `reset`).
    pub fn stats(&self) -> ResyncStats {
        self.stats
    }

    /// Bytes of a candidate frame held, waiting for the rest (at most `MAX_FRAME_LEN - 1`).
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// Drops any pending candidate and assumes the next byte starts a frame.
    pub fn reset(&mut self) {
        self.buffer.clear();
        self.need = 0;
        self.in_sync = true;
    }

    /// The framing's verdict on `bytes`, held to its contract (see the module doc).
    fn judge(framing: &F, bytes: &[u8]) -> Head<F::Error> {
        let shown = bytes.len();
        match framing.head(bytes) {
            Head::Partial { need } if need > shown && need <= F::MAX_FRAME_LEN => Head::Partial { need },
            Head::Complete(total) if total > 0 && total <= shown => Head::Complete(total),
            Head::Skip(n) => Head::Skip(n.clamp(1, shown.max(1))),
            Head::Reject(error) => Head::Reject(error),
            Head::Partial { .. } | Head::Complete(_) => Head::Skip(1),
        }
    }

    /// Decodes whole frames straight from `input` and buffers a trailing partial candidate.
    ///
    /// Called with an empty buffer only.
    fn scan(&mut self, mut input: &[u8], out: &mut Items<F>) {
        while let [_, after_first @ ..] = input {
            match Self::judge(&self.framing, input) {
                Head::Partial { need } => {
                    self.buffer.extend_from_slice(input);
                    self.need = need;
                    return;
                }
                Head::Complete(total) => {
                    let (frame, rest) = input.split_at(total.min(input.len()));
                    input = if self.accept(frame, out) { rest } else { after_first };
                }
                Head::Skip(n) => {
                    let n = n.min(input.len());
                    self.stats.bytes_skipped += n as u64;
                    input = &input[n..];
                }
                Head::Reject(error) => {
                    self.reject(error, out);
                    input = after_first;
                }
            }
        }
    }

    /// Parses one whole candidate; returns true when it was accepted.
    fn accept(&mut self, frame: &[u8], out: &mut Items<F>) -> bool {
        match self.framing.parse(frame) {
            Ok(parsed) => {
                self.in_sync = true;
                self.stats.frames += 1;
                self.stats.bytes_in_frames += frame.len() as u64;
                out.push(Ok(parsed));
                true
            }
            Err(error) => {
                self.reject(error, out);
                false
            }
        }
    }

    /// Drops the candidate's first byte and reports `error` if [`Framing::REPORT`] says so.
    fn reject(&mut self, error: F::Error, out: &mut Items<F>) {
        self.stats.bytes_skipped += 1;
        if F::REPORT == Report::EveryRejection || self.in_sync {
            self.stats.errors += 1;
            out.push(Err(error));
        }
        self.in_sync = false;
    }
}

impl<F: Framing> Decoder for Resync<F> {
    type Frame = F::Frame;
    type Error = F::Error;
    type Stats = ResyncStats;

    fn feed(&mut self, bytes: &[u8]) -> Items<F> {
        Resync::feed(self, bytes)
    }

    fn stats(&self) -> ResyncStats {
        Resync::stats(self)
    }

    fn buffered(&self) -> usize {
        Resync::buffered(self)
    }

    fn reset(&mut self) {
        Resync::reset(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A framing that breaks its contract in the way `verdict` says, on every call.
    struct Broken {
        verdict: fn(usize) -> Head<()>,
    }

    impl Framing for Broken {
        type Frame = ();
        type Error = ();
        const MAX_FRAME_LEN: usize = 4;
        const REPORT: Report = Report::EveryRejection;

        fn head(&self, bytes: &[u8]) -> Head<()> {
            (self.verdict)(bytes.len())
        }

        fn parse(&self, _frame: &[u8]) -> Result<(), ()> {
            Ok(())
        }
    }

    #[test]
    fn a_framing_that_breaks_its_contract_costs_a_byte_not_a_stall_or_a_panic() {
        let cases: [fn(usize) -> Head<()>; 5] = [
            |shown| Head::Partial { need: shown }, // asks for nothing more
            |_| Head::Partial { need: 1000 },      // asks for more than MAX_FRAME_LEN
            |shown| Head::Complete(shown + 1),     // longer than what it was shown
            |_| Head::Complete(0),                 // empty frame
            |_| Head::Skip(0),                     // skips nothing
        ];
        for verdict in cases {
            let mut decoder = Resync::new(Broken { verdict });
            assert_eq!(decoder.feed(&[1, 2, 3, 4, 5, 6, 7, 8, 9]), vec![]);
            let stats = decoder.stats();
            assert_eq!((stats.bytes, stats.bytes_skipped, decoder.buffered()), (9, 9, 0));
        }
    }

    /// `1 · x` is a 2-byte frame; any other byte is rejected.
    #[derive(Default)]
    struct Pairs;

    impl Framing for Pairs {
        type Frame = u8;
        type Error = u8;
        const MAX_FRAME_LEN: usize = 2;
        const REPORT: Report = Report::OncePerLossOfSync;

        fn head(&self, bytes: &[u8]) -> Head<u8> {
            match bytes {
                [1] => Head::Partial { need: 2 },
                [1, ..] => Head::Complete(2),
                [other, ..] => Head::Reject(*other),
                [] => Head::Skip(1),
            }
        }

        fn parse(&self, frame: &[u8]) -> Result<u8, u8> {
            frame.get(1).copied().ok_or(0)
        }
    }

    #[test]
    fn once_per_loss_of_sync_reports_the_first_rejection_only() {
        let mut decoder = Resync::<Pairs>::default();
        let out = decoder.feed(&[7, 8, 9, 1, 42, 5, 1]);
        assert_eq!(out, vec![Err(7), Ok(42), Err(5)]);
        assert_eq!(decoder.buffered(), 1);
        let stats = decoder.stats();
        assert_eq!((stats.errors, stats.bytes_skipped, stats.bytes_in_frames), (2, 4, 2));
        // A reset forgets the partial frame and starts in sync again.
        decoder.reset();
        assert_eq!(decoder.feed(&[6, 6]), vec![Err(6)]);
    }
}
