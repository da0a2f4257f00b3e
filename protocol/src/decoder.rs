//! `Decoder`: the one streaming interface of the three wire formats.
//!
//! A decoder is sans-IO: the caller pushes whatever bytes it read into [`Decoder::feed`] and gets
//! back, in stream order, every frame those bytes completed and every error they revealed. It
//! never reads, never waits and never looks at a clock. Each implementation keeps a bounded
//! buffer (one partial frame at most) and counters of its own ([`Decoder::Stats`]).
//!
//! | implementation | `Frame` | `Stats` | recovery |
//! |---|---|---|---|
//! | [`link::Decoder`](crate::link::Decoder) | `GuiMessage` | [`link::DecoderStats`](crate::link::DecoderStats) | none (TCP): a bad `Size` is fatal until `reset` |
//! | [`motor::Decoder`](crate::motor::Decoder) | `MotorPacket` | [`motor::DecoderStats`](crate::motor::DecoderStats) | [`Resync`](crate::resync::Resync) on `0xAA` |
//! | [`sensor::Decoder`](crate::sensor::Decoder) | `SensorPacket` | [`ResyncStats`](crate::resync::ResyncStats) | [`Resync`](crate::resync::Resync), one byte at a time |
//!
//! The trait mirrors each type's inherent methods, so code that holds a concrete decoder keeps
//! calling `decoder.feed(..)` without importing it; code that serves several formats is written
//! once over `D: Decoder`.
//!
//! ```
//! use protocol::{Decoder, motor, sensor};
//!
//! /// Feeds a capture one byte at a time, as a UART would, and counts the frames.
//! fn count_frames<D: Decoder>(decoder: &mut D, capture: &[u8]) -> usize {
//!     capture.iter().flat_map(|b| decoder.feed(&[*b])).filter(Result::is_ok).count()
//! }
//!
//! let seed = [0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x0A];
//! assert_eq!(count_frames(&mut motor::Decoder::new(motor::ChecksumPolicy::Sum), &seed), 1);
//! let keep_alive = [0x01, 0x03, 0x01, 0x00, 0x01];
//! assert_eq!(count_frames(&mut sensor::Decoder::new(), &keep_alive), 1);
//! ```

/// A sans-IO streaming decoder: bytes in, frames and errors out.
pub trait Decoder {
    /// What a good frame decodes to.
    type Frame;
    /// Why bytes were rejected.
    type Error;
    /// The decoder's counters.
    type Stats: Copy + core::fmt::Debug + Default + PartialEq;

    /// Consumes all of `bytes` and returns every frame or error they complete, in order.
    fn feed(&mut self, bytes: &[u8]) -> Vec<Result<Self::Frame, Self::Error>>;

    /// Counters since the decoder was made.
    fn stats(&self) -> Self::Stats;

    /// Bytes of a partial frame held, waiting for the rest.
    fn buffered(&self) -> usize;

    /// Drops any partial frame, as at the start of a new stream.
    fn reset(&mut self);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{link, motor, sensor};

    /// Feeds `bytes` through the trait, leaves a partial frame, resets, and reports what it saw.
    fn through_trait<D: Decoder>(decoder: &mut D, bytes: &[u8], partial: &[u8]) -> (usize, usize, usize) {
        let ok = decoder.feed(bytes).iter().filter(|item| item.is_ok()).count();
        assert!(decoder.feed(partial).is_empty());
        let buffered = decoder.buffered();
        decoder.reset();
        (ok, buffered, decoder.buffered())
    }

    #[test]
    fn every_decoder_works_through_the_trait() {
        let link_frame = link::GuiMessage::MoveDone.to_bytes(link::MsgOrder::BigEndian);
        let mut link = link::Decoder::default();
        assert_eq!(through_trait(&mut link, &link_frame, &link_frame[..3]), (1, 3, 0));
        assert_eq!(Decoder::stats(&link), link.stats());

        let seed = [0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x0A];
        let mut motor = motor::Decoder::new(motor::ChecksumPolicy::Sum);
        assert_eq!(through_trait(&mut motor, &seed, &seed[..2]), (1, 2, 0));
        assert_eq!(Decoder::stats(&motor).frames, 1);

        let keep_alive = [0x01, 0x03, 0x01, 0x00, 0x01];
        let mut sensor = sensor::Decoder::new();
        assert_eq!(through_trait(&mut sensor, &keep_alive, &keep_alive[..4]), (1, 4, 0));
        assert_eq!(Decoder::stats(&sensor).bytes_in_frames, 5);
    }
}
