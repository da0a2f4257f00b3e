//! `explobot decode` and `explobot encode`: the three wire formats by hand, for people reading a
//! serial capture or crafting a test frame.
//!
//! ```
//! use sim::wiretool::{Protocol, decode_hex, encode};
//! let out = decode_hex(Protocol::Motor, "AA 03 01 80 80 06 0A", Default::default()).unwrap();
//! assert!(out.contains("dir_x: 128"));
//! let bytes = encode(Protocol::Link, &["trajectory", "6", "forward"], false).unwrap();
//! assert_eq!(bytes, vec![0x00, 0x04, 0x01, 0x00, 0x06, 0x00]);
//! ```

use std::fmt::Write as _;

use protocol::link::{self, Command, Direction, GuiMessage, MsgOrder};
use protocol::motor::{self, ChecksumPolicy, MotorCommand, MotorPacket, Telemetry, TelemetryForm};
use protocol::sensor::{
    self, CommandId, EncoderDirection, NavX, SensorPacket, SensorReading, SensorStatus, SensorValue,
    SwitchState,
};

/// Which wire format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Protocol {
    /// Cute ⇄ Carto, TCP.
    Link,
    /// Carto ⇄ motor board, UART.
    Motor,
    /// Carto ⇄ sensor board, UART.
    Sensor,
}

/// Parses hex text: pairs of digits, optionally `0x`-prefixed, separated by anything.
pub fn parse_hex(text: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    for token in text.split(|c: char| c.is_whitespace() || c == ',' || c == ':' || c == '-') {
        let t = token.trim_start_matches("0x").trim_start_matches("0X");
        if t.is_empty() {
            continue;
        }
        if t.len() % 2 != 0 {
            return Err(format!("'{token}' has an odd number of hex digits"));
        }
        for i in (0..t.len()).step_by(2) {
            let pair = t.get(i..i + 2).ok_or_else(|| format!("'{token}' is not hex"))?;
            out.push(u8::from_str_radix(pair, 16).map_err(|_| format!("'{pair}' in '{token}' is not hex"))?);
        }
    }
    Ok(out)
}

/// Decodes hex text and describes every frame, error and skipped byte, one per line.
pub fn decode_hex(protocol: Protocol, hex: &str, checksum: ChecksumPolicy) -> Result<String, String> {
    let bytes = parse_hex(hex)?;
    Ok(decode_bytes(protocol, &bytes, checksum))
}

/// Describes `bytes` frame by frame. Bytes are fed one at a time, so each line can say where
/// its frame ended.
pub fn decode_bytes(protocol: Protocol, bytes: &[u8], checksum: ChecksumPolicy) -> String {
    let mut out = String::new();
    match protocol {
        Protocol::Link => {
            let (mut frames, mut errors) = (0u64, 0u64);
            let mut d = link::Decoder::default();
            for (i, b) in bytes.iter().enumerate() {
                for item in d.feed(std::slice::from_ref(b)) {
                    match item {
                        Ok(m) => {
                            frames += 1;
                            let order = d.last_order().unwrap_or_default();
                            let len = m.to_bytes(order).len();
                            let _ = writeln!(
                                out,
                                "[{:>4}..{:<4}] ok    {m:?} (Msg {order:?})",
                                i + 1 - len,
                                i + 1
                            );
                        }
                        Err(e) => {
                            errors += 1;
                            let fatal = if e.is_fatal() {
                                " — fatal: a receiver closes the connection here"
                            } else {
                                ""
                            };
                            let _ = writeln!(out, "[{:>4}]       error {e}{fatal}", i + 1);
                        }
                    }
                }
                if d.is_failed() {
                    let _ = writeln!(
                        out,
                        "[{:>4}]       {} more bytes ignored after the fatal error",
                        i + 1,
                        bytes.len() - i - 1
                    );
                    break;
                }
            }
            tail(&mut out, d.buffered(), frames, errors, None);
        }
        Protocol::Motor => describe_resyncing(&mut out, bytes, &mut motor::Decoder::new(checksum)),
        Protocol::Sensor => describe_resyncing(&mut out, bytes, &mut sensor::Decoder::new()),
    }
    out
}

/// The two decoders that resynchronise by skipping bytes (motor, sensor).
trait Resyncing {
    type Packet: std::fmt::Debug;
    type Error: std::fmt::Display;
    const RESYNC: &'static str;
    fn feed(&mut self, bytes: &[u8]) -> Vec<Result<Self::Packet, Self::Error>>;
    fn frame_len(packet: &Self::Packet) -> usize;
    /// (bytes skipped, bytes waiting in the buffer)
    fn skipped_and_pending(&self) -> (u64, usize);
}

impl Resyncing for motor::Decoder {
    type Packet = MotorPacket;
    type Error = motor::DecodeError;
    const RESYNC: &'static str = "resync on the next 0xAA";
    fn feed(&mut self, bytes: &[u8]) -> Vec<Result<MotorPacket, motor::DecodeError>> {
        motor::Decoder::feed(self, bytes)
    }
    fn frame_len(packet: &MotorPacket) -> usize {
        packet.to_bytes().len()
    }
    fn skipped_and_pending(&self) -> (u64, usize) {
        let s = self.stats();
        (s.bytes_skipped, (s.bytes - s.bytes_in_frames - s.bytes_skipped) as usize)
    }
}

impl Resyncing for sensor::Decoder {
    type Packet = SensorPacket;
    type Error = sensor::DecodeError;
    const RESYNC: &'static str = "dropping one byte and retrying";
    fn feed(&mut self, bytes: &[u8]) -> Vec<Result<SensorPacket, sensor::DecodeError>> {
        sensor::Decoder::feed(self, bytes)
    }
    fn frame_len(packet: &SensorPacket) -> usize {
        packet.to_bytes().len()
    }
    fn skipped_and_pending(&self) -> (u64, usize) {
        let s = self.stats();
        (s.bytes_skipped, (s.bytes - s.bytes_in_frames - s.bytes_skipped) as usize)
    }
}

/// Feeds `bytes` one at a time and writes a line per frame, error and resync.
fn describe_resyncing<D: Resyncing>(out: &mut String, bytes: &[u8], d: &mut D) {
    let (mut frames, mut errors, mut skipped_before) = (0u64, 0u64, 0u64);
    for (i, b) in bytes.iter().enumerate() {
        for item in d.feed(std::slice::from_ref(b)) {
            match item {
                Ok(p) => {
                    frames += 1;
                    let len = D::frame_len(&p);
                    let _ = writeln!(out, "[{:>4}..{:<4}] ok    {p:?}", i + 1 - len, i + 1);
                }
                Err(e) => {
                    errors += 1;
                    let _ = writeln!(out, "[{:>4}]       error {e} ({})", i + 1, D::RESYNC);
                }
            }
            note_skipped(out, &mut skipped_before, d.skipped_and_pending().0, i + 1);
        }
    }
    let (skipped, pending) = d.skipped_and_pending();
    note_skipped(out, &mut skipped_before, skipped, bytes.len());
    tail(out, pending, frames, errors, Some(skipped));
}

fn note_skipped(out: &mut String, before: &mut u64, now: u64, at: usize) {
    if now > *before {
        let _ = writeln!(out, "[{at:>4}]       resync: {} byte(s) skipped", now - *before);
        *before = now;
    }
}

fn tail(out: &mut String, pending: usize, frames: u64, errors: u64, skipped: Option<u64>) {
    if pending > 0 {
        let _ = writeln!(out, "               {pending} trailing byte(s): an incomplete frame");
    }
    let skipped = skipped.map_or(String::new(), |s| format!(", {s} bytes skipped"));
    let _ = writeln!(out, "{frames} frame(s), {errors} error(s){skipped}");
}

/// Builds one frame from words. Formats (numbers decimal, or hex with `0x`):
///
/// * link: `trajectory N CMD`, `cartography CMD`, `move-done`, `obstacle X Y`, `robot X Y`,
///   `stop`, `position X Y DIR`, `position-received` — CMD is forward/right/left/stop or a number,
///   DIR south/north/west/east or a number; `little_endian` writes `Msg` as the 2024 Cute did;
/// * motor: `drive-v1 DIR_X DIR_Y GEAR`, `drive-v2 VX VY OMEGA [RATIO]`,
///   `telemetry RPM×4 POWER×4` (32-byte form), `telemetry36 …`;
/// * sensor: `keep-state STATUS SEQ`, `command ID PARAM`, `distance ID CM`,
///   `encoder ID COUNT forward|reverse`, `switch ID pressed|released`, `pot ID ANGLE`,
///   `navx ID ALT PRESSURE HEADING TEMP AX AY AZ MX MY`.
pub fn encode(protocol: Protocol, words: &[&str], little_endian: bool) -> Result<Vec<u8>, String> {
    let (&kind, args) = words.split_first().ok_or("nothing to encode")?;
    let want = |n: usize| {
        if args.len() == n {
            Ok(())
        } else {
            Err(format!("'{kind}' takes {n} argument(s), got {}", args.len()))
        }
    };
    match protocol {
        Protocol::Link => {
            let msg = match kind {
                "trajectory" => {
                    want(2)?;
                    GuiMessage::SendMovesTrajectory { n_total: num(args[0])?, command: command(args[1])? }
                }
                "cartography" => {
                    want(1)?;
                    GuiMessage::SendMoveCartography { command: command(args[0])? }
                }
                "move-done" => GuiMessage::MoveDone,
                "obstacle" => {
                    want(2)?;
                    GuiMessage::SetObstaclePosition { x: num(args[0])?, y: num(args[1])? }
                }
                "robot" => {
                    want(2)?;
                    GuiMessage::SetRobotPosition { x: num(args[0])?, y: num(args[1])? }
                }
                "stop" => GuiMessage::StopRobot,
                "position" => {
                    want(3)?;
                    GuiMessage::SendRobotPosition {
                        x: num(args[0])?,
                        y: num(args[1])?,
                        direction: direction(args[2])?,
                    }
                }
                "position-received" => GuiMessage::RobotPositionReceived,
                other => return Err(format!("unknown link message '{other}'")),
            };
            let order = if little_endian { MsgOrder::LittleEndian } else { MsgOrder::BigEndian };
            Ok(msg.to_bytes(order))
        }
        Protocol::Motor => {
            let packet = match kind {
                "drive-v1" => {
                    want(3)?;
                    MotorPacket::Drive(MotorCommand::V1 {
                        dir_x: num(args[0])?,
                        dir_y: num(args[1])?,
                        gear: num(args[2])?,
                    })
                }
                "drive-v2" => {
                    if args.len() != 3 && args.len() != 4 {
                        return Err(format!("'drive-v2' takes 3 or 4 arguments, got {}", args.len()));
                    }
                    let speed_ratio = args.get(3).map_or(Ok(0), |a| num(a))?;
                    MotorPacket::Drive(MotorCommand::V2 {
                        vx: num(args[0])?,
                        vy: num(args[1])?,
                        omega: num(args[2])?,
                        speed_ratio,
                        reserved: [0, 0],
                    })
                }
                "telemetry" | "telemetry36" => {
                    want(8)?;
                    let v: Vec<f32> = args.iter().map(|a| float(a)).collect::<Result<_, _>>()?;
                    let mut t = Telemetry::motor([v[0], v[1], v[2], v[3]], [v[4], v[5], v[6], v[7]]);
                    if kind == "telemetry36" {
                        t.form = TelemetryForm::Motor36;
                    }
                    MotorPacket::Telemetry(t)
                }
                other => return Err(format!("unknown motor packet '{other}'")),
            };
            Ok(packet.to_bytes())
        }
        Protocol::Sensor => {
            let reading = |id: &str, value: SensorValue| -> Result<SensorPacket, String> {
                Ok(SensorPacket::Reading(SensorReading {
                    sensor_id: num(id)?,
                    status: SensorStatus::Operational,
                    value,
                }))
            };
            let packet = match kind {
                "keep-state" => {
                    want(2)?;
                    SensorPacket::KeepState { status: num(args[0])?, sequence: num(args[1])? }
                }
                "command" => {
                    want(2)?;
                    SensorPacket::Command {
                        id: CommandId::from(num::<u8>(args[0])?),
                        parameter: num(args[1])?,
                    }
                }
                "distance" => {
                    want(2)?;
                    reading(args[0], SensorValue::Distance { cm: float(args[1])? })?
                }
                "encoder" => {
                    want(3)?;
                    let direction = match args[2] {
                        "forward" => EncoderDirection::Forward,
                        "reverse" => EncoderDirection::Reverse,
                        other => EncoderDirection::from(num::<u8>(other)?),
                    };
                    reading(args[0], SensorValue::Encoder { count: num(args[1])?, direction })?
                }
                "switch" => {
                    want(2)?;
                    let state = match args[1] {
                        "pressed" => SwitchState::Pressed,
                        "released" => SwitchState::Released,
                        other => SwitchState::from(num::<u8>(other)?),
                    };
                    reading(args[0], SensorValue::Switch(state))?
                }
                "pot" => {
                    want(2)?;
                    reading(args[0], SensorValue::Potentiometer { angle: float(args[1])? })?
                }
                "navx" => {
                    want(10)?;
                    let v: Vec<f32> = args[1..].iter().map(|a| float(a)).collect::<Result<_, _>>()?;
                    reading(
                        args[0],
                        SensorValue::NavX(NavX {
                            altitude: v[0],
                            pressure: v[1],
                            heading_deg: v[2],
                            temperature: v[3],
                            accel: [v[4], v[5], v[6]],
                            mag: [v[7], v[8]],
                        }),
                    )?
                }
                other => return Err(format!("unknown sensor packet '{other}'")),
            };
            Ok(packet.to_bytes())
        }
    }
}

fn num<T: std::str::FromStr + TryFrom<i64>>(s: &str) -> Result<T, String> {
    if let Some(hex) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        let v = i64::from_str_radix(hex, 16).map_err(|_| format!("'{s}' is not a number"))?;
        return T::try_from(v).map_err(|_| format!("'{s}' is out of range"));
    }
    s.parse::<T>().map_err(|_| format!("'{s}' is not a valid number here"))
}

fn float(s: &str) -> Result<f32, String> {
    s.parse::<f32>().map_err(|_| format!("'{s}' is not a number"))
}

fn command(s: &str) -> Result<Command, String> {
    Ok(match s {
        "forward" => Command::Forward,
        "right" => Command::Right,
        "left" => Command::Left,
        "stop" => Command::Stop,
        other => Command::from(num::<u8>(other)?),
    })
}

fn direction(s: &str) -> Result<Direction, String> {
    Ok(match s {
        "south" => Direction::South,
        "north" => Direction::North,
        "west" => Direction::West,
        "east" => Direction::East,
        other => Direction::from(num::<u8>(other)?),
    })
}

/// Formats bytes as spaced upper-case hex.
pub fn to_hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_reports_resync_and_checksum_verdicts() {
        // Garbage, a frame with a bad checksum, then the seed's frame.
        let out = decode_hex(
            Protocol::Motor,
            "11 22 AA 03 01 80 80 06 0B AA 03 01 80 80 06 0A",
            ChecksumPolicy::Sum,
        )
        .unwrap();
        assert!(out.contains("bad checksum"), "{out}");
        assert!(out.contains("skipped"), "{out}");
        assert!(out.contains("dir_x: 128, dir_y: 128, gear: 6"), "{out}");
        assert!(out.trim_end().ends_with("1 frame(s), 1 error(s), 9 bytes skipped"), "{out}");
        assert!(out.find("bad checksum") < out.find("resync"), "{out}");
        // With the firmware's "ignore" policy the first frame is accepted too.
        let out = decode_hex(Protocol::Motor, "AA 03 01 80 80 06 0B", ChecksumPolicy::Ignore).unwrap();
        assert!(out.contains("1 frame(s), 0 error(s)"), "{out}");
    }

    #[test]
    fn decode_link_says_which_byte_order_and_flags_fatal_sizes() {
        let out = decode_hex(Protocol::Link, "00 05 00 07 02 03 03", ChecksumPolicy::Sum).unwrap();
        assert!(out.contains("LittleEndian"), "{out}");
        let out = decode_hex(Protocol::Link, "00 00 01 02", ChecksumPolicy::Sum).unwrap();
        assert!(out.contains("fatal"), "{out}");
    }

    #[test]
    fn encode_builds_the_spec_frames() {
        assert_eq!(
            encode(Protocol::Motor, &["drive-v1", "0x80", "0x80", "6"], false).unwrap(),
            parse_hex("AA 03 01 80 80 06 0A").unwrap()
        );
        assert_eq!(
            encode(Protocol::Motor, &["drive-v2", "50", "0", "-20", "6"], false).unwrap(),
            parse_hex("AA 06 10 32 00 EC 06 00 00 3A").unwrap()
        );
        assert_eq!(encode(Protocol::Link, &["stop"], true).unwrap(), parse_hex("00 02 00 06").unwrap());
        assert_eq!(
            encode(Protocol::Sensor, &["distance", "1", "123.25"], false).unwrap(),
            parse_hex("03 08 04 01 01 04 42 F6 80 00").unwrap()
        );
        assert_eq!(
            encode(Protocol::Sensor, &["keep-state", "2", "258"], false).unwrap(),
            parse_hex("01 03 02 01 02").unwrap()
        );
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        assert!(parse_hex("A").is_err());
        assert!(parse_hex("zz").is_err());
        assert!(encode(Protocol::Link, &["trajectory", "300", "forward"], false).is_err());
        assert!(encode(Protocol::Motor, &["drive-v2", "1"], false).is_err());
        assert!(encode(Protocol::Sensor, &["warp"], false).is_err());
        assert!(encode(Protocol::Link, &[], false).is_err());
    }
}
