//! Input: one byte choosing the chunk size (low 6 bits) and checksum policy (top 2 bits), then
//! the stream.
//! Checks: no panic; chunking does not change the output; every byte is accounted for; every
//! decoded packet re-emits to bytes that parse and re-emit identically.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::motor::{ChecksumKind, ChecksumPolicy, Decoder, Frame, MAX_FRAME_LEN, MotorPacket};

fuzz_target!(|data: &[u8]| {
    let Some((&control, bytes)) = data.split_first() else {
        return;
    };
    let policy = [
        ChecksumPolicy::Sum,
        ChecksumPolicy::XorPayload,
        ChecksumPolicy::ConstFc,
        ChecksumPolicy::Ignore,
    ][usize::from(control >> 6)];
    let chunk = usize::from(control & 0x3F).max(1);
    let _ = MotorPacket::parse(&Frame::new_unchecked(bytes), policy);

    let mut whole = Decoder::new(policy);
    let expected = whole.feed(bytes);
    let mut chunked = Decoder::new(policy);
    let got: Vec<_> = bytes.chunks(chunk).flat_map(|c| chunked.feed(c)).collect();
    // Compare by re-emitted bytes: telemetry may carry NaN, which is never equal to itself.
    let as_bytes =
        |items: &[Result<MotorPacket, _>]| -> Vec<Result<Vec<u8>, protocol::motor::DecodeError>> {
            items
                .iter()
                .map(|item| {
                    item.as_ref()
                        .map(MotorPacket::to_bytes)
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
    assert!(chunked.buffered() <= MAX_FRAME_LEN);

    for packet in expected.iter().flatten() {
        let frame = packet.to_bytes_with(ChecksumKind::Sum);
        let reparsed = MotorPacket::parse(&Frame::new_unchecked(&frame[..]), ChecksumPolicy::Sum);
        assert_eq!(reparsed.map(|p| p.to_bytes()), Ok(frame));
    }
});
