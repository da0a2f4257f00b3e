//! Input: one byte choosing the chunk size, then the stream.
//! Checks: no panic; chunking does not change the output; every decoded message re-emits to a
//! frame that parses back to it.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::link::{Decoder, Frame, GuiMessage, MsgOrder};

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, bytes)) = data.split_first() else {
        return;
    };
    let _ = GuiMessage::parse(&Frame::new_unchecked(bytes));

    let mut whole = Decoder::new(256);
    let expected = whole.feed(bytes);
    let mut chunked = Decoder::new(256);
    let got: Vec<_> = bytes
        .chunks(usize::from(chunk).max(1))
        .flat_map(|c| chunked.feed(c))
        .collect();
    assert_eq!(got, expected);
    assert!(chunked.buffered() <= 257);

    for message in expected.iter().flatten() {
        for order in [MsgOrder::BigEndian, MsgOrder::LittleEndian] {
            let frame = message.to_bytes(order);
            assert_eq!(
                GuiMessage::parse(&Frame::new_unchecked(&frame[..])).as_ref(),
                Ok(message)
            );
        }
    }
});
