//! `motor`: the Carto ⇄ motor board protocol over UART, 115200 8N1 (seed 000).
//!
//! ```text
//! ┌─────────┬───────┬─────────┬────────────────────────────────────────────┬──────┐
//! │ offset  │ bytes │ field   │ meaning                                    │ unit │
//! ├─────────┼───────┼─────────┼────────────────────────────────────────────┼──────┤
//! │ 0       │ 1     │ SYNC    │ start byte, always 0xAA                    │ —    │
//! │ 1       │ 1     │ LEN     │ payload bytes (not the header, not CK)     │ u8   │
//! │ 2       │ 1     │ TYPE    │ packet type, see [`PacketType`]            │ u8   │
//! │ 3       │ LEN   │ PAYLOAD │ per type, below                            │ —    │
//! │ 3 + LEN │ 1     │ CK      │ (LEN + TYPE + Σ PAYLOAD) mod 256           │ u8   │
//! └─────────┴───────┴─────────┴────────────────────────────────────────────┴──────┘
//! ```
//!
//! Payloads (floats are IEEE-754 binary32 **little-endian**, wheel order FL, FR, RL, RR):
//!
//! ```text
//! TYPE 0x01 drive v1, LEN 3           TYPE 0x10 drive v2, LEN 6
//! ┌────────┬───────┬───────┬─────────────┐   ┌────────┬───────┬─────────────┬───────────┐
//! │ offset │ bytes │ field │ unit        │   │ offset │ bytes │ field       │ unit      │
//! │ 0      │ 1     │ dir_x │ u8, 0x80 =0 │   │ 0      │ 1     │ vx          │ i8 %      │
//! │ 1      │ 1     │ dir_y │ u8, 0x80 =0 │   │ 1      │ 1     │ vy          │ i8 %      │
//! │ 2      │ 1     │ gear  │ u8, /8      │   │ 2      │ 1     │ omega       │ i8 %      │
//! └────────┴───────┴───────┴─────────────┘   │ 3      │ 1     │ speed_ratio │ u8        │
//!                                            │ 4      │ 2     │ reserved    │ —         │
//!                                            └────────┴───────┴─────────────┴───────────┘
//! TYPE 0x04 telemetry, LEN 32 / 36 / 104
//! ┌──────────────┬──────────────┬───────┬─────────────┬─────────────────────────────────┐
//! │ offset (32)  │ offset (36)  │ bytes │ field       │ unit                            │
//! │ —            │ 0            │ 1     │ motor_id    │ u8                              │
//! │ —            │ 1            │ 3     │ padding     │ written 0, ignored              │
//! │ 0            │ 4            │ 16    │ wheel_rpm   │ 4 × f32 LE, rpm                 │
//! │ 16           │ 20           │ 16    │ motor_power │ 4 × f32 LE, % (±100)            │
//! │ 32 (104 only)│ —            │ 24    │ odometry    │ x, y m; θ rad; vx, vy m/s; ω rad/s │
//! │ 56 (104 only)│ —            │ 48    │ imu         │ accel[3] m/s², gyro[3] rad/s, mag[3] µT, roll, pitch, yaw rad │
//! └──────────────┴──────────────┴───────┴─────────────┴─────────────────────────────────┘
//! ```
//!
//! The 104-byte "complete" form (32-byte layout followed by odometry and IMU) is our optional
//! extension; no firmware sends it.
//!
//! **Checksums.** We emit the seed's sum by default. Real firmware sends the XOR of the payload or
//! the constant 0xFC, so a receiver picks a [`ChecksumPolicy`] per port.
//!
//! **Contract.** [`Frame::check_len`] proves every getter in bounds; [`MotorPacket::parse`] never
//! panics (it calls `check_len` itself); [`MotorPacket::emit`] never panics when the buffer is at
//! least [`MotorPacket::buffer_len`] bytes, and writes exactly that many.
//!
//! **Streaming.** [`Decoder`] is the shared [`Resync`] engine with the
//! motor framing: it skips to the next `0xAA`, waits for `LEN + 4` bytes (at most 259, its whole
//! buffer), then checks. A bad checksum or a bad length drops only the start byte: the bytes after
//! it are scanned again, so a good frame hidden inside a corrupted one is still found. Recovery
//! after garbage is therefore automatic; it fails only when a *false* frame (a stray `0xAA` in the
//! garbage) passes the checksum, which for the `sum` policy happens about once in 256 false
//! starts, and with `ignore` always.
//!
//! ```
//! use protocol::motor::{Decoder, ChecksumPolicy, MotorCommand, MotorPacket};
//!
//! let drive = MotorPacket::Drive(MotorCommand::V1 { dir_x: 0x80, dir_y: 0x80, gear: 6 });
//! assert_eq!(drive.to_bytes(), [0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x0A]);
//!
//! let mut decoder = Decoder::new(ChecksumPolicy::Sum);
//! let mut stream = vec![0x13, 0x37]; // line noise first
//! stream.extend(drive.to_bytes());
//! assert_eq!(decoder.feed(&stream), vec![Ok(drive)]);
//! assert_eq!(decoder.stats().bytes_skipped, 2);
//! ```

use crate::resync::{self, Head, Report, Resync, ResyncStats};

/// Byte ranges of the motor frame.
pub mod field {
    use crate::{Field, Rest};

    /// The start byte.
    pub const SYNC: usize = 0;
    /// Payload length.
    pub const LEN: usize = 1;
    /// Packet type.
    pub const TYPE: usize = 2;
    /// Payload, up to the checksum.
    pub const PAYLOAD: Rest = 3..;
    /// Bytes before the payload.
    pub const HEADER_LEN: usize = 3;
    /// Header plus checksum: a frame is `LEN + OVERHEAD` bytes.
    pub const OVERHEAD: usize = 4;

    /// The payload range for a given `LEN`.
    pub const fn payload(len: u8) -> Field {
        HEADER_LEN..HEADER_LEN + len as usize
    }

    /// The checksum offset for a given `LEN`.
    pub const fn checksum(len: u8) -> usize {
        HEADER_LEN + len as usize
    }
}

/// The start byte of every frame.
pub const SYNC: u8 = 0xAA;
/// The longest possible frame (LEN 255).
pub const MAX_FRAME_LEN: usize = u8::MAX as usize + field::OVERHEAD;
/// The constant "checksum" of the Arduino transmitters.
pub const CONST_CHECKSUM: u8 = 0xFC;
/// Payload lengths accepted for telemetry: motor block, motor block with id, complete block.
pub const TELEMETRY_LENGTHS: &[u8] = &[32, 36, 104];
const DRIVE_V1_LENGTHS: &[u8] = &[3];
const DRIVE_V2_LENGTHS: &[u8] = &[6];

enum_with_unknown! {
    /// The `TYPE` byte.
    pub enum PacketType(u8) {
        /// 0x01, Carto → board: drive command v1 (3 bytes).
        DriveV1 = 0x01,
        /// 0x04, board → Carto: telemetry (32, 36 or 104 bytes).
        Telemetry = 0x04,
        /// 0x10, Carto → board: drive command v2 (6 bytes).
        DriveV2 = 0x10,
    }
}

impl PacketType {
    /// Payload lengths valid for this type; empty for an unknown type (any length).
    pub fn valid_lengths(self) -> &'static [u8] {
        match self {
            PacketType::DriveV1 => DRIVE_V1_LENGTHS,
            PacketType::DriveV2 => DRIVE_V2_LENGTHS,
            PacketType::Telemetry => TELEMETRY_LENGTHS,
            PacketType::Unknown(_) => &[],
        }
    }
}

/// How a transmitter computes the checksum byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ChecksumKind {
    /// `(LEN + TYPE + Σ payload) mod 256`: the seed's rule, our default.
    #[default]
    Sum,
    /// XOR of the payload bytes: the Zephyr firmware.
    XorPayload,
    /// The constant 0xFC: the Arduino firmware.
    ConstFc,
}

impl ChecksumKind {
    /// The checksum byte for this header and payload.
    pub fn compute(self, len: u8, packet_type: u8, payload: &[u8]) -> u8 {
        match self {
            ChecksumKind::Sum => {
                payload.iter().fold(len.wrapping_add(packet_type), |acc, b| acc.wrapping_add(*b))
            }
            ChecksumKind::XorPayload => payload.iter().fold(0, |acc, b| acc ^ b),
            ChecksumKind::ConstFc => CONST_CHECKSUM,
        }
    }
}

/// What a receiver accepts as a checksum.
///
/// Its names, used in configuration files and on the command line, are derived from the variants
/// (kebab-case): `sum`, `xor-payload`, `const-fc`, `ignore`. They drive `FromStr`, `Display`,
/// [`ChecksumPolicy::name`] and [`ChecksumPolicy::NAMES`].
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    Default,
    strum::EnumString,
    strum::Display,
    strum::IntoStaticStr,
    strum::VariantNames,
)]
#[strum(serialize_all = "kebab-case", parse_err_ty = ParsePolicyError, parse_err_fn = ParsePolicyError::unknown)]
pub enum ChecksumPolicy {
    /// Only the seed's sum (default).
    #[default]
    Sum,
    /// Only the XOR of the payload.
    XorPayload,
    /// Only the constant 0xFC.
    ConstFc,
    /// Anything: the firmware's own receivers never check.
    Ignore,
}

impl ChecksumPolicy {
    /// Every policy's name, in declaration order (for `--help` and error messages).
    pub const NAMES: &'static [&'static str] = <ChecksumPolicy as strum::VariantNames>::VARIANTS;

    /// The checksum kind this policy requires, `None` for `Ignore`.
    pub fn kind(self) -> Option<ChecksumKind> {
        match self {
            ChecksumPolicy::Sum => Some(ChecksumKind::Sum),
            ChecksumPolicy::XorPayload => Some(ChecksumKind::XorPayload),
            ChecksumPolicy::ConstFc => Some(ChecksumKind::ConstFc),
            ChecksumPolicy::Ignore => None,
        }
    }

    /// The name used in configuration files and on the command line.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// A checksum policy name that is not one of `sum`, `xor-payload`, `const-fc`, `ignore`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown checksum policy {input:?}: expected sum, xor-payload, const-fc or ignore")]
pub struct ParsePolicyError {
    /// The text given.
    pub input: String,
}

impl ParsePolicyError {
    fn unknown(input: &str) -> Self {
        ParsePolicyError { input: input.to_owned() }
    }
}

/// Errors from framing and parsing motor frames.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DecodeError {
    /// The buffer ends before the frame does.
    #[error("truncated frame: need {need} bytes, got {got}")]
    Truncated {
        /// Bytes the frame needs.
        need: usize,
        /// Bytes available.
        got: usize,
    },
    /// The first byte is not 0xAA.
    #[error("bad start byte {found:#04x}, expected 0xaa")]
    BadSync {
        /// The byte found.
        found: u8,
    },
    /// The checksum byte does not match the receiver's policy.
    #[error("bad checksum: expected {expected:#04x}, got {actual:#04x}")]
    BadChecksum {
        /// What the policy computes.
        expected: u8,
        /// What the frame carries.
        actual: u8,
    },
    /// A known type with a payload length it cannot have.
    #[error("bad length {actual} for packet type {packet_type:?}, expected one of {expected:?}")]
    BadLength {
        /// The packet type.
        packet_type: PacketType,
        /// Valid lengths for it.
        expected: &'static [u8],
        /// The `LEN` field.
        actual: u8,
    },
}

/// A read/write view of one motor frame over any byte buffer.
///
/// # Panics
/// Getters and setters index the buffer directly and panic if it is shorter than the field they
/// touch; [`Frame::check_len`] rules that out for getters, a buffer of
/// [`MotorPacket::buffer_len`] bytes for setters.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Frame<T> {
    /// Wraps a buffer without checking its length.
    pub const fn new_unchecked(buffer: T) -> Frame<T> {
        Frame { buffer }
    }

    /// Wraps a buffer after [`Frame::check_len`].
    pub fn new_checked(buffer: T) -> Result<Frame<T>, DecodeError> {
        let frame = Self::new_unchecked(buffer);
        frame.check_len()?;
        Ok(frame)
    }

    /// Checks that the buffer holds the header, `LEN` payload bytes and the checksum.
    pub fn check_len(&self) -> Result<(), DecodeError> {
        let got = self.buffer.as_ref().len();
        if got < field::OVERHEAD {
            return Err(DecodeError::Truncated { need: field::OVERHEAD, got });
        }
        let need = self.frame_len();
        if got < need {
            return Err(DecodeError::Truncated { need, got });
        }
        Ok(())
    }

    /// Gives the buffer back.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The start byte (0xAA in a valid frame).
    pub fn sync(&self) -> u8 {
        self.buffer.as_ref()[field::SYNC]
    }

    /// The `LEN` field: payload bytes.
    pub fn len(&self) -> u8 {
        self.buffer.as_ref()[field::LEN]
    }

    /// True when `LEN` is 0.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Total frame length, `LEN + 4`.
    pub fn frame_len(&self) -> usize {
        usize::from(self.len()) + field::OVERHEAD
    }

    /// The `TYPE` field.
    pub fn packet_type(&self) -> PacketType {
        PacketType::from(self.buffer.as_ref()[field::TYPE])
    }

    /// The payload bytes.
    pub fn payload(&self) -> &[u8] {
        &self.buffer.as_ref()[field::payload(self.len())]
    }

    /// The checksum byte as carried.
    pub fn checksum(&self) -> u8 {
        self.buffer.as_ref()[field::checksum(self.len())]
    }

    /// The checksum this frame's header and payload give under `kind`.
    pub fn compute_checksum(&self, kind: ChecksumKind) -> u8 {
        kind.compute(self.len(), u8::from(self.packet_type()), self.payload())
    }

    /// Checks the checksum byte against `policy`.
    pub fn verify_checksum(&self, policy: ChecksumPolicy) -> Result<(), DecodeError> {
        let Some(kind) = policy.kind() else {
            return Ok(());
        };
        let expected = self.compute_checksum(kind);
        let actual = self.checksum();
        if expected == actual { Ok(()) } else { Err(DecodeError::BadChecksum { expected, actual }) }
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Frame<T> {
    /// Writes the start byte.
    pub fn set_sync(&mut self, value: u8) {
        self.buffer.as_mut()[field::SYNC] = value;
    }

    /// Writes `LEN`.
    pub fn set_len(&mut self, len: u8) {
        self.buffer.as_mut()[field::LEN] = len;
    }

    /// Writes `TYPE`.
    pub fn set_packet_type(&mut self, packet_type: PacketType) {
        self.buffer.as_mut()[field::TYPE] = u8::from(packet_type);
    }

    /// The payload bytes, mutable (the range follows the current `LEN`).
    pub fn payload_mut(&mut self) -> &mut [u8] {
        let range = field::payload(self.len());
        &mut self.buffer.as_mut()[range]
    }

    /// Writes the checksum byte.
    pub fn set_checksum(&mut self, value: u8) {
        let at = field::checksum(self.len());
        self.buffer.as_mut()[at] = value;
    }

    /// Computes and writes the checksum byte (call after writing the payload).
    pub fn fill_checksum(&mut self, kind: ChecksumKind) {
        let value = self.compute_checksum(kind);
        self.set_checksum(value);
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Frame<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// A drive command from Carto to the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MotorCommand {
    /// TYPE 0x01: offset-binary axes (0x80 neutral, 0x00 full negative, 0xFF full positive).
    V1 {
        /// Strafe right.
        dir_x: u8,
        /// Forward.
        dir_y: u8,
        /// Speed scale `gear / 8` (0 stops, above 8 clamps on the board).
        gear: u8,
    },
    /// TYPE 0x10: signed percent setpoints, sent raw (the board clamps to ±100).
    V2 {
        /// Forward, %.
        vx: i8,
        /// Left, %.
        vy: i8,
        /// Counter-clockwise, %.
        omega: i8,
        /// Unused by the firmware.
        speed_ratio: u8,
        /// Reserved bytes, kept as sent.
        reserved: [u8; 2],
    },
}

impl MotorCommand {
    /// Neutral v1 command: both axes 0x80, gear 0.
    pub const NEUTRAL_V1: MotorCommand = MotorCommand::V1 { dir_x: 0x80, dir_y: 0x80, gear: 0 };
    /// Stop v2 command: every field 0.
    pub const STOP_V2: MotorCommand =
        MotorCommand::V2 { vx: 0, vy: 0, omega: 0, speed_ratio: 0, reserved: [0; 2] };

    /// The frame type carrying this command.
    pub fn packet_type(&self) -> PacketType {
        match self {
            MotorCommand::V1 { .. } => PacketType::DriveV1,
            MotorCommand::V2 { .. } => PacketType::DriveV2,
        }
    }
}

/// Which telemetry payload layout a [`Telemetry`] came in or goes out as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum TelemetryForm {
    /// 32 bytes: rpm and power (the seed's layout, our default).
    #[default]
    Motor32,
    /// 36 bytes: `motor_id`, 3 padding bytes, then rpm and power (later firmware).
    Motor36,
    /// 104 bytes: rpm, power, odometry, IMU (our optional extension).
    Complete104,
}

impl TelemetryForm {
    /// Payload length of this form.
    pub fn payload_len(self) -> u8 {
        match self {
            TelemetryForm::Motor32 => 32,
            TelemetryForm::Motor36 => 36,
            TelemetryForm::Complete104 => 104,
        }
    }

    /// The form with this payload length, if any.
    pub fn from_payload_len(len: u8) -> Option<TelemetryForm> {
        match len {
            32 => Some(TelemetryForm::Motor32),
            36 => Some(TelemetryForm::Motor36),
            104 => Some(TelemetryForm::Complete104),
            _ => None,
        }
    }
}

/// Telemetry from the board. Wheel order FL, FR, RL, RR.
///
/// Only the fields its `form` carries go on the wire; the others parse as `motor_id = 1` and
/// zeros.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Telemetry {
    /// Payload layout.
    pub form: TelemetryForm,
    /// Motor block id (36-byte form only; 1 otherwise).
    pub motor_id: u8,
    /// Wheel speeds, rpm.
    pub wheel_rpm: [f32; 4],
    /// Motor power, % (±100).
    pub motor_power: [f32; 4],
    /// x, y (m), θ (rad), vx, vy (m/s), ω (rad/s) — 104-byte form only.
    pub odometry: [f32; 6],
    /// accel\[3\] m/s², gyro\[3\] rad/s, mag\[3\] µT, roll, pitch, yaw rad — 104-byte form only.
    pub imu: [f32; 12],
}

impl Default for Telemetry {
    fn default() -> Self {
        Telemetry {
            form: TelemetryForm::Motor32,
            motor_id: 1,
            wheel_rpm: [0.0; 4],
            motor_power: [0.0; 4],
            odometry: [0.0; 6],
            imu: [0.0; 12],
        }
    }
}

impl Telemetry {
    /// A 32-byte-form record with these wheel speeds and powers.
    pub fn motor(wheel_rpm: [f32; 4], motor_power: [f32; 4]) -> Telemetry {
        Telemetry { wheel_rpm, motor_power, ..Telemetry::default() }
    }

    fn parse(payload: &[u8]) -> Option<Telemetry> {
        let len = u8::try_from(payload.len()).ok()?;
        let form = TelemetryForm::from_payload_len(len)?;
        let mut telemetry = Telemetry { form, ..Telemetry::default() };
        let motor = match form {
            TelemetryForm::Motor36 => {
                telemetry.motor_id = *payload.first()?;
                payload.get(4..36)?
            }
            TelemetryForm::Motor32 | TelemetryForm::Complete104 => payload.get(0..32)?,
        };
        read_f32_le(&motor[0..16], &mut telemetry.wheel_rpm);
        read_f32_le(&motor[16..32], &mut telemetry.motor_power);
        if form == TelemetryForm::Complete104 {
            read_f32_le(payload.get(32..56)?, &mut telemetry.odometry);
            read_f32_le(payload.get(56..104)?, &mut telemetry.imu);
        }
        Some(telemetry)
    }

    fn emit(&self, payload: &mut [u8]) {
        let motor = match self.form {
            TelemetryForm::Motor36 => {
                payload[0] = self.motor_id;
                payload[1..4].fill(0);
                &mut payload[4..36]
            }
            TelemetryForm::Motor32 | TelemetryForm::Complete104 => &mut payload[0..32],
        };
        write_f32_le(&self.wheel_rpm, &mut motor[0..16]);
        write_f32_le(&self.motor_power, &mut motor[16..32]);
        if self.form == TelemetryForm::Complete104 {
            write_f32_le(&self.odometry, &mut payload[32..56]);
            write_f32_le(&self.imu, &mut payload[56..104]);
        }
    }
}

fn read_f32_le(bytes: &[u8], out: &mut [f32]) {
    for (value, chunk) in out.iter_mut().zip(bytes.chunks_exact(4)) {
        *value = f32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
    }
}

fn write_f32_le(values: &[f32], bytes: &mut [u8]) {
    for (value, chunk) in values.iter().zip(bytes.chunks_exact_mut(4)) {
        chunk.copy_from_slice(&value.to_le_bytes());
    }
}

/// One motor-board packet: the typed representation of a frame.
#[derive(Debug, Clone, PartialEq)]
pub enum MotorPacket {
    /// A drive command (TYPE 0x01 or 0x10).
    Drive(MotorCommand),
    /// Telemetry (TYPE 0x04).
    Telemetry(Telemetry),
    /// A type this crate does not know, kept with its payload (emit truncates it to 255 bytes).
    Unknown {
        /// The `TYPE` byte.
        packet_type: u8,
        /// The payload.
        payload: Vec<u8>,
    },
}

impl MotorPacket {
    /// The `TYPE` this packet goes out as.
    pub fn packet_type(&self) -> PacketType {
        match self {
            MotorPacket::Drive(command) => command.packet_type(),
            MotorPacket::Telemetry(_) => PacketType::Telemetry,
            MotorPacket::Unknown { packet_type, .. } => PacketType::from(*packet_type),
        }
    }

    /// The `LEN` this packet goes out with.
    pub fn payload_len(&self) -> u8 {
        match self {
            MotorPacket::Drive(MotorCommand::V1 { .. }) => 3,
            MotorPacket::Drive(MotorCommand::V2 { .. }) => 6,
            MotorPacket::Telemetry(telemetry) => telemetry.form.payload_len(),
            MotorPacket::Unknown { payload, .. } => u8::try_from(payload.len()).unwrap_or(u8::MAX),
        }
    }

    /// Total frame length when emitted, `LEN + 4`.
    pub fn buffer_len(&self) -> usize {
        usize::from(self.payload_len()) + field::OVERHEAD
    }

    /// Parses a frame, checking its checksum against `policy`. Never panics.
    ///
    /// An unknown `TYPE` with an accepted checksum is `Ok(Unknown)`.
    pub fn parse<T: AsRef<[u8]> + ?Sized>(
        frame: &Frame<&T>,
        policy: ChecksumPolicy,
    ) -> Result<MotorPacket, DecodeError> {
        frame.check_len()?;
        if frame.sync() != SYNC {
            return Err(DecodeError::BadSync { found: frame.sync() });
        }
        frame.verify_checksum(policy)?;
        let packet_type = frame.packet_type();
        let payload = frame.payload();
        let bad_length = || DecodeError::BadLength {
            packet_type,
            expected: packet_type.valid_lengths(),
            actual: frame.len(),
        };
        match (packet_type, payload) {
            (PacketType::DriveV1, &[dir_x, dir_y, gear]) => {
                Ok(MotorPacket::Drive(MotorCommand::V1 { dir_x, dir_y, gear }))
            }
            (PacketType::DriveV2, &[vx, vy, omega, speed_ratio, r0, r1]) => {
                Ok(MotorPacket::Drive(MotorCommand::V2 {
                    vx: vx as i8,
                    vy: vy as i8,
                    omega: omega as i8,
                    speed_ratio,
                    reserved: [r0, r1],
                }))
            }
            (PacketType::Telemetry, _) => {
                Telemetry::parse(payload).map(MotorPacket::Telemetry).ok_or_else(bad_length)
            }
            (PacketType::Unknown(raw), _) => {
                Ok(MotorPacket::Unknown { packet_type: raw, payload: payload.to_vec() })
            }
            (PacketType::DriveV1 | PacketType::DriveV2, _) => Err(bad_length()),
        }
    }

    /// Writes the frame into the first [`MotorPacket::buffer_len`] bytes, checksum of `kind`.
    ///
    /// Never panics when the buffer is at least `buffer_len()` bytes long.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]> + ?Sized>(&self, frame: &mut Frame<&mut T>, kind: ChecksumKind) {
        let len = self.payload_len();
        frame.set_sync(SYNC);
        frame.set_len(len);
        frame.set_packet_type(self.packet_type());
        let payload = frame.payload_mut();
        match self {
            MotorPacket::Drive(MotorCommand::V1 { dir_x, dir_y, gear }) => {
                payload.copy_from_slice(&[*dir_x, *dir_y, *gear])
            }
            MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, speed_ratio, reserved }) => payload
                .copy_from_slice(&[
                    *vx as u8,
                    *vy as u8,
                    *omega as u8,
                    *speed_ratio,
                    reserved[0],
                    reserved[1],
                ]),
            MotorPacket::Telemetry(telemetry) => telemetry.emit(payload),
            MotorPacket::Unknown { payload: data, .. } => payload.copy_from_slice(&data[..usize::from(len)]),
        }
        frame.fill_checksum(kind);
    }

    /// The whole frame with the seed's sum checksum.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.to_bytes_with(ChecksumKind::Sum)
    }

    /// The whole frame with the given checksum kind.
    pub fn to_bytes_with(&self, kind: ChecksumKind) -> Vec<u8> {
        let mut buffer = vec![0; self.buffer_len()];
        self.emit(&mut Frame::new_unchecked(&mut buffer[..]), kind);
        buffer
    }
}

/// Counters kept by a [`Decoder`] since it was made.
///
/// Every byte fed ends up in exactly one place: a decoded frame, a rejected frame's start byte or
/// a skipped byte (both in `bytes_skipped`), or the pending buffer ([`Decoder::buffered`]). The
/// five counters shared with [`ResyncStats`] come from the engine; the others are the motor's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DecoderStats {
    /// Packets decoded (`Ok` items, `Unknown` included).
    pub frames: u64,
    /// Frames rejected (`Err` items), whatever the reason.
    pub errors: u64,
    /// Frames rejected for their checksum.
    pub checksum_errors: u64,
    /// Frames rejected for a payload length their type cannot have.
    pub length_errors: u64,
    /// `Unknown` packets among `frames`.
    pub unknown_types: u64,
    /// Bytes dropped while hunting for 0xAA, including the start byte of each rejected frame.
    pub bytes_skipped: u64,
    /// Bytes decoded as part of accepted frames.
    pub bytes_in_frames: u64,
    /// Bytes fed in total.
    pub bytes: u64,
}

impl From<DecoderStats> for ResyncStats {
    fn from(stats: DecoderStats) -> ResyncStats {
        let DecoderStats { frames, errors, bytes_skipped, bytes_in_frames, bytes, .. } = stats;
        ResyncStats { frames, errors, bytes_skipped, bytes_in_frames, bytes }
    }
}

/// The motor framing for the [`Resync`] engine: skip to the next 0xAA, wait for `LEN + 4` bytes,
/// parse with the checksum policy, report every rejection.
#[derive(Debug, Clone, Copy, Default)]
struct MotorFraming {
    policy: ChecksumPolicy,
}

impl resync::Framing for MotorFraming {
    type Frame = MotorPacket;
    type Error = DecodeError;
    const MAX_FRAME_LEN: usize = MAX_FRAME_LEN;
    const REPORT: Report = Report::EveryRejection;

    fn head(&self, bytes: &[u8]) -> Head<DecodeError> {
        if bytes.first() != Some(&SYNC) {
            return Head::Skip(bytes.iter().position(|b| *b == SYNC).unwrap_or(bytes.len()));
        }
        let Some(len) = bytes.get(field::LEN) else {
            return Head::Partial { need: field::LEN + 1 };
        };
        let total = usize::from(*len) + field::OVERHEAD;
        if bytes.len() >= total { Head::Complete(total) } else { Head::Partial { need: total } }
    }

    fn parse(&self, frame: &[u8]) -> Result<MotorPacket, DecodeError> {
        MotorPacket::parse(&Frame::new_unchecked(frame), self.policy)
    }
}

/// Sans-IO streaming decoder for motor frames: the shared [`Resync`] engine with the motor
/// framing, plus the motor's own counters.
///
/// Its buffer holds at most one candidate frame ([`MAX_FRAME_LEN`] bytes).
#[derive(Debug, Clone, Default)]
pub struct Decoder {
    engine: Resync<MotorFraming>,
    /// Only the motor's own counters are kept here; the rest come from `engine`.
    own: DecoderStats,
}

impl Decoder {
    /// A decoder checking checksums with `policy`.
    pub fn new(policy: ChecksumPolicy) -> Self {
        Decoder { engine: Resync::new(MotorFraming { policy }), own: DecoderStats::default() }
    }

    /// The checksum policy.
    pub fn policy(&self) -> ChecksumPolicy {
        self.engine.framing().policy
    }

    /// Consumes all of `bytes` and returns every packet or error they complete, in order.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Result<MotorPacket, DecodeError>> {
        let items = self.engine.feed(bytes);
        for item in &items {
            match item {
                Ok(MotorPacket::Unknown { .. }) => self.own.unknown_types += 1,
                Err(DecodeError::BadChecksum { .. }) => self.own.checksum_errors += 1,
                Err(DecodeError::BadLength { .. }) => self.own.length_errors += 1,
                _ => {}
            }
        }
        items
    }

    /// Counters since creation (not cleared by `reset`).
    pub fn stats(&self) -> DecoderStats {
        let ResyncStats { frames, errors, bytes_skipped, bytes_in_frames, bytes } = self.engine.stats();
        DecoderStats { frames, errors, bytes_skipped, bytes_in_frames, bytes, ..self.own }
    }

    /// Bytes of a candidate frame held, waiting for the rest.
    pub fn buffered(&self) -> usize {
        self.engine.buffered()
    }

    /// Drops any partial candidate.
    pub fn reset(&mut self) {
        self.engine.reset();
    }
}

impl_decoder!(Decoder, MotorPacket, DecodeError, DecoderStats);

#[cfg(test)]
mod tests {
    use super::*;

    // ── Golden frames: the seed's received-frame example and protocols-research.md §2.8.

    /// Seed 000: drive v1, neutral X and Y, gear 6.
    /// CK = 0x0A: (03 + 01 + 80 + 80 + 06) mod 256 = 0x10A mod 256 (seed example, §2.4).
    static SEED_DRIVE_V1: [u8; 7] = [0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x0A];
    /// §2.8: drive v2, vx +50, vy 0, omega −20, speed ratio 6.
    /// CK = 0x3A: sum 06+10+32+00+EC+06+00+00 = 0x13A (§2.8); XOR-of-payload would be 0xD8.
    static DRIVE_V2_FORWARD: [u8; 10] = [0xAA, 0x06, 0x10, 0x32, 0x00, 0xEC, 0x06, 0x00, 0x00, 0x3A];
    /// §2.8: drive v2, stop. CK = 0x16: sum 06 + 10 (§2.8).
    static DRIVE_V2_STOP: [u8; 10] = [0xAA, 0x06, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x16];
    /// §2.8: telemetry, 32-byte form, rpm [100, −100, 50.5, 0], power [25, −25, 12.5, 0].
    /// CK = 0x5F: sum (§2.8); the Arduino firmware would send 0xFC, the Zephyr one 0x01 (XOR).
    static TELEMETRY_32: [u8; 36] = [
        0xAA, 0x20, 0x04, //
        0x00, 0x00, 0xC8, 0x42, 0x00, 0x00, 0xC8, 0xC2, 0x00, 0x00, 0x4A, 0x42, 0x00, 0x00, 0x00,
        0x00, //
        0x00, 0x00, 0xC8, 0x41, 0x00, 0x00, 0xC8, 0xC1, 0x00, 0x00, 0x48, 0x41, 0x00, 0x00, 0x00,
        0x00, //
        0x5F,
    ];
    /// §2.8: telemetry, 36-byte form (motor id 1, 3 padding bytes), same values.
    /// CK = 0x64: sum (§2.8); XOR-of-payload would be 0x00.
    static TELEMETRY_36: [u8; 40] = [
        0xAA, 0x24, 0x04, 0x01, 0x00, 0x00, 0x00, //
        0x00, 0x00, 0xC8, 0x42, 0x00, 0x00, 0xC8, 0xC2, 0x00, 0x00, 0x4A, 0x42, 0x00, 0x00, 0x00,
        0x00, //
        0x00, 0x00, 0xC8, 0x41, 0x00, 0x00, 0xC8, 0xC1, 0x00, 0x00, 0x48, 0x41, 0x00, 0x00, 0x00,
        0x00, //
        0x64,
    ];

    const RPM: [f32; 4] = [100.0, -100.0, 50.5, 0.0];
    const POWER: [f32; 4] = [25.0, -25.0, 12.5, 0.0];

    fn golden() -> Vec<(&'static [u8], MotorPacket)> {
        vec![
            (&SEED_DRIVE_V1, MotorPacket::Drive(MotorCommand::V1 { dir_x: 0x80, dir_y: 0x80, gear: 6 })),
            (
                &DRIVE_V2_FORWARD,
                MotorPacket::Drive(MotorCommand::V2 {
                    vx: 50,
                    vy: 0,
                    omega: -20,
                    speed_ratio: 6,
                    reserved: [0, 0],
                }),
            ),
            (&DRIVE_V2_STOP, MotorPacket::Drive(MotorCommand::STOP_V2)),
            (&TELEMETRY_32, MotorPacket::Telemetry(Telemetry::motor(RPM, POWER))),
            (
                &TELEMETRY_36,
                MotorPacket::Telemetry(Telemetry {
                    form: TelemetryForm::Motor36,
                    ..Telemetry::motor(RPM, POWER)
                }),
            ),
        ]
    }

    #[test]
    fn test_deconstruct() {
        let frame = Frame::new_checked(&SEED_DRIVE_V1[..]).unwrap();
        assert_eq!(frame.sync(), 0xAA);
        assert_eq!(frame.len(), 3);
        assert_eq!(frame.frame_len(), 7);
        assert_eq!(frame.packet_type(), PacketType::DriveV1);
        assert_eq!(frame.payload(), &[0x80, 0x80, 0x06]);
        assert_eq!(frame.checksum(), 0x0A);
        assert_eq!(frame.compute_checksum(ChecksumKind::Sum), 0x0A);
        assert_eq!(frame.verify_checksum(ChecksumPolicy::Sum), Ok(()));

        let frame = Frame::new_checked(&TELEMETRY_36[..]).unwrap();
        assert_eq!(frame.len(), 36);
        assert_eq!(frame.packet_type(), PacketType::Telemetry);
        assert_eq!(frame.payload()[0], 0x01);
        assert_eq!(frame.checksum(), 0x64);
    }

    #[test]
    fn test_construct() {
        let mut bytes = vec![0xa5; 7];
        let mut frame = Frame::new_unchecked(&mut bytes);
        frame.set_sync(SYNC);
        frame.set_len(3);
        frame.set_packet_type(PacketType::DriveV1);
        frame.payload_mut().copy_from_slice(&[0x80, 0x80, 0x06]);
        frame.fill_checksum(ChecksumKind::Sum);
        assert_eq!(frame.into_inner(), &SEED_DRIVE_V1);
    }

    #[test]
    fn test_deconstruct_construct_every_golden_frame() {
        for (bytes, _) in golden() {
            let frame = Frame::new_checked(bytes).unwrap();
            let mut out = vec![0xa5; bytes.len()];
            let mut built = Frame::new_unchecked(&mut out);
            built.set_sync(frame.sync());
            built.set_len(frame.len());
            built.set_packet_type(frame.packet_type());
            built.payload_mut().copy_from_slice(frame.payload());
            built.fill_checksum(ChecksumKind::Sum);
            assert_eq!(&out[..], bytes);
        }
    }

    #[test]
    fn test_parse() {
        for (bytes, packet) in golden() {
            let frame = Frame::new_checked(bytes).unwrap();
            assert_eq!(MotorPacket::parse(&frame, ChecksumPolicy::Sum), Ok(packet), "{bytes:02x?}");
        }
    }

    #[test]
    fn test_emit() {
        for (bytes, packet) in golden() {
            assert_eq!(packet.buffer_len(), bytes.len());
            let mut out = vec![0xa5; packet.buffer_len()];
            packet.emit(&mut Frame::new_unchecked(&mut out), ChecksumKind::Sum);
            assert_eq!(&out[..], bytes, "{packet:?}");
            assert_eq!(packet.to_bytes(), bytes);
        }
    }

    #[test]
    fn test_firmware_checksum_variants() {
        // §2.8: the XOR-of-payload byte of each frame, and the Arduino constant.
        let cases: [(&[u8], u8); 4] =
            [(&DRIVE_V2_FORWARD, 0xD8), (&DRIVE_V2_STOP, 0x00), (&TELEMETRY_32, 0x01), (&TELEMETRY_36, 0x00)];
        for (bytes, xor) in cases {
            let packet =
                MotorPacket::parse(&Frame::new_checked(bytes).unwrap(), ChecksumPolicy::Sum).unwrap();
            let as_xor = packet.to_bytes_with(ChecksumKind::XorPayload);
            assert_eq!(as_xor.last(), Some(&xor));
            let as_fc = packet.to_bytes_with(ChecksumKind::ConstFc);
            assert_eq!(as_fc.last(), Some(&0xFC));

            let xor_frame = Frame::new_checked(&as_xor[..]).unwrap();
            assert_eq!(MotorPacket::parse(&xor_frame, ChecksumPolicy::XorPayload), Ok(packet.clone()));
            assert_eq!(MotorPacket::parse(&xor_frame, ChecksumPolicy::Ignore), Ok(packet.clone()));
            let fc_frame = Frame::new_checked(&as_fc[..]).unwrap();
            assert_eq!(MotorPacket::parse(&fc_frame, ChecksumPolicy::ConstFc), Ok(packet.clone()));
            assert_eq!(
                MotorPacket::parse(&fc_frame, ChecksumPolicy::Sum),
                Err(DecodeError::BadChecksum { expected: *bytes.last().unwrap(), actual: 0xFC })
            );
        }
    }

    #[test]
    fn test_bad_checksum_carries_both_bytes() {
        let mut bytes = SEED_DRIVE_V1;
        bytes[6] = 0x0B;
        let error =
            MotorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap(), ChecksumPolicy::Sum).unwrap_err();
        assert_eq!(error, DecodeError::BadChecksum { expected: 0x0A, actual: 0x0B });
        assert_eq!(error.to_string(), "bad checksum: expected 0x0a, got 0x0b");
    }

    #[test]
    fn test_bad_lengths() {
        // Drive v2 with LEN 3 (what the Arduino receiver would accept). CK = 03+10+01+02+03.
        let bytes = [0xAA, 0x03, 0x10, 0x01, 0x02, 0x03, 0x19];
        assert_eq!(
            MotorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap(), ChecksumPolicy::Sum),
            Err(DecodeError::BadLength { packet_type: PacketType::DriveV2, expected: &[6], actual: 3 })
        );
        // Telemetry with LEN 4. CK = 04+04.
        let bytes = [0xAA, 0x04, 0x04, 0x00, 0x00, 0x00, 0x00, 0x08];
        assert_eq!(
            MotorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap(), ChecksumPolicy::Sum),
            Err(DecodeError::BadLength {
                packet_type: PacketType::Telemetry,
                expected: TELEMETRY_LENGTHS,
                actual: 4
            })
        );
    }

    #[test]
    fn test_unknown_type_keeps_payload() {
        // CK = 02 + 42 + 01 + 02.
        let bytes = [0xAA, 0x02, 0x42, 0x01, 0x02, 0x47];
        let packet =
            MotorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap(), ChecksumPolicy::Sum).unwrap();
        assert_eq!(packet, MotorPacket::Unknown { packet_type: 0x42, payload: vec![1, 2] });
        assert_eq!(packet.to_bytes(), bytes);
        assert_eq!(PacketType::from(0x42), PacketType::Unknown(0x42));
        assert_eq!(u8::from(PacketType::DriveV2), 0x10);
    }

    #[test]
    fn test_check_len_and_sync_errors() {
        assert_eq!(
            Frame::new_checked(&[0xAA, 0x03, 0x01][..]),
            Err(DecodeError::Truncated { need: 4, got: 3 })
        );
        assert_eq!(Frame::new_checked(&SEED_DRIVE_V1[..6]), Err(DecodeError::Truncated { need: 7, got: 6 }));
        let mut bytes = SEED_DRIVE_V1;
        bytes[0] = 0x55;
        assert_eq!(
            MotorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap(), ChecksumPolicy::Sum),
            Err(DecodeError::BadSync { found: 0x55 })
        );
        assert_eq!(
            MotorPacket::parse(&Frame::new_unchecked(&[0xAA][..]), ChecksumPolicy::Sum),
            Err(DecodeError::Truncated { need: 4, got: 1 })
        );
    }

    #[test]
    fn test_telemetry_104_round_trip() {
        let mut telemetry = Telemetry::motor(RPM, POWER);
        telemetry.form = TelemetryForm::Complete104;
        telemetry.odometry = [1.0, 2.0, 0.5, 0.1, -0.1, 0.25];
        telemetry.imu = [0.0, 0.0, 9.81, 0.01, 0.02, 0.03, 20.0, -5.0, 40.0, 0.1, 0.2, 3.0];
        let packet = MotorPacket::Telemetry(telemetry);
        let bytes = packet.to_bytes();
        assert_eq!(bytes.len(), 108);
        assert_eq!(&bytes[..3], &[0xAA, 104, 0x04]);
        // The motor block is laid out as in the 32-byte form.
        assert_eq!(&bytes[3..35], &TELEMETRY_32[3..35]);
        // Odometry x = 1.0 little-endian right after it.
        assert_eq!(&bytes[35..39], &[0x00, 0x00, 0x80, 0x3F]);
        let parsed = MotorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap(), ChecksumPolicy::Sum);
        assert_eq!(parsed, Ok(packet));
    }

    #[test]
    fn test_policy_names_round_trip() {
        for policy in
            [ChecksumPolicy::Sum, ChecksumPolicy::XorPayload, ChecksumPolicy::ConstFc, ChecksumPolicy::Ignore]
        {
            assert_eq!(policy.to_string().parse::<ChecksumPolicy>(), Ok(policy));
        }
        assert_eq!("sum".parse(), Ok(ChecksumPolicy::Sum));
        assert_eq!("xor-payload".parse(), Ok(ChecksumPolicy::XorPayload));
        assert_eq!("const-fc".parse(), Ok(ChecksumPolicy::ConstFc));
        assert_eq!("ignore".parse(), Ok(ChecksumPolicy::Ignore));
        assert_eq!("crc".parse::<ChecksumPolicy>(), Err(ParsePolicyError { input: "crc".to_owned() }));
        assert_eq!(ChecksumPolicy::default(), ChecksumPolicy::Sum);
    }

    #[test]
    fn test_decoder_errors_count_every_rejected_frame() {
        let mut bad_checksum = SEED_DRIVE_V1;
        bad_checksum[6] = 0x0B;
        // Drive v2 with LEN 3. CK = 03+10+01+02+03 (see `test_bad_lengths`).
        let bad_length = [0xAA, 0x03, 0x10, 0x01, 0x02, 0x03, 0x19];
        let stream = [&bad_checksum[..], &bad_length, &SEED_DRIVE_V1].concat();
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let out = decoder.feed(&stream);
        assert_eq!(out.iter().filter(|item| item.is_err()).count(), 2, "{out:?}");
        let stats = decoder.stats();
        assert_eq!((stats.errors, stats.checksum_errors, stats.length_errors, stats.frames), (2, 1, 1, 1));
        assert_eq!(
            ResyncStats::from(stats),
            ResyncStats { frames: 1, errors: 2, bytes_skipped: 14, bytes_in_frames: 7, bytes: 21 }
        );
    }

    #[test]
    fn test_decoder_finds_good_frame_hidden_inside_a_corrupted_one() {
        // A false start `AA 10` announces 20 bytes; the seed frame sits inside them.
        let mut stream = vec![0xAA, 0x10];
        stream.extend_from_slice(&SEED_DRIVE_V1);
        stream.extend_from_slice(&[0x00; 14]); // completes the false frame (bad checksum)
        let mut decoder = Decoder::new(ChecksumPolicy::Sum);
        let out = decoder.feed(&stream);
        assert!(matches!(out[0], Err(DecodeError::BadChecksum { .. })), "{out:?}");
        assert_eq!(out[1], Ok(golden()[0].1.clone()));
        assert_eq!(out.len(), 2);
        let stats = decoder.stats();
        assert_eq!(stats.checksum_errors, 1);
        assert_eq!(stats.frames, 1);
        assert_eq!(stats.bytes, stats.bytes_in_frames + stats.bytes_skipped + decoder.buffered() as u64);
    }
}
