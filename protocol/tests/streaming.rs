//! The streaming matrix (style rule 6) for each decoder: empty input, byte by byte, whole frame,
//! two frames in one chunk, a frame split at every point, garbage before, the sync byte (or a
//! header-like byte) inside a payload, the sync byte at a chunk end, a bad frame then a good one,
//! and an oversize length.

use protocol::{link, motor, sensor};

/// Feeds `chunks` one after the other and collects every item.
fn feed_all<T, E>(mut feed: impl FnMut(&[u8]) -> Vec<Result<T, E>>, chunks: &[&[u8]]) -> Vec<Result<T, E>> {
    chunks.iter().flat_map(|chunk| feed(chunk)).collect()
}

mod link_stream {
    use super::*;
    use link::{Command, DecodeError, Decoder, Direction, GuiMessage, MsgOrder, MsgType};

    fn position() -> GuiMessage {
        GuiMessage::SendRobotPosition { x: 2, y: 3, direction: Direction::East }
    }
    fn forward() -> GuiMessage {
        GuiMessage::SendMoveCartography { command: Command::Forward }
    }

    #[test]
    fn empty_input_yields_nothing() {
        let mut decoder = Decoder::default();
        assert!(decoder.feed(&[]).is_empty());
        assert_eq!(decoder.buffered(), 0);
        assert_eq!(decoder.stats(), link::DecoderStats::default());
    }

    #[test]
    fn whole_frame() {
        let mut decoder = Decoder::default();
        let bytes = position().to_bytes(MsgOrder::LittleEndian);
        assert_eq!(decoder.feed(&bytes), vec![Ok(position())]);
        assert_eq!(decoder.buffered(), 0);
        assert_eq!(decoder.last_order(), Some(MsgOrder::LittleEndian));
    }

    #[test]
    fn byte_by_byte() {
        let mut decoder = Decoder::default();
        let bytes = position().to_bytes(MsgOrder::BigEndian);
        let chunks: Vec<&[u8]> = bytes.chunks(1).collect();
        assert_eq!(feed_all(|b| decoder.feed(b), &chunks), vec![Ok(position())]);
    }

    #[test]
    fn two_frames_in_one_chunk_with_mixed_orders() {
        let mut decoder = Decoder::default();
        let mut bytes = position().to_bytes(MsgOrder::LittleEndian);
        bytes.extend(GuiMessage::MoveDone.to_bytes(MsgOrder::BigEndian));
        assert_eq!(decoder.feed(&bytes), vec![Ok(position()), Ok(GuiMessage::MoveDone)]);
        assert_eq!(decoder.last_order(), Some(MsgOrder::BigEndian));
    }

    #[test]
    fn split_at_every_point() {
        let mut bytes = position().to_bytes(MsgOrder::BigEndian);
        bytes.extend(forward().to_bytes(MsgOrder::LittleEndian));
        bytes.extend(GuiMessage::StopRobot.to_bytes(MsgOrder::BigEndian));
        for cut in 0..=bytes.len() {
            let mut decoder = Decoder::default();
            let out = feed_all(|b| decoder.feed(b), &[&bytes[..cut], &bytes[cut..]]);
            assert_eq!(out, vec![Ok(position()), Ok(forward()), Ok(GuiMessage::StopRobot)], "cut {cut}");
            assert_eq!(decoder.buffered(), 0);
        }
    }

    #[test]
    fn partial_frame_waits_in_the_buffer() {
        let mut decoder = Decoder::default();
        let bytes = position().to_bytes(MsgOrder::BigEndian);
        assert!(decoder.feed(&bytes[..5]).is_empty());
        assert_eq!(decoder.buffered(), 5);
        assert_eq!(decoder.feed(&bytes[5..]), vec![Ok(position())]);
    }

    #[test]
    fn garbage_before_is_misread_as_a_frame() {
        // No sync byte: garbage is taken as a header. `00 03 ff` reads as Size 3 and swallows the
        // next two bytes; the framing is then lost for good, as the module doc states.
        let mut decoder = Decoder::new(64);
        let mut bytes = vec![0x00, 0x03, 0xFF];
        bytes.extend(GuiMessage::MoveDone.to_bytes(MsgOrder::BigEndian));
        let out = decoder.feed(&bytes);
        assert_eq!(
            out,
            vec![
                Ok(GuiMessage::Unknown { msg: 0xFF00, data: vec![0x02] }),
                Err(DecodeError::SizeTooLarge { size: 0x0300, max: 64 }),
            ]
        );
        // `03 00` is now read as a Size of 0x0300, above the maximum of 64.
        assert_eq!(decoder.buffered(), 0);
        assert!(decoder.is_failed());
        assert_eq!(decoder.stats().errors, 1);
    }

    #[test]
    fn whole_unknown_frames_before_are_skipped_cleanly() {
        let mut decoder = Decoder::default();
        let mut bytes = vec![0x00, 0x04, 0x12, 0x34, 0xAA, 0xBB];
        bytes.extend(forward().to_bytes(MsgOrder::BigEndian));
        let out = decoder.feed(&bytes);
        assert_eq!(out, vec![Ok(GuiMessage::Unknown { msg: 0x1234, data: vec![0xAA, 0xBB] }), Ok(forward())]);
        assert_eq!(decoder.stats().unknown, 1);
    }

    #[test]
    fn header_like_bytes_inside_data_do_not_matter() {
        // Data that looks like a frame header (`00 02` …) is still data.
        let mut decoder = Decoder::default();
        let message = GuiMessage::SetRobotPosition { x: 0x00, y: 0x02 };
        let mut bytes = message.to_bytes(MsgOrder::BigEndian);
        bytes.extend(message.to_bytes(MsgOrder::BigEndian));
        assert_eq!(decoder.feed(&bytes), vec![Ok(message.clone()), Ok(message)]);
    }

    #[test]
    fn size_bytes_split_at_chunk_end() {
        let mut decoder = Decoder::default();
        let bytes = forward().to_bytes(MsgOrder::BigEndian);
        assert!(decoder.feed(&bytes[..1]).is_empty());
        assert!(decoder.feed(&bytes[1..2]).is_empty());
        assert_eq!(decoder.feed(&bytes[2..]), vec![Ok(forward())]);
    }

    #[test]
    fn bad_length_then_good_frame() {
        // Cute 2024's SEND_MOVE_CARTOGRAPHY with Size 2: reported, skipped, the stream goes on.
        let mut decoder = Decoder::default();
        let mut bytes = vec![0x00, 0x02, 0x02, 0x00];
        bytes.extend(forward().to_bytes(MsgOrder::LittleEndian));
        let out = decoder.feed(&bytes);
        assert_eq!(
            out,
            vec![
                Err(DecodeError::BadLength { msg: MsgType::SendMoveCartography, expected: 1, actual: 0 }),
                Ok(forward()),
            ]
        );
        assert!(!decoder.is_failed());
        let stats = decoder.stats();
        assert_eq!((stats.frames, stats.errors), (1, 1));
    }

    #[test]
    fn oversize_length_is_fatal_until_reset() {
        let mut decoder = Decoder::new(64);
        let mut bytes = vec![0x00, 0x41, 0x01, 0x00];
        bytes.extend(forward().to_bytes(MsgOrder::BigEndian));
        let out = decoder.feed(&bytes);
        assert_eq!(out, vec![Err(DecodeError::SizeTooLarge { size: 0x41, max: 64 })]);
        assert!(out[0].as_ref().unwrap_err().is_fatal());
        assert!(decoder.feed(&forward().to_bytes(MsgOrder::BigEndian)).is_empty());
        decoder.reset();
        assert_eq!(decoder.feed(&forward().to_bytes(MsgOrder::BigEndian)), vec![Ok(forward())]);
    }

    #[test]
    fn undersize_length_is_fatal() {
        let mut decoder = Decoder::default();
        let out = decoder.feed(&[0x00, 0x01, 0x03]);
        assert_eq!(out, vec![Err(DecodeError::SizeTooSmall { size: 1 })]);
        assert!(decoder.is_failed());
    }

    #[test]
    fn largest_allowed_frame_passes() {
        let mut decoder = Decoder::new(64);
        let message = GuiMessage::Unknown { msg: 0x7777, data: vec![0xAB; 62] };
        let bytes = message.to_bytes(MsgOrder::BigEndian);
        let chunks: Vec<&[u8]> = bytes.chunks(5).collect();
        assert_eq!(feed_all(|b| decoder.feed(b), &chunks), vec![Ok(message)]);
    }
}

mod motor_stream {
    use super::*;
    use motor::{ChecksumPolicy, DecodeError, Decoder, MotorCommand, MotorPacket, Telemetry};

    /// Seed example `AA 03 01 80 80 06 0A`.
    const SEED: [u8; 7] = [0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x0A];

    fn seed() -> MotorPacket {
        MotorPacket::Drive(MotorCommand::V1 { dir_x: 0x80, dir_y: 0x80, gear: 6 })
    }
    fn telemetry() -> MotorPacket {
        MotorPacket::Telemetry(Telemetry::motor([1.0, 2.0, 3.0, 4.0], [10.0, 20.0, -30.0, 40.0]))
    }
    fn accounted(decoder: &Decoder) {
        let s = decoder.stats();
        assert_eq!(s.bytes, s.bytes_in_frames + s.bytes_skipped + decoder.buffered() as u64, "{s:?}");
    }

    #[test]
    fn empty_input_yields_nothing() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        assert!(decoder.feed(&[]).is_empty());
        assert_eq!(decoder.stats(), motor::DecoderStats::default());
    }

    #[test]
    fn whole_frame() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        assert_eq!(decoder.feed(&SEED), vec![Ok(seed())]);
        assert_eq!(decoder.buffered(), 0);
        accounted(&decoder);
    }

    #[test]
    fn byte_by_byte() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let mut bytes = SEED.to_vec();
        bytes.extend(telemetry().to_bytes());
        let chunks: Vec<&[u8]> = bytes.chunks(1).collect();
        assert_eq!(feed_all(|b| decoder.feed(b), &chunks), vec![Ok(seed()), Ok(telemetry())]);
        accounted(&decoder);
    }

    #[test]
    fn two_frames_in_one_chunk() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let mut bytes = SEED.to_vec();
        bytes.extend(SEED);
        assert_eq!(decoder.feed(&bytes), vec![Ok(seed()), Ok(seed())]);
    }

    #[test]
    fn split_at_every_point() {
        let mut bytes = SEED.to_vec();
        bytes.extend(telemetry().to_bytes());
        bytes.extend(MotorPacket::Drive(MotorCommand::STOP_V2).to_bytes());
        for cut in 0..=bytes.len() {
            let mut decoder = Decoder::new(ChecksumPolicy::Sum);
            let out = feed_all(|b| decoder.feed(b), &[&bytes[..cut], &bytes[cut..]]);
            assert_eq!(
                out,
                vec![Ok(seed()), Ok(telemetry()), Ok(MotorPacket::Drive(MotorCommand::STOP_V2))],
                "cut {cut}"
            );
            accounted(&decoder);
        }
    }

    #[test]
    fn garbage_before() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let mut bytes = vec![0x00, 0x13, 0x55, 0xFF, 0x37];
        bytes.extend(SEED);
        assert_eq!(decoder.feed(&bytes), vec![Ok(seed())]);
        assert_eq!(decoder.stats().bytes_skipped, 5);
        accounted(&decoder);
    }

    #[test]
    fn sync_byte_inside_payload() {
        // dir_x = 0xAA and gear = 0xAA: the decoder must not restart on them.
        let packet = MotorPacket::Drive(MotorCommand::V1 { dir_x: 0xAA, dir_y: 0x80, gear: 0xAA });
        let bytes = packet.to_bytes();
        assert_eq!(&bytes[..6], &[0xAA, 0x03, 0x01, 0xAA, 0x80, 0xAA]);
        for chunk_len in 1..=bytes.len() {
            let mut decoder = Decoder::new(ChecksumPolicy::Sum);
            let chunks: Vec<&[u8]> = bytes.chunks(chunk_len).collect();
            assert_eq!(feed_all(|b| decoder.feed(b), &chunks), vec![Ok(packet.clone())]);
            assert_eq!(decoder.stats().bytes_skipped, 0);
        }
    }

    #[test]
    fn sync_byte_at_chunk_end() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        assert!(decoder.feed(&[0x01, 0x02, 0xAA]).is_empty());
        assert_eq!(decoder.buffered(), 1);
        assert_eq!(decoder.feed(&SEED[1..]), vec![Ok(seed())]);
        accounted(&decoder);
    }

    #[test]
    fn bad_checksum_then_good_frame() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let mut corrupted = SEED;
        corrupted[4] ^= 0x01; // payload bit flip
        let mut bytes = corrupted.to_vec();
        bytes.extend(SEED);
        let out = decoder.feed(&bytes);
        assert_eq!(out, vec![Err(DecodeError::BadChecksum { expected: 0x0B, actual: 0x0A }), Ok(seed())]);
        assert_eq!(decoder.stats().checksum_errors, 1);
        accounted(&decoder);
    }

    #[test]
    fn bad_length_then_good_frame() {
        // Drive v1 with LEN 2, valid checksum (02 + 01 + 80 + 80 = 0x103 → 0x03).
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let mut bytes = vec![0xAA, 0x02, 0x01, 0x80, 0x80, 0x03];
        bytes.extend(SEED);
        let out = decoder.feed(&bytes);
        assert!(matches!(out[0], Err(DecodeError::BadLength { actual: 2, .. })), "{out:?}");
        assert_eq!(out[1..], [Ok(seed())]);
        assert_eq!(decoder.stats().length_errors, 1);
    }

    #[test]
    fn oversize_length_swallows_then_recovers() {
        // A false start announcing LEN 255 holds 259 bytes; once they are in and the checksum
        // fails, the bytes after the false start are scanned again and every frame is found.
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let mut bytes = vec![0xAA, 0xFF];
        for _ in 0..40 {
            bytes.extend(SEED);
        }
        let out = feed_all(|b| decoder.feed(b), &bytes.chunks(16).collect::<Vec<_>>());
        assert!(matches!(out[0], Err(DecodeError::BadChecksum { .. })), "{out:?}");
        assert_eq!(out.iter().filter(|item| **item == Ok(seed())).count(), 40);
        assert_eq!(decoder.buffered(), 0);
        accounted(&decoder);
    }

    #[test]
    fn unknown_type_is_counted() {
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let unknown = MotorPacket::Unknown { packet_type: 0x20, payload: vec![1, 2, 3] };
        let mut bytes = unknown.to_bytes();
        bytes.extend(SEED);
        assert_eq!(decoder.feed(&bytes), vec![Ok(unknown), Ok(seed())]);
        assert_eq!(decoder.stats().unknown_types, 1);
    }

    #[test]
    fn ignore_policy_accepts_firmware_checksums() {
        let mut decoder = Decoder::new(ChecksumPolicy::Ignore);
        let bytes = telemetry().to_bytes_with(motor::ChecksumKind::ConstFc);
        assert_eq!(decoder.feed(&bytes), vec![Ok(telemetry())]);
    }
}

mod sensor_stream {
    use super::*;
    use sensor::{
        DecodeError, Decoder, EncoderDirection, SensorPacket, SensorReading, SensorStatus, SensorValue,
        SwitchState,
    };

    fn keep_state() -> SensorPacket {
        SensorPacket::KeepState { status: 1, sequence: 0x0103 }
    }
    fn encoder() -> SensorPacket {
        SensorPacket::Reading(SensorReading {
            sensor_id: 3,
            status: SensorStatus::Operational,
            value: SensorValue::Encoder { count: 0x0103_0203, direction: EncoderDirection::Reverse },
        })
    }
    fn bumper() -> SensorPacket {
        SensorPacket::Reading(SensorReading {
            sensor_id: 1,
            status: SensorStatus::Operational,
            value: SensorValue::Switch(SwitchState::Pressed),
        })
    }
    fn accounted(decoder: &Decoder) {
        let s = decoder.stats();
        assert_eq!(s.bytes, s.bytes_in_frames + s.bytes_skipped + decoder.buffered() as u64, "{s:?}");
    }

    #[test]
    fn empty_input_yields_nothing() {
        let mut decoder = Decoder::new();
        assert!(decoder.feed(&[]).is_empty());
        assert_eq!(decoder.stats(), sensor::DecoderStats::default());
    }

    #[test]
    fn whole_frame() {
        let mut decoder = Decoder::new();
        assert_eq!(decoder.feed(&encoder().to_bytes()), vec![Ok(encoder())]);
        assert_eq!(decoder.buffered(), 0);
    }

    #[test]
    fn byte_by_byte() {
        let mut decoder = Decoder::new();
        let mut bytes = encoder().to_bytes();
        bytes.extend(keep_state().to_bytes());
        let chunks: Vec<&[u8]> = bytes.chunks(1).collect();
        assert_eq!(feed_all(|b| decoder.feed(b), &chunks), vec![Ok(encoder()), Ok(keep_state())]);
        accounted(&decoder);
    }

    #[test]
    fn two_frames_in_one_chunk() {
        let mut decoder = Decoder::new();
        let mut bytes = keep_state().to_bytes();
        bytes.extend(bumper().to_bytes());
        assert_eq!(decoder.feed(&bytes), vec![Ok(keep_state()), Ok(bumper())]);
    }

    #[test]
    fn split_at_every_point() {
        let mut bytes = keep_state().to_bytes();
        bytes.extend(encoder().to_bytes());
        bytes.extend(bumper().to_bytes());
        for cut in 0..=bytes.len() {
            let mut decoder = Decoder::new();
            let out = feed_all(|b| decoder.feed(b), &[&bytes[..cut], &bytes[cut..]]);
            assert_eq!(out, vec![Ok(keep_state()), Ok(encoder()), Ok(bumper())], "cut {cut}");
            accounted(&decoder);
        }
    }

    #[test]
    fn garbage_without_type_bytes_before() {
        let mut decoder = Decoder::new();
        let mut bytes = vec![0x00, 0xFF, 0x42, 0x07];
        bytes.extend(encoder().to_bytes());
        let out = decoder.feed(&bytes);
        assert_eq!(out, vec![Err(DecodeError::UnknownType { raw: 0 }), Ok(encoder())]);
        assert_eq!(decoder.stats().bytes_skipped, 4);
        assert_eq!(decoder.stats().errors, 1);
        accounted(&decoder);
    }

    #[test]
    fn garbage_that_forms_a_header_swallows_the_next_frame() {
        // The documented limit: a stray `01 03` reads as a keep-state and eats three bytes of the
        // real frame. The decoder then realigns on the next consistent header.
        let mut decoder = Decoder::new();
        let mut bytes = vec![0x01, 0x03];
        bytes.extend(bumper().to_bytes()); // 03 05 05 01 01 01 01
        bytes.extend(keep_state().to_bytes());
        let out = decoder.feed(&bytes);
        assert_eq!(out[0], Ok(SensorPacket::KeepState { status: 0x03, sequence: 0x0505 }));
        assert!(!out.contains(&Ok(bumper())), "{out:?}");
        assert_eq!(out.last(), Some(&Ok(keep_state())));
        accounted(&decoder);
    }

    #[test]
    fn type_bytes_inside_data() {
        // keep_state's sequence is `01 03` and the encoder's count `01 03 02 03`: header-like
        // bytes inside a frame are never re-examined once the frame is accepted.
        let mut decoder = Decoder::new();
        let mut bytes = Vec::new();
        for _ in 0..3 {
            bytes.extend(keep_state().to_bytes());
            bytes.extend(encoder().to_bytes());
        }
        let out = feed_all(|b| decoder.feed(b), &bytes.chunks(3).collect::<Vec<_>>());
        assert_eq!(out.len(), 6);
        assert!(out.iter().all(Result::is_ok));
        assert_eq!(decoder.stats().bytes_skipped, 0);
    }

    #[test]
    fn header_at_chunk_end() {
        let mut decoder = Decoder::new();
        let bytes = encoder().to_bytes();
        assert!(decoder.feed(&bytes[..1]).is_empty());
        assert_eq!(decoder.buffered(), 1);
        assert!(decoder.feed(&bytes[1..6]).is_empty());
        assert_eq!(decoder.feed(&bytes[6..]), vec![Ok(encoder())]);
    }

    #[test]
    fn corrupted_header_then_good_frame() {
        // A command whose LEN was hit (3 → 7) is rejected byte by byte; its tail bytes
        // `02 00 05` are tried as headers too (`02 00` fails: LEN must be 3), then the next
        // frame is found. (With a tail ending in `01`, `01 03` from the next frame would read
        // as a keep-state: see `garbage_that_forms_a_header_swallows_the_next_frame`.)
        let mut decoder = Decoder::new();
        let mut bytes = vec![0x02, 0x07, 0x02, 0x00, 0x05];
        bytes.extend(bumper().to_bytes());
        let out = decoder.feed(&bytes);
        assert_eq!(
            out,
            vec![
                Err(DecodeError::BadLength {
                    packet_type: sensor::PacketType::Command,
                    expected: 3,
                    actual: 7
                }),
                Ok(bumper()),
            ]
        );
        assert_eq!(decoder.stats().bytes_skipped, 5);
    }

    #[test]
    fn oversize_length_is_rejected_at_once() {
        // A sensor-data header claiming LEN 200 can never be valid; nothing waits for it.
        let mut decoder = Decoder::new();
        let mut bytes = vec![0x03, 200, 0x04];
        bytes.extend(bumper().to_bytes());
        let out = decoder.feed(&bytes);
        assert_eq!(out.len(), 2, "{out:?}");
        assert!(matches!(out[0], Err(DecodeError::BadLength { actual: 200, .. })));
        assert_eq!(out[1], Ok(bumper()));
        accounted(&decoder);
    }
}
