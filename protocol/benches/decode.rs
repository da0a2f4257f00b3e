//! Decode throughput of the three streaming decoders on a stream of valid frames with 1 % of its
//! bytes corrupted (seeded, so every run sees the same stream).
//!
//! Each stream is measured twice: once with byte throughput (MB/s) and once with element
//! throughput, an element being one frame the decoder returned `Ok` (decoded frames/s). `link` is
//! also measured on the clean stream, the realistic case for TCP. Chunking follows the transport: 1460-byte reads (one TCP segment) for
//! `link`, 64-byte reads for the UART protocols. A fatal `link` error resets the decoder, as a
//! server does when the next client connects.
//!
//! `cargo bench -p protocol`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use protocol::{link, motor, sensor};
use std::hint::black_box;

/// Frames per stream.
const FRAMES: usize = 10_000;
/// One corrupted byte per this many.
const CORRUPT_ONE_IN: u64 = 100;

/// SplitMix64: a tiny seeded generator (the crate has no RNG dependency).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn byte(&mut self) -> u8 {
        self.next() as u8
    }
}

/// Replaces about 1 % of the bytes with random ones.
fn corrupt(stream: &mut [u8], rng: &mut SplitMix) {
    for byte in stream.iter_mut() {
        if rng.next().is_multiple_of(CORRUPT_ONE_IN) {
            *byte = rng.byte();
        }
    }
}

fn link_stream(rng: &mut SplitMix) -> Vec<u8> {
    use link::{Command, Direction, GuiMessage, MsgOrder};
    let mut stream = Vec::new();
    for _ in 0..FRAMES {
        let message = match rng.next() % 5 {
            0 => GuiMessage::SendMovesTrajectory {
                n_total: rng.byte(),
                command: Command::from(rng.byte() % 4),
            },
            1 => GuiMessage::SendMoveCartography { command: Command::from(rng.byte() % 4) },
            2 => GuiMessage::SetRobotPosition { x: rng.byte(), y: rng.byte() },
            3 => GuiMessage::SendRobotPosition {
                x: rng.byte(),
                y: rng.byte(),
                direction: Direction::from(rng.byte() % 4),
            },
            _ => GuiMessage::MoveDone,
        };
        let order = if rng.next().is_multiple_of(2) { MsgOrder::BigEndian } else { MsgOrder::LittleEndian };
        stream.extend(message.to_bytes(order));
    }
    stream
}

fn motor_stream(rng: &mut SplitMix) -> Vec<u8> {
    use motor::{MotorCommand, MotorPacket, Telemetry};
    let mut stream = Vec::new();
    for _ in 0..FRAMES {
        let packet = match rng.next() % 3 {
            0 => MotorPacket::Drive(MotorCommand::V1 {
                dir_x: rng.byte(),
                dir_y: rng.byte(),
                gear: rng.byte() % 9,
            }),
            1 => MotorPacket::Drive(MotorCommand::V2 {
                vx: rng.byte() as i8,
                vy: rng.byte() as i8,
                omega: rng.byte() as i8,
                speed_ratio: 0,
                reserved: [0; 2],
            }),
            _ => {
                let f = |rng: &mut SplitMix| (rng.next() % 20_000) as f32 / 100.0 - 100.0;
                MotorPacket::Telemetry(Telemetry::motor(
                    [f(rng), f(rng), f(rng), f(rng)],
                    [f(rng), f(rng), f(rng), f(rng)],
                ))
            }
        };
        stream.extend(packet.to_bytes());
    }
    stream
}

fn sensor_stream(rng: &mut SplitMix) -> Vec<u8> {
    use sensor::{EncoderDirection, NavX, SensorPacket, SensorReading, SensorStatus, SensorValue};
    let mut stream = Vec::new();
    for i in 0..FRAMES {
        let value = match rng.next() % 4 {
            0 => SensorValue::Distance { cm: (rng.next() % 40_000) as f32 / 100.0 },
            1 => SensorValue::Encoder {
                count: rng.next() as i32,
                direction: EncoderDirection::from(1 + rng.byte() % 2),
            },
            2 => SensorValue::NavX(NavX { heading_deg: (rng.next() % 360) as f32, ..NavX::default() }),
            _ => SensorValue::Switch(sensor::SwitchState::from(1 + rng.byte() % 2)),
        };
        let packet = if i % 10 == 0 {
            SensorPacket::KeepState { status: 1, sequence: i as u16 }
        } else {
            SensorPacket::Reading(SensorReading { sensor_id: 1, status: SensorStatus::Operational, value })
        };
        stream.extend(packet.to_bytes());
    }
    stream
}

fn decode_link(stream: &[u8]) -> usize {
    let mut decoder = link::Decoder::default();
    let mut ok = 0;
    for chunk in stream.chunks(1460) {
        ok += decoder.feed(chunk).iter().filter(|item| item.is_ok()).count();
        if decoder.is_failed() {
            decoder.reset();
        }
    }
    ok
}

fn decode_motor(stream: &[u8]) -> usize {
    let mut decoder = motor::Decoder::new(motor::ChecksumPolicy::Sum);
    stream.chunks(64).map(|chunk| decoder.feed(chunk).iter().filter(|item| item.is_ok()).count()).sum()
}

fn decode_sensor(stream: &[u8]) -> usize {
    let mut decoder = sensor::Decoder::new();
    stream.chunks(64).map(|chunk| decoder.feed(chunk).iter().filter(|item| item.is_ok()).count()).sum()
}

fn bench(c: &mut Criterion) {
    let mut rng = SplitMix(0x5EED_2024);
    type Decode = fn(&[u8]) -> usize;
    let link = link_stream(&mut rng);
    let cases: [(&str, Vec<u8>, bool, Decode); 4] = [
        ("link_clean", link.clone(), false, decode_link),
        ("link", link, true, decode_link),
        ("motor", motor_stream(&mut rng), true, decode_motor),
        ("sensor", sensor_stream(&mut rng), true, decode_sensor),
    ];
    for (name, mut stream, corrupted, decode) in cases {
        if corrupted {
            corrupt(&mut stream, &mut rng);
        }
        let decoded = decode(&stream);
        eprintln!("{name}: {} bytes, {FRAMES} frames written, {decoded} decoded Ok", stream.len());

        let mut group = c.benchmark_group(format!("decode_{name}"));
        group.throughput(Throughput::Bytes(stream.len() as u64));
        group.bench_function("bytes", |b| b.iter(|| decode(black_box(&stream))));
        // Elements = frames decoded `Ok` per pass, so the figure is decoded frames per second.
        group.throughput(Throughput::Elements(decoded as u64));
        group.bench_function("frames", |b| b.iter(|| decode(black_box(&stream))));
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(4));
    targets = bench
}
criterion_main!(benches);
