//! `explobot decode` and `explobot encode`: the three wire formats by hand, for people reading a
//! serial capture or crafting a test frame.
//!
//! Decoding goes through [`protocol::Decoder`], one byte at a time, so each line can say where its
//! frame ended. Encoding takes typed arguments: [`EncodeArgs`] holds the protocol and one
//! [`Message`], a clap subcommand per message, so clap checks the field count and every number's
//! range before any frame is built.
//!
//! ```
//! use clap::Parser;
//! use sim::wiretool::{EncodeArgs, Protocol, decode_hex};
//!
//! let out = decode_hex(Protocol::Motor, "AA 03 01 80 80 06 0A", Default::default()).unwrap();
//! assert!(out.contains("dir_x: 128"));
//! let args = EncodeArgs::try_parse_from(["encode", "--protocol", "link", "trajectory", "6", "forward"]).unwrap();
//! assert_eq!(args.encode().unwrap(), vec![0x00, 0x04, 0x01, 0x00, 0x06, 0x00]);
//! ```

use std::fmt::{Debug, Display, Write as _};

use clap::builder::{PossibleValuesParser, TypedValueParser as _};
use protocol::Decoder;
use protocol::link::{self, Command, Direction, GuiMessage, MsgOrder};
use protocol::motor::{self, ChecksumPolicy, MotorCommand, MotorPacket, Telemetry, TelemetryForm};
use protocol::resync::ResyncStats;
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

impl Display for Protocol {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use clap::ValueEnum as _;
        match self.to_possible_value() {
            Some(value) => f.write_str(value.get_name()),
            None => Ok(()),
        }
    }
}

/// What `decode` and `encode` can refuse.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum WireToolError {
    /// A hex token that does not decode.
    #[error("'{token}' is not hex")]
    Hex {
        /// The token, as given.
        token: String,
        /// What the `hex` crate found (the error's source).
        source: hex::FromHexError,
    },
    /// The message belongs to another protocol than `--protocol`.
    #[error("that is a {message_protocol} message, but --protocol is {protocol}")]
    WrongProtocol {
        /// The protocol it belongs to.
        message_protocol: Protocol,
        /// The protocol asked for.
        protocol: Protocol,
    },
}

/// A command-line value that is not what its argument takes (clap prints it).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{input}' is not {expected}")]
struct BadValue {
    input: String,
    expected: String,
}

/// `explobot decode`: hex bytes in, one line per frame, error and resync out.
#[derive(Debug, Clone, clap::Parser)]
pub struct DecodeArgs {
    /// Which wire format.
    #[arg(long, value_enum)]
    pub protocol: Protocol,
    /// Motor-link checksum policy.
    #[arg(
        long,
        default_value = "sum",
        value_parser = PossibleValuesParser::new(ChecksumPolicy::NAMES).try_map(|name| name.parse::<ChecksumPolicy>()),
    )]
    pub checksum: ChecksumPolicy,
    /// Hex bytes, e.g. `AA 03 01 80 80 06 0A` (any separators).
    #[arg(required = true, num_args = 1..)]
    pub hex: Vec<String>,
}

impl DecodeArgs {
    /// The report `explobot decode` prints.
    pub fn decode(&self) -> Result<String, WireToolError> {
        decode_hex(self.protocol, &self.hex.join(" "), self.checksum)
    }
}

/// `explobot encode`: one message in, its frame out.
#[derive(Debug, Clone, clap::Parser)]
pub struct EncodeArgs {
    /// Which wire format (must be the message's).
    #[arg(long, value_enum)]
    pub protocol: Protocol,
    /// Write the link `Msg` little-endian, as the 2024 Cute did.
    #[arg(long)]
    pub little_endian: bool,
    /// The message and its fields. Numbers are decimal, or hex with `0x`.
    #[command(subcommand)]
    pub message: Message,
}

impl EncodeArgs {
    /// The frame, after checking that the message belongs to `--protocol`.
    pub fn encode(&self) -> Result<Vec<u8>, WireToolError> {
        let message_protocol = self.message.protocol();
        if message_protocol != self.protocol {
            return Err(WireToolError::WrongProtocol { message_protocol, protocol: self.protocol });
        }
        let order = if self.little_endian { MsgOrder::LittleEndian } else { MsgOrder::BigEndian };
        Ok(match &self.message {
            Message::Link(message) => message.to_message().to_bytes(order),
            Message::Motor(message) => message.to_packet().to_bytes(),
            Message::Sensor(message) => message.to_packet().to_bytes(),
        })
    }
}

/// Any message of the three protocols (one flat list of subcommands).
#[derive(Debug, Clone, clap::Subcommand)]
pub enum Message {
    /// A link message.
    #[command(flatten)]
    Link(LinkMessage),
    /// A motor-board packet.
    #[command(flatten)]
    Motor(MotorMessage),
    /// A sensor-board packet.
    #[command(flatten)]
    Sensor(SensorMessage),
}

impl Message {
    /// The protocol this message belongs to.
    pub fn protocol(&self) -> Protocol {
        match self {
            Message::Link(_) => Protocol::Link,
            Message::Motor(_) => Protocol::Motor,
            Message::Sensor(_) => Protocol::Sensor,
        }
    }
}

/// Cute ⇄ Carto messages. CMD is forward, right, left, stop or a number; DIR is south, north,
/// west, east or a number.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum LinkMessage {
    /// `SendMovesTrajectory`: N_TOTAL CMD.
    Trajectory {
        /// Moves in the trajectory.
        #[arg(value_parser = number::<u8>)]
        n_total: u8,
        /// The move.
        #[arg(value_parser = |text: &str| code(text, Command::NAMED))]
        command: Command,
    },
    /// `SendMoveCartography`: CMD.
    Cartography {
        /// The move.
        #[arg(value_parser = |text: &str| code(text, Command::NAMED))]
        command: Command,
    },
    /// `MoveDone`.
    MoveDone,
    /// `SetObstaclePosition`: X Y.
    Obstacle {
        /// Row.
        #[arg(value_parser = number::<u8>)]
        x: u8,
        /// Column.
        #[arg(value_parser = number::<u8>)]
        y: u8,
    },
    /// `SetRobotPosition`: X Y.
    Robot {
        /// Row.
        #[arg(value_parser = number::<u8>)]
        x: u8,
        /// Column.
        #[arg(value_parser = number::<u8>)]
        y: u8,
    },
    /// `StopRobot`.
    Stop,
    /// `SendRobotPosition`: X Y DIR.
    Position {
        /// Row.
        #[arg(value_parser = number::<u8>)]
        x: u8,
        /// Column.
        #[arg(value_parser = number::<u8>)]
        y: u8,
        /// Heading.
        #[arg(value_parser = |text: &str| code(text, Direction::NAMED))]
        direction: Direction,
    },
    /// `RobotPositionReceived`.
    PositionReceived,
}

impl LinkMessage {
    /// The typed message.
    pub fn to_message(&self) -> GuiMessage {
        match *self {
            LinkMessage::Trajectory { n_total, command } => {
                GuiMessage::SendMovesTrajectory { n_total, command }
            }
            LinkMessage::Cartography { command } => GuiMessage::SendMoveCartography { command },
            LinkMessage::MoveDone => GuiMessage::MoveDone,
            LinkMessage::Obstacle { x, y } => GuiMessage::SetObstaclePosition { x, y },
            LinkMessage::Robot { x, y } => GuiMessage::SetRobotPosition { x, y },
            LinkMessage::Stop => GuiMessage::StopRobot,
            LinkMessage::Position { x, y, direction } => GuiMessage::SendRobotPosition { x, y, direction },
            LinkMessage::PositionReceived => GuiMessage::RobotPositionReceived,
        }
    }
}

/// Carto ⇄ motor board packets.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum MotorMessage {
    /// Drive v1: DIR_X DIR_Y GEAR (0x80 is neutral).
    DriveV1 {
        /// X axis.
        #[arg(value_parser = number::<u8>)]
        dir_x: u8,
        /// Y axis.
        #[arg(value_parser = number::<u8>)]
        dir_y: u8,
        /// Gear.
        #[arg(value_parser = number::<u8>)]
        gear: u8,
    },
    /// Drive v2: VX VY OMEGA [SPEED_RATIO], percent.
    DriveV2 {
        /// Forward speed, %.
        #[arg(value_parser = number::<i8>, allow_negative_numbers = true)]
        vx: i8,
        /// Sideways speed, %.
        #[arg(value_parser = number::<i8>, allow_negative_numbers = true)]
        vy: i8,
        /// Turn rate, %.
        #[arg(value_parser = number::<i8>, allow_negative_numbers = true)]
        omega: i8,
        /// Speed ratio.
        #[arg(value_parser = number::<u8>, default_value_t = 0)]
        speed_ratio: u8,
    },
    /// Telemetry, 32-byte form: RPM×4 POWER×4 (FL, FR, RL, RR).
    Telemetry(WheelValues),
    /// Telemetry, 36-byte form (motor id 1): RPM×4 POWER×4.
    Telemetry36(WheelValues),
}

/// Wheel speeds then motor powers, each FL, FR, RL, RR.
#[derive(Debug, Clone, clap::Args)]
pub struct WheelValues {
    /// Front left wheel speed, rpm.
    #[arg(allow_negative_numbers = true)]
    pub rpm_fl: f32,
    /// Front right wheel speed, rpm.
    #[arg(allow_negative_numbers = true)]
    pub rpm_fr: f32,
    /// Rear left wheel speed, rpm.
    #[arg(allow_negative_numbers = true)]
    pub rpm_rl: f32,
    /// Rear right wheel speed, rpm.
    #[arg(allow_negative_numbers = true)]
    pub rpm_rr: f32,
    /// Front left wheel power, %.
    #[arg(allow_negative_numbers = true)]
    pub power_fl: f32,
    /// Front right wheel power, %.
    #[arg(allow_negative_numbers = true)]
    pub power_fr: f32,
    /// Rear left wheel power, %.
    #[arg(allow_negative_numbers = true)]
    pub power_rl: f32,
    /// Rear right wheel power, %.
    #[arg(allow_negative_numbers = true)]
    pub power_rr: f32,
}

impl WheelValues {
    fn telemetry(&self, form: TelemetryForm) -> Telemetry {
        let rpm = [self.rpm_fl, self.rpm_fr, self.rpm_rl, self.rpm_rr];
        let power = [self.power_fl, self.power_fr, self.power_rl, self.power_rr];
        Telemetry { form, ..Telemetry::motor(rpm, power) }
    }
}

impl MotorMessage {
    /// The typed packet.
    pub fn to_packet(&self) -> MotorPacket {
        match self {
            &MotorMessage::DriveV1 { dir_x, dir_y, gear } => {
                MotorPacket::Drive(MotorCommand::V1 { dir_x, dir_y, gear })
            }
            &MotorMessage::DriveV2 { vx, vy, omega, speed_ratio } => {
                MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, speed_ratio, reserved: [0, 0] })
            }
            MotorMessage::Telemetry(wheels) => {
                MotorPacket::Telemetry(wheels.telemetry(TelemetryForm::Motor32))
            }
            MotorMessage::Telemetry36(wheels) => {
                MotorPacket::Telemetry(wheels.telemetry(TelemetryForm::Motor36))
            }
        }
    }
}

/// Carto ⇄ sensor board packets. Readings go out with status operational.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum SensorMessage {
    /// Keep-state: STATUS SEQUENCE.
    KeepState {
        /// Status byte.
        #[arg(value_parser = number::<u8>)]
        status: u8,
        /// Sequence number.
        #[arg(value_parser = number::<u16>)]
        sequence: u16,
    },
    /// Command: ID PARAMETER.
    Command {
        /// Command id.
        #[arg(value_parser = number::<u8>)]
        id: u8,
        /// Parameter.
        #[arg(value_parser = number::<i16>, allow_negative_numbers = true)]
        parameter: i16,
    },
    /// Distance reading: ID CM (−1 = no echo).
    Distance {
        /// Sensor id.
        #[arg(value_parser = number::<u8>)]
        id: u8,
        /// Distance, cm.
        #[arg(allow_negative_numbers = true)]
        cm: f32,
    },
    /// Encoder reading: ID COUNT forward|reverse|N.
    Encoder {
        /// Sensor id.
        #[arg(value_parser = number::<u8>)]
        id: u8,
        /// Count.
        #[arg(value_parser = number::<i32>, allow_negative_numbers = true)]
        count: i32,
        /// Direction.
        #[arg(value_parser = |text: &str| code(text, EncoderDirection::NAMED))]
        direction: EncoderDirection,
    },
    /// Switch reading: ID pressed|released|N.
    Switch {
        /// Sensor id.
        #[arg(value_parser = number::<u8>)]
        id: u8,
        /// State.
        #[arg(value_parser = |text: &str| code(text, SwitchState::NAMED))]
        state: SwitchState,
    },
    /// Potentiometer reading: ID ANGLE.
    Pot {
        /// Sensor id.
        #[arg(value_parser = number::<u8>)]
        id: u8,
        /// Angle.
        #[arg(allow_negative_numbers = true)]
        angle: f32,
    },
    /// NavX reading: ID ALT PRESSURE HEADING TEMP AX AY AZ MX MY.
    Navx {
        /// Sensor id.
        #[arg(value_parser = number::<u8>)]
        id: u8,
        /// Altitude.
        #[arg(allow_negative_numbers = true)]
        altitude: f32,
        /// Pressure.
        #[arg(allow_negative_numbers = true)]
        pressure: f32,
        /// Heading, degrees.
        #[arg(allow_negative_numbers = true)]
        heading: f32,
        /// Temperature.
        #[arg(allow_negative_numbers = true)]
        temperature: f32,
        /// Acceleration x.
        #[arg(allow_negative_numbers = true)]
        ax: f32,
        /// Acceleration y.
        #[arg(allow_negative_numbers = true)]
        ay: f32,
        /// Acceleration z.
        #[arg(allow_negative_numbers = true)]
        az: f32,
        /// Magnetometer x.
        #[arg(allow_negative_numbers = true)]
        mx: f32,
        /// Magnetometer y.
        #[arg(allow_negative_numbers = true)]
        my: f32,
    },
}

impl SensorMessage {
    /// The typed packet.
    pub fn to_packet(&self) -> SensorPacket {
        let reading = |sensor_id: u8, value: SensorValue| {
            SensorPacket::Reading(SensorReading { sensor_id, status: SensorStatus::Operational, value })
        };
        match *self {
            SensorMessage::KeepState { status, sequence } => SensorPacket::KeepState { status, sequence },
            SensorMessage::Command { id, parameter } => {
                SensorPacket::Command { id: CommandId::from(id), parameter }
            }
            SensorMessage::Distance { id, cm } => reading(id, SensorValue::Distance { cm }),
            SensorMessage::Encoder { id, count, direction } => {
                reading(id, SensorValue::Encoder { count, direction })
            }
            SensorMessage::Switch { id, state } => reading(id, SensorValue::Switch(state)),
            SensorMessage::Pot { id, angle } => reading(id, SensorValue::Potentiometer { angle }),
            SensorMessage::Navx { id, altitude, pressure, heading, temperature, ax, ay, az, mx, my } => {
                reading(
                    id,
                    SensorValue::NavX(NavX {
                        altitude,
                        pressure,
                        heading_deg: heading,
                        temperature,
                        accel: [ax, ay, az],
                        mag: [mx, my],
                    }),
                )
            }
        }
    }
}

/// An integer, decimal or `0x` hex, in `T`'s range.
fn number<T: std::str::FromStr + TryFrom<i64>>(text: &str) -> Result<T, BadValue> {
    let bad = || BadValue {
        input: text.to_owned(),
        expected: format!("a {} (decimal, or hex with 0x)", std::any::type_name::<T>()),
    };
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(digits) => {
            i64::from_str_radix(digits, 16).ok().and_then(|v| T::try_from(v).ok()).ok_or_else(bad)
        }
        None => text.parse::<T>().map_err(|_| bad()),
    }
}

/// A code by its lower-case name (`forward`, `east`, …, from the type's `NAMED` list) or its raw
/// byte.
fn code<T: Copy + From<u8>>(text: &str, named: &[(&str, T)]) -> Result<T, BadValue> {
    if let Some((_, code)) = named.iter().find(|(name, _)| name.to_ascii_lowercase() == text) {
        return Ok(*code);
    }
    number::<u8>(text).map(T::from).map_err(|_| BadValue {
        input: text.to_owned(),
        expected: format!(
            "one of {} or a byte",
            named.iter().map(|(name, _)| name.to_ascii_lowercase()).collect::<Vec<_>>().join(", ")
        ),
    })
}

/// Parses hex text: pairs of digits, optionally `0x`-prefixed, separated by white space, `,`,
/// `:` or `-`.
pub fn parse_hex(text: &str) -> Result<Vec<u8>, WireToolError> {
    let mut out = Vec::new();
    for token in text.split(|c: char| c.is_whitespace() || matches!(c, ',' | ':' | '-')) {
        let digits = token.strip_prefix("0x").or_else(|| token.strip_prefix("0X")).unwrap_or(token);
        let bytes =
            hex::decode(digits).map_err(|source| WireToolError::Hex { token: token.to_owned(), source })?;
        out.extend(bytes);
    }
    Ok(out)
}

/// Formats bytes as spaced upper-case hex.
pub fn to_hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| hex::encode_upper([*b])).collect::<Vec<_>>().join(" ")
}

/// Decodes hex text and describes every frame, error and skipped byte, one per line.
pub fn decode_hex(protocol: Protocol, hex: &str, checksum: ChecksumPolicy) -> Result<String, WireToolError> {
    let bytes = parse_hex(hex)?;
    Ok(decode_bytes(protocol, &bytes, checksum))
}

/// Describes `bytes` frame by frame. Bytes are fed one at a time, so each line can say where
/// its frame ended.
pub fn decode_bytes(protocol: Protocol, bytes: &[u8], checksum: ChecksumPolicy) -> String {
    let mut out = String::new();
    match protocol {
        Protocol::Link => describe_link(&mut out, bytes),
        Protocol::Motor => describe_resyncing(
            &mut out,
            bytes,
            motor::Decoder::new(checksum),
            "resync on the next 0xAA",
            MotorPacket::buffer_len,
        ),
        Protocol::Sensor => describe_resyncing(
            &mut out,
            bytes,
            sensor::Decoder::new(),
            "dropping one byte and retrying",
            SensorPacket::buffer_len,
        ),
    }
    out
}

/// `link` has no resync: a fatal `Size` ends what can be decoded.
fn describe_link(out: &mut String, bytes: &[u8]) {
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
                        (i + 1).saturating_sub(len),
                        i + 1
                    );
                }
                Err(e) => {
                    errors += 1;
                    let fatal =
                        if e.is_fatal() { " — fatal: a receiver closes the connection here" } else { "" };
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
    tail(out, d.buffered(), frames, errors, None);
}

/// Feeds `bytes` one at a time to a decoder that resynchronises (motor, sensor) and writes a
/// line per frame, error and resync. `resync` says how it recovers; `frame_len` gives a decoded
/// frame's length on the wire.
fn describe_resyncing<D>(
    out: &mut String,
    bytes: &[u8],
    mut d: D,
    resync: &str,
    frame_len: impl Fn(&D::Frame) -> usize,
) where
    D: Decoder,
    D::Frame: Debug,
    D::Error: Display,
    ResyncStats: From<D::Stats>,
{
    let skipped = |d: &D| ResyncStats::from(d.stats()).bytes_skipped;
    let (mut frames, mut errors, mut skipped_before) = (0u64, 0u64, 0u64);
    for (i, b) in bytes.iter().enumerate() {
        for item in d.feed(std::slice::from_ref(b)) {
            match item {
                Ok(p) => {
                    frames += 1;
                    let len = frame_len(&p);
                    let _ = writeln!(out, "[{:>4}..{:<4}] ok    {p:?}", (i + 1).saturating_sub(len), i + 1);
                }
                Err(e) => {
                    errors += 1;
                    let _ = writeln!(out, "[{:>4}]       error {e} ({resync})", i + 1);
                }
            }
            note_skipped(out, &mut skipped_before, skipped(&d), i + 1);
        }
    }
    note_skipped(out, &mut skipped_before, skipped(&d), bytes.len());
    tail(out, d.buffered(), frames, errors, Some(skipped(&d)));
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

#[cfg(test)]
mod tests {
    use clap::Parser as _;

    use super::*;

    /// `explobot encode WORDS…`, parsed and encoded as the CLI does.
    fn encode(words: &[&str]) -> Result<Vec<u8>, String> {
        let args = EncodeArgs::try_parse_from(std::iter::once("encode").chain(words.iter().copied()))
            .map_err(|e| e.to_string())?;
        args.encode().map_err(|e| e.to_string())
    }

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
            encode(&["--protocol", "motor", "drive-v1", "0x80", "0x80", "6"]).unwrap(),
            parse_hex("AA 03 01 80 80 06 0A").unwrap()
        );
        assert_eq!(
            encode(&["--protocol", "motor", "drive-v2", "50", "0", "-20", "6"]).unwrap(),
            parse_hex("AA 06 10 32 00 EC 06 00 00 3A").unwrap()
        );
        assert_eq!(
            encode(&["--protocol", "link", "--little-endian", "stop"]).unwrap(),
            parse_hex("00 02 00 06").unwrap()
        );
        assert_eq!(
            encode(&["--protocol", "sensor", "distance", "1", "123.25"]).unwrap(),
            parse_hex("03 08 04 01 01 04 42 F6 80 00").unwrap()
        );
        assert_eq!(
            encode(&["--protocol", "sensor", "keep-state", "2", "258"]).unwrap(),
            parse_hex("01 03 02 01 02").unwrap()
        );
    }

    #[test]
    fn the_argument_definitions_pass_clap_debug_asserts() {
        use clap::CommandFactory as _;
        EncodeArgs::command().debug_assert();
        DecodeArgs::command().debug_assert();
    }

    #[test]
    fn every_message_encodes_a_frame_that_decodes_cleanly() {
        let lines: [&[&str]; 19] = [
            &["link", "trajectory", "6", "right"],
            &["link", "cartography", "0x02"],
            &["link", "move-done"],
            &["link", "obstacle", "2", "4"],
            &["link", "robot", "2", "4"],
            &["link", "stop"],
            &["link", "position", "2", "3", "east"],
            &["link", "position-received"],
            &["motor", "drive-v1", "1", "2", "3"],
            &["motor", "drive-v2", "-128", "127", "0x7F"],
            &["motor", "telemetry", "100", "-100", "50.5", "0", "25", "-25", "12.5", "0"],
            &["motor", "telemetry36", "1", "2", "3", "4", "5", "6", "7", "-8e3"],
            &["sensor", "keep-state", "1", "1"],
            &["sensor", "command", "1", "-5"],
            &["sensor", "distance", "1", "-1"],
            &["sensor", "encoder", "2", "-2", "reverse"],
            &["sensor", "switch", "4", "pressed"],
            &["sensor", "pot", "3", "45.5"],
            &["sensor", "navx", "7", "1.5", "1013.25", "90", "20.25", "0.5", "-0.5", "9.81", "12", "-3"],
        ];
        for line in lines {
            let (protocol, message) = line.split_first().unwrap();
            let words: Vec<&str> =
                ["--protocol", protocol].into_iter().chain(message.iter().copied()).collect();
            let bytes = encode(&words).unwrap_or_else(|e| panic!("{line:?}: {e}"));
            let protocol = <Protocol as clap::ValueEnum>::from_str(protocol, false).unwrap();
            let out = decode_bytes(protocol, &bytes, ChecksumPolicy::Sum);
            let summary = out.lines().last().unwrap_or_default();
            assert!(summary.starts_with("1 frame(s), 0 error(s)"), "{line:?}: {out}");
        }
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        assert!(parse_hex("A").is_err());
        assert!(parse_hex("zz").is_err());
        assert!(encode(&["--protocol", "link", "trajectory", "300", "forward"]).is_err());
        assert!(encode(&["--protocol", "motor", "drive-v2", "1"]).is_err());
        assert!(encode(&["--protocol", "sensor", "warp"]).is_err());
        assert!(encode(&["--protocol", "link"]).is_err());
        assert_eq!(
            encode(&["--protocol", "link", "drive-v1", "1", "2", "3"]),
            Err("that is a motor message, but --protocol is link".to_owned())
        );
    }
}
