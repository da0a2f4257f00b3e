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
//! use explobot::wiretool::{EncodeArgs, Protocol, decode_hex};
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

mod encode;

pub use encode::{LinkMessage, Message, MotorMessage, SensorMessage, WheelValues};

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
mod tests;
