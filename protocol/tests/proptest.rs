//! Property tests: emit → parse round trips with generators that build valid frames, decoders
//! that never panic and do not depend on how the stream is chunked, and exactly the recovery each
//! framing allows (see each module's doc).
//!
//! Failures persist to `protocol/proptest-regressions/proptest.txt` (commit that file).

use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use protocol::{link, motor, sensor};

fn config() -> ProptestConfig {
    ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/proptest.txt",
        ))),
        cases: 1024,
        ..ProptestConfig::default()
    }
}

/// Decoded output compared by its `Debug` text: arbitrary bytes decode to NaN floats too, and
/// NaN != NaN would fail `==` on two identical decodes. `Debug` prints every other f32 exactly
/// (shortest round-trip form), so this is still a value-for-value comparison.
fn debug_text<T: core::fmt::Debug>(value: &T) -> String {
    format!("{value:?}")
}

/// Any f32 except NaN (NaN != NaN would make equality checks meaningless), every bit pattern
/// otherwise: subnormals, infinities, −0.
fn f32_not_nan() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits).prop_filter("NaN", |f| !f.is_nan())
}

fn floats<const N: usize>() -> impl Strategy<Value = [f32; N]> {
    prop::collection::vec(f32_not_nan(), N).prop_map(|v| {
        let mut out = [0.0; N];
        out.copy_from_slice(&v);
        out
    })
}

/// Splits `bytes` at the given cut points (any order, duplicates allowed).
fn chunks<'a>(bytes: &'a [u8], cuts: &[prop::sample::Index]) -> Vec<&'a [u8]> {
    let mut points: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
    points.push(0);
    points.push(bytes.len());
    points.sort_unstable();
    points.windows(2).map(|w| &bytes[w[0]..w[1]]).collect()
}

fn cuts() -> impl Strategy<Value = Vec<prop::sample::Index>> {
    prop::collection::vec(any::<prop::sample::Index>(), 0..12)
}

// ───────────────────────────────────────── link ─────────────────────────────────────────

mod link_props {
    use super::*;
    use link::{Command, Decoder, Direction, Frame, GuiMessage, MsgOrder, MsgType};

    pub fn order() -> impl Strategy<Value = MsgOrder> {
        prop_oneof![Just(MsgOrder::BigEndian), Just(MsgOrder::LittleEndian)]
    }

    pub fn message() -> impl Strategy<Value = GuiMessage> {
        let command = any::<u8>().prop_map(Command::from);
        let direction = any::<u8>().prop_map(Direction::from);
        // Unknown ids must not be a valid id in either order, or they re-parse as that message.
        let unknown_msg = any::<u16>().prop_filter("valid id", |m| {
            matches!(MsgType::from_wire(m.to_be_bytes()).0, MsgType::Unknown(_))
        });
        prop_oneof![
            (any::<u8>(), command.clone())
                .prop_map(|(n_total, command)| { GuiMessage::SendMovesTrajectory { n_total, command } }),
            command.prop_map(|command| GuiMessage::SendMoveCartography { command }),
            Just(GuiMessage::MoveDone),
            (any::<u8>(), any::<u8>()).prop_map(|(x, y)| GuiMessage::SetObstaclePosition { x, y }),
            (any::<u8>(), any::<u8>()).prop_map(|(x, y)| GuiMessage::SetRobotPosition { x, y }),
            Just(GuiMessage::StopRobot),
            (any::<u8>(), any::<u8>(), direction)
                .prop_map(|(x, y, direction)| GuiMessage::SendRobotPosition { x, y, direction }),
            Just(GuiMessage::RobotPositionReceived),
            (unknown_msg, prop::collection::vec(any::<u8>(), 0..64))
                .prop_map(|(msg, data)| GuiMessage::Unknown { msg, data }),
        ]
    }

    /// A well-formed frame of any id and any data (Size within `max`), not necessarily valid.
    pub fn any_whole_frame(max: usize) -> impl Strategy<Value = Vec<u8>> {
        (any::<[u8; 2]>(), prop::collection::vec(any::<u8>(), 0..=max - 2)).prop_map(|(msg, data)| {
            let mut bytes = ((data.len() + 2) as u16).to_be_bytes().to_vec();
            bytes.extend(msg);
            bytes.extend(data);
            bytes
        })
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn emit_parse_round_trip(message in message(), order in order()) {
            let bytes = message.to_bytes(order);
            prop_assert_eq!(bytes.len(), message.buffer_len());
            let frame = Frame::new_checked(&bytes[..]).unwrap();
            prop_assert_eq!(GuiMessage::parse(&frame), Ok(message.clone()));
            if !matches!(message, GuiMessage::Unknown { .. }) {
                prop_assert_eq!(frame.msg_order(), Some(order));
            }
        }

        #[test]
        fn decoder_returns_every_message_whatever_the_chunking(
            messages in prop::collection::vec((message(), order()), 0..12),
            cuts in cuts(),
        ) {
            let stream: Vec<u8> = messages.iter().flat_map(|(m, o)| m.to_bytes(*o)).collect();
            let mut decoder = Decoder::default();
            let out: Vec<_> = chunks(&stream, &cuts).into_iter().flat_map(|c| decoder.feed(c)).collect();
            let expected: Vec<_> = messages.iter().map(|(m, _)| Ok(m.clone())).collect();
            prop_assert_eq!(out, expected);
            prop_assert_eq!(decoder.buffered(), 0);
            prop_assert_eq!(decoder.last_order(), messages.iter().rev().find(|(m, _)| !matches!(m, GuiMessage::Unknown { .. })).map(|(_, o)| *o));
        }

        #[test]
        fn arbitrary_bytes_never_panic_and_chunking_does_not_matter(
            bytes in prop::collection::vec(any::<u8>(), 0..600),
            cuts in cuts(),
            max in 2usize..2000,
        ) {
            let _ = GuiMessage::parse(&Frame::new_unchecked(&bytes[..]));
            let mut whole = Decoder::new(max);
            let expected = whole.feed(&bytes);
            let mut chunked = Decoder::new(max);
            let out: Vec<_> = chunks(&bytes, &cuts).into_iter().flat_map(|c| chunked.feed(c)).collect();
            prop_assert_eq!(debug_text(&out), debug_text(&expected));
            prop_assert!(chunked.buffered() <= chunked.max_frame() + 1);
            // After a fatal error nothing else comes out.
            if let Some(at) = out.iter().position(|item| matches!(item, Err(e) if e.is_fatal())) {
                prop_assert_eq!(at, out.len() - 1);
                prop_assert!(chunked.is_failed());
            }
        }

        /// No resync exists: recovery happens exactly when the bad bytes were whole frames.
        #[test]
        fn valid_frame_after_whole_frames_of_garbage_is_decoded(
            garbage in prop::collection::vec(any_whole_frame(64), 0..6),
            message in message(),
            order in order(),
            cuts in cuts(),
        ) {
            let mut stream: Vec<u8> = garbage.concat();
            stream.extend(message.to_bytes(order));
            let mut decoder = Decoder::new(64 + 4);
            let out: Vec<_> = chunks(&stream, &cuts).into_iter().flat_map(|c| decoder.feed(c)).collect();
            prop_assert_eq!(out.len(), garbage.len() + 1);
            prop_assert_eq!(out.last(), Some(&Ok(message)));
            prop_assert!(out.iter().all(|item| !matches!(item, Err(e) if e.is_fatal())));
        }

        /// For arbitrary garbage the exact condition: the decoder holds no pending bytes and has
        /// not failed. Then the next frame is decoded; after a failure, `reset` restores it.
        #[test]
        fn valid_frame_after_arbitrary_garbage_needs_a_clean_boundary(
            garbage in prop::collection::vec(any::<u8>(), 0..200),
            message in message(),
            order in order(),
        ) {
            let mut decoder = Decoder::default();
            decoder.feed(&garbage);
            if decoder.is_failed() {
                decoder.reset();
            }
            let clean = decoder.buffered() == 0;
            let out = decoder.feed(&message.to_bytes(order));
            if clean {
                prop_assert_eq!(out, vec![Ok(message)]);
            }
        }
    }
}

// ───────────────────────────────────────── motor ────────────────────────────────────────

mod motor_props {
    use super::*;
    use motor::{
        ChecksumKind, ChecksumPolicy, Decoder, Frame, MotorCommand, MotorPacket, PacketType, Telemetry,
        TelemetryForm,
    };

    pub fn packet() -> impl Strategy<Value = MotorPacket> {
        let v1 = any::<[u8; 3]>()
            .prop_map(|[dir_x, dir_y, gear]| MotorPacket::Drive(MotorCommand::V1 { dir_x, dir_y, gear }));
        let v2 = (any::<[i8; 3]>(), any::<u8>(), any::<[u8; 2]>()).prop_map(
            |([vx, vy, omega], speed_ratio, reserved)| {
                MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, speed_ratio, reserved })
            },
        );
        let motor32 = (floats::<4>(), floats::<4>())
            .prop_map(|(rpm, power)| MotorPacket::Telemetry(Telemetry::motor(rpm, power)));
        let motor36 = (any::<u8>(), floats::<4>(), floats::<4>()).prop_map(|(motor_id, rpm, power)| {
            MotorPacket::Telemetry(Telemetry {
                form: TelemetryForm::Motor36,
                motor_id,
                ..Telemetry::motor(rpm, power)
            })
        });
        let complete = (floats::<4>(), floats::<4>(), floats::<6>(), floats::<12>()).prop_map(
            |(rpm, power, odometry, imu)| {
                MotorPacket::Telemetry(Telemetry {
                    form: TelemetryForm::Complete104,
                    odometry,
                    imu,
                    ..Telemetry::motor(rpm, power)
                })
            },
        );
        let unknown = (
            any::<u8>().prop_filter("known type", |t| matches!(PacketType::from(*t), PacketType::Unknown(_))),
            prop::collection::vec(any::<u8>(), 0..=255),
        )
            .prop_map(|(packet_type, payload)| MotorPacket::Unknown { packet_type, payload });
        prop_oneof![v1, v2, motor32, motor36, complete, unknown]
    }

    fn kind_and_policy() -> impl Strategy<Value = (ChecksumKind, ChecksumPolicy)> {
        prop_oneof![
            Just((ChecksumKind::Sum, ChecksumPolicy::Sum)),
            Just((ChecksumKind::XorPayload, ChecksumPolicy::XorPayload)),
            Just((ChecksumKind::ConstFc, ChecksumPolicy::ConstFc)),
            Just((ChecksumKind::XorPayload, ChecksumPolicy::Ignore)),
        ]
    }

    /// Valid frames, random bytes and frames with one flipped bit, mixed.
    fn mixed_stream() -> impl Strategy<Value = Vec<u8>> {
        let piece = prop_oneof![
            packet().prop_map(|p| p.to_bytes()),
            prop::collection::vec(any::<u8>(), 0..40),
            (packet(), any::<prop::sample::Index>(), 0u8..8).prop_map(|(p, at, bit)| {
                let mut bytes = p.to_bytes();
                let i = at.index(bytes.len());
                bytes[i] ^= 1 << bit;
                bytes
            }),
        ];
        prop::collection::vec(piece, 0..10).prop_map(|pieces| pieces.concat())
    }

    fn accounted(decoder: &Decoder) -> bool {
        let s = decoder.stats();
        s.bytes == s.bytes_in_frames + s.bytes_skipped + decoder.buffered() as u64
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn emit_parse_round_trip(packet in packet(), (kind, policy) in kind_and_policy()) {
            let bytes = packet.to_bytes_with(kind);
            prop_assert_eq!(bytes.len(), packet.buffer_len());
            let frame = Frame::new_checked(&bytes[..]).unwrap();
            prop_assert_eq!(MotorPacket::parse(&frame, policy), Ok(packet.clone()));
        }

        #[test]
        fn decoder_returns_every_packet_whatever_the_chunking(
            packets in prop::collection::vec(packet(), 0..10),
            cuts in cuts(),
        ) {
            let stream: Vec<u8> = packets.iter().flat_map(MotorPacket::to_bytes).collect();
            let mut decoder = Decoder::new(ChecksumPolicy::Sum);
            let out: Vec<_> = chunks(&stream, &cuts).into_iter().flat_map(|c| decoder.feed(c)).collect();
            let expected: Vec<_> = packets.into_iter().map(Ok).collect();
            prop_assert_eq!(out, expected);
            prop_assert_eq!(decoder.stats().bytes_skipped, 0);
        }

        #[test]
        fn arbitrary_bytes_never_panic_and_chunking_does_not_matter(
            bytes in prop_oneof![prop::collection::vec(any::<u8>(), 0..600), mixed_stream()],
            cuts in cuts(),
            policy in prop_oneof![Just(ChecksumPolicy::Sum), Just(ChecksumPolicy::Ignore)],
        ) {
            let _ = MotorPacket::parse(&Frame::new_unchecked(&bytes[..]), policy);
            let mut whole = Decoder::new(policy);
            let expected = whole.feed(&bytes);
            let mut chunked = Decoder::new(policy);
            let out: Vec<_> = chunks(&bytes, &cuts).into_iter().flat_map(|c| chunked.feed(c)).collect();
            prop_assert_eq!(debug_text(&out), debug_text(&expected));
            prop_assert!(chunked.buffered() <= motor::MAX_FRAME_LEN);
            prop_assert!(accounted(&chunked));
        }

        /// Garbage without a 0xAA byte is skipped: the next frame is always decoded.
        #[test]
        fn valid_frame_after_garbage_without_sync_is_always_decoded(
            garbage in prop::collection::vec(any::<u8>().prop_filter("sync", |b| *b != motor::SYNC), 0..300),
            packet in packet(),
        ) {
            let mut decoder = Decoder::new(ChecksumPolicy::Sum);
            let mut stream = garbage.clone();
            stream.extend(packet.to_bytes());
            prop_assert_eq!(decoder.feed(&stream), vec![Ok(packet)]);
            prop_assert_eq!(decoder.stats().bytes_skipped, garbage.len() as u64);
        }

        /// Arbitrary garbage (0xAA very likely): once enough bytes follow to complete any false
        /// frame (258 filler bytes), the valid frame is decoded, unless a false frame starting in
        /// the garbage passed the checksum and swallowed it, which shows as an extra `Ok`.
        #[test]
        fn valid_frame_after_arbitrary_garbage_is_decoded_unless_a_false_frame_passed(
            garbage in prop::collection::vec(prop_oneof![Just(motor::SYNC), any::<u8>()], 0..300),
            packet in packet(),
            cuts in cuts(),
        ) {
            let mut stream = garbage;
            stream.extend(packet.to_bytes());
            stream.extend([0u8; motor::MAX_FRAME_LEN - 1]);
            let mut decoder = Decoder::new(ChecksumPolicy::Sum);
            let out: Vec<_> = chunks(&stream, &cuts).into_iter().flat_map(|c| decoder.feed(c)).collect();
            let found = out.contains(&Ok(packet.clone()));
            let false_frame = out.iter().any(|item| matches!(item, Ok(p) if *p != packet));
            prop_assert!(found || false_frame, "{:?}", out);
            prop_assert_eq!(decoder.buffered(), 0);
        }

        /// The exact condition for immediate recovery: no pending candidate when the frame starts.
        #[test]
        fn valid_frame_after_a_clean_boundary_is_decoded_at_once(
            garbage in prop::collection::vec(prop_oneof![Just(motor::SYNC), any::<u8>()], 0..300),
            packet in packet(),
        ) {
            let mut decoder = Decoder::new(ChecksumPolicy::Sum);
            decoder.feed(&garbage);
            if decoder.buffered() == 0 {
                prop_assert_eq!(decoder.feed(&packet.to_bytes()), vec![Ok(packet)]);
            }
        }
    }
}

// ───────────────────────────────────────── sensor ───────────────────────────────────────

mod sensor_props {
    use super::*;
    use sensor::{
        CommandId, Decoder, EncoderDirection, Frame, NavX, SensorPacket, SensorReading, SensorStatus,
        SensorValue, SwitchState,
    };

    pub fn packet() -> impl Strategy<Value = SensorPacket> {
        let navx = (floats::<4>(), floats::<3>(), floats::<2>()).prop_map(
            |([altitude, pressure, heading_deg, temperature], accel, mag)| {
                SensorValue::NavX(NavX { altitude, pressure, heading_deg, temperature, accel, mag })
            },
        );
        let value = prop_oneof![
            navx,
            (any::<i32>(), any::<u8>())
                .prop_map(|(count, d)| SensorValue::Encoder { count, direction: EncoderDirection::from(d) }),
            f32_not_nan().prop_map(|angle| SensorValue::Potentiometer { angle }),
            f32_not_nan().prop_map(|cm| SensorValue::Distance { cm }),
            any::<u8>().prop_map(|s| SensorValue::Switch(SwitchState::from(s))),
        ];
        prop_oneof![
            (any::<u8>(), any::<u16>())
                .prop_map(|(status, sequence)| SensorPacket::KeepState { status, sequence }),
            (any::<u8>(), any::<i16>())
                .prop_map(|(id, parameter)| SensorPacket::Command { id: CommandId::from(id), parameter }),
            (any::<u8>(), any::<u8>(), value).prop_map(|(sensor_id, status, value)| {
                SensorPacket::Reading(SensorReading { sensor_id, status: SensorStatus::from(status), value })
            }),
        ]
    }

    fn mixed_stream() -> impl Strategy<Value = Vec<u8>> {
        let piece = prop_oneof![
            packet().prop_map(|p| p.to_bytes()),
            prop::collection::vec(any::<u8>(), 0..20),
            prop::collection::vec(1u8..=5, 0..20),
        ];
        prop::collection::vec(piece, 0..10).prop_map(|pieces| pieces.concat())
    }

    fn accounted(decoder: &Decoder) -> bool {
        let s = decoder.stats();
        s.bytes == s.bytes_in_frames + s.bytes_skipped + decoder.buffered() as u64
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn emit_parse_round_trip(packet in packet()) {
            let bytes = packet.to_bytes();
            prop_assert_eq!(bytes.len(), packet.buffer_len());
            let frame = Frame::new_checked(&bytes[..]).unwrap();
            prop_assert_eq!(SensorPacket::parse(&frame), Ok(packet));
        }

        #[test]
        fn decoder_returns_every_packet_whatever_the_chunking(
            packets in prop::collection::vec(packet(), 0..12),
            cuts in cuts(),
        ) {
            let stream: Vec<u8> = packets.iter().flat_map(SensorPacket::to_bytes).collect();
            let mut decoder = Decoder::new();
            let out: Vec<_> = chunks(&stream, &cuts).into_iter().flat_map(|c| decoder.feed(c)).collect();
            let expected: Vec<_> = packets.into_iter().map(Ok).collect();
            prop_assert_eq!(out, expected);
            prop_assert_eq!(decoder.stats().bytes_skipped, 0);
        }

        #[test]
        fn arbitrary_bytes_never_panic_and_chunking_does_not_matter(
            bytes in prop_oneof![prop::collection::vec(any::<u8>(), 0..600), mixed_stream()],
            cuts in cuts(),
        ) {
            let _ = SensorPacket::parse(&Frame::new_unchecked(&bytes[..]));
            let mut whole = Decoder::new();
            let expected = whole.feed(&bytes);
            let mut chunked = Decoder::new();
            let out: Vec<_> = chunks(&bytes, &cuts).into_iter().flat_map(|c| chunked.feed(c)).collect();
            prop_assert_eq!(debug_text(&out), debug_text(&expected));
            prop_assert!(chunked.buffered() < sensor::MAX_FRAME_LEN);
            prop_assert!(accounted(&chunked));
            // One error per loss of sync: never two errors in a row.
            prop_assert!(out.windows(2).all(|w| w[0].is_ok() || w[1].is_ok()));
        }

        /// Garbage with no byte that can begin a frame (1, 2, 3) is dropped; the frame follows.
        #[test]
        fn valid_frame_after_garbage_without_type_bytes_is_always_decoded(
            garbage in prop::collection::vec(any::<u8>().prop_filter("type byte", |b| !(1..=3).contains(b)), 0..300),
            packet in packet(),
        ) {
            let mut decoder = Decoder::new();
            let mut stream = garbage.clone();
            stream.extend(packet.to_bytes());
            let out = decoder.feed(&stream);
            prop_assert_eq!(out.last(), Some(&Ok(packet)));
            prop_assert_eq!(out.len(), if garbage.is_empty() { 1 } else { 2 });
            prop_assert_eq!(decoder.stats().bytes_skipped, garbage.len() as u64);
        }

        /// For arbitrary garbage the exact condition: no pending candidate when the frame starts.
        #[test]
        fn valid_frame_after_a_clean_boundary_is_decoded_at_once(
            garbage in prop::collection::vec(prop_oneof![1u8..=5, any::<u8>()], 0..300),
            packet in packet(),
        ) {
            let mut decoder = Decoder::new();
            decoder.feed(&garbage);
            if decoder.buffered() == 0 {
                let out = decoder.feed(&packet.to_bytes());
                prop_assert_eq!(out, vec![Ok(packet)]);
            }
        }
    }
}
