//! Input: one byte choosing the chunk size, then the stream.
//! Checks: no panic; chunking does not change the output; every byte is accounted for; never
//! two errors in a row; every decoded packet re-emits to bytes that parse and re-emit identically.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::sensor::{Decoder, Frame, MAX_FRAME_LEN, SensorPacket};

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, bytes)) = data.split_first() else {
        return;
    };
    let _ = SensorPacket::parse(&Frame::new_unchecked(bytes));

    let mut whole = Decoder::new();
    let expected = whole.feed(bytes);
    let mut chunked = Decoder::new();
    let got: Vec<_> = bytes
        .chunks(usize::from(chunk).max(1))
        .flat_map(|c| chunked.feed(c))
        .collect();
    // Compare by re-emitted bytes: floats may be NaN, which is never equal to itself.
    let as_bytes =
        |items: &[Result<SensorPacket, _>]| -> Vec<Result<Vec<u8>, protocol::sensor::DecodeError>> {
            items
                .iter()
                .map(|item| {
                    item.as_ref()
                        .map(SensorPacket::to_bytes)
                        .map_err(Clone::clone)
                })
                .collect()
        };
    assert_eq!(as_bytes(&got), as_bytes(&expected));
    let stats = chunked.stats();
    assert_eq!(
        stats.bytes,
        stats.bytes_in_frames + stats.bytes_skipped + chunked.buffered() as u64
    );
    assert!(chunked.buffered() < MAX_FRAME_LEN);
    assert!(got.windows(2).all(|w| w[0].is_ok() || w[1].is_ok()));

    for packet in expected.iter().flatten() {
        let frame = packet.to_bytes();
        let reparsed = SensorPacket::parse(&Frame::new_unchecked(&frame[..]));
        assert_eq!(reparsed.map(|p| p.to_bytes()), Ok(frame));
    }
});
