//! `sensor`: the Carto ⇄ sensor board protocol over UART, 9600 8N1 (seed 004, FRC 5190).
//!
//! No sync byte, no checksum; every multi-byte field is **big-endian** (u16, i16, i32, f32).
//!
//! ```text
//! ┌────────┬───────┬───────┬──────────────────────────────┬──────┐
//! │ offset │ bytes │ field │ meaning                      │ unit │
//! ├────────┼───────┼───────┼──────────────────────────────┼──────┤
//! │ 0      │ 1     │ TYPE  │ 1 keep-state, 2 command, 3 sensor data │ u8 │
//! │ 1      │ 1     │ LEN   │ DATA bytes                   │ u8   │
//! │ 2      │ LEN   │ DATA  │ per type, below              │ —    │
//! └────────┴───────┴───────┴──────────────────────────────┴──────┘
//! TYPE 1 keep-state, LEN 3          TYPE 2 command, LEN 3
//! ┌────────┬───────┬──────────┬────────┐  ┌────────┬───────┬───────────┬────────┐
//! │ 2      │ 1     │ status   │ u8     │  │ 2      │ 1     │ id        │ u8     │
//! │ 3      │ 2     │ sequence │ u16 BE │  │ 3      │ 2     │ parameter │ i16 BE │
//! └────────┴───────┴──────────┴────────┘  └────────┴───────┴───────────┴────────┘
//! TYPE 3 sensor data, LEN 4 + data_len
//! ┌────────┬──────────┬───────────────┬──────────────────────────────┐
//! │ offset │ bytes    │ field         │ unit                         │
//! │ 2      │ 1        │ sensor_type   │ u8 (1 NavX … 5 switch)       │
//! │ 3      │ 1        │ sensor_id     │ u8                           │
//! │ 4      │ 1        │ sensor_status │ u8 (1 operational, 2 error)  │
//! │ 5      │ 1        │ data_len      │ u8, fixed by sensor_type     │
//! │ 6      │ data_len │ sensor data   │ below                        │
//! └────────┴──────────┴───────────────┴──────────────────────────────┘
//! sensor data by sensor_type
//! ┌───────────────────┬──────────┬─────────────────────────────────────────────────────────┐
//! │ sensor_type       │ data_len │ layout                                                  │
//! │ 1 NavX            │ 36       │ altitude, pressure, heading °, temperature, accel x/y/z, mag x/y: 9 × f32 BE │
//! │ 2 encoder         │ 5        │ count i32 BE, direction u8 (1 forward, 2 reverse)       │
//! │ 3 potentiometer   │ 4        │ angle f32 BE                                            │
//! │ 4 distance        │ 4        │ cm f32 BE (−1.0 = no echo)                              │
//! │ 5 switch          │ 1        │ u8 (1 pressed, 2 released)                              │
//! └───────────────────┴──────────┴─────────────────────────────────────────────────────────┘
//! ```
//!
//! **Contract.** [`Frame::check_len`] proves every getter in bounds for the frame's type;
//! [`SensorPacket::parse`] never panics (it calls `check_len` itself); [`SensorPacket::emit`]
//! never panics when the buffer is at least [`SensorPacket::buffer_len`] bytes.
//!
//! **Streaming and what recovery is possible.** Without a sync byte or checksum, the only
//! evidence of framing is the header's consistency. [`Decoder`] is the shared [`Resync`] engine
//! with the sensor framing: it accepts a candidate at the current position when TYPE is 1 or 2
//! with LEN 3, or TYPE 3 with a known sensor type, LEN = 4 + data_len and the data_len byte equal
//! to that sensor type's length (so no valid frame is longer than 42 bytes, the decoder's whole
//! buffer). Otherwise it drops **one** byte and retries at the
//! next position. Field *values* are not checked (unknown status, command id, direction or switch
//! state are kept as `Unknown`).
//!
//! - A stream that starts on a frame boundary and loses no byte is decoded exactly, whatever the
//!   chunking.
//! - After garbage or a lost byte, the decoder realigns at the first position where a consistent
//!   header starts. If the garbage's tail and the next real frame's head happen to form one (e.g.
//!   a stray `01 03`), a false frame is accepted and the real one lost. The guarantee is narrow
//!   and exact: **a valid frame is decoded if the decoder holds no pending bytes when it starts**
//!   ([`Decoder::buffered`] is 0). That holds after any whole frame it accepted, and after
//!   garbage containing no 1, 2 or 3 byte (no byte that could begin a frame).
//! - Errors are reported once per loss of sync: the first rejected byte yields one `Err` (its
//!   reason), further drops only count in [`DecoderStats::bytes_skipped`] until a frame is
//!   accepted again.
//!
//! ```
//! use protocol::sensor::{Decoder, SensorPacket, SensorReading, SensorStatus, SensorValue};
//!
//! let distance = SensorPacket::Reading(SensorReading {
//!     sensor_id: 1,
//!     status: SensorStatus::Operational,
//!     value: SensorValue::Distance { cm: 123.25 },
//! });
//! assert_eq!(distance.to_bytes(), [0x03, 0x08, 0x04, 0x01, 0x01, 0x04, 0x42, 0xF6, 0x80, 0x00]);
//!
//! let mut decoder = Decoder::new();
//! let mut stream = vec![0xEE, 0x42]; // bytes that cannot start a frame
//! stream.extend(distance.to_bytes());
//! let items = decoder.feed(&stream);
//! assert_eq!(items.len(), 2); // one error for the lost sync, then the reading
//! assert_eq!(items[1], Ok(distance));
//! assert_eq!(decoder.stats().bytes_skipped, 2);
//! ```

use crate::resync::{self, Head, Report, Resync, ResyncStats};

/// Byte ranges of the sensor frame.
pub mod field {
    use crate::{Field, Rest};

    /// Packet type.
    pub const TYPE: usize = 0;
    /// DATA length.
    pub const LEN: usize = 1;
    /// DATA, to the end of the frame.
    pub const DATA: Rest = 2..;
    /// Bytes before DATA.
    pub const HEADER_LEN: usize = 2;

    /// Keep-state: status.
    pub const STATUS: usize = 2;
    /// Keep-state: sequence, u16 BE.
    pub const SEQUENCE: Field = 3..5;
    /// Command: id.
    pub const COMMAND_ID: usize = 2;
    /// Command: parameter, i16 BE.
    pub const PARAMETER: Field = 3..5;
    /// Sensor data: sensor type.
    pub const SENSOR_TYPE: usize = 2;
    /// Sensor data: sensor id.
    pub const SENSOR_ID: usize = 3;
    /// Sensor data: sensor status.
    pub const SENSOR_STATUS: usize = 4;
    /// Sensor data: data length.
    pub const DATA_LEN: usize = 5;
    /// Sensor data: the readings, to the end of the frame.
    pub const SENSOR_DATA: Rest = 6..;
    /// Sensor data: bytes of DATA before the readings.
    pub const SENSOR_HEADER_LEN: u8 = 4;

    /// The DATA range for a given `LEN`.
    pub const fn data(len: u8) -> Field {
        HEADER_LEN..HEADER_LEN + len as usize
    }

    /// The readings range for a given `data_len`.
    pub const fn sensor_data(data_len: u8) -> Field {
        6..6 + data_len as usize
    }
}

/// DATA length of keep-state and command frames.
pub const FIXED_LEN: u8 = 3;
/// The longest valid frame (NavX: 2 + 4 + 36).
pub const MAX_FRAME_LEN: usize = 42;

enum_with_unknown! {
    /// The `TYPE` byte.
    pub enum PacketType(u8) {
        /// 1: keep-state (heartbeat).
        KeepState = 1,
        /// 2: command to the board.
        Command = 2,
        /// 3: one sensor reading.
        SensorData = 3,
    }
}

enum_with_unknown! {
    /// The sensor type of a sensor-data frame.
    pub enum SensorType(u8) {
        /// 1: NavX IMU, 36 bytes.
        NavX = 1,
        /// 2: wheel encoder, 5 bytes.
        Encoder = 2,
        /// 3: potentiometer, 4 bytes.
        Potentiometer = 3,
        /// 4: distance (ultrasound), 4 bytes.
        Distance = 4,
        /// 5: switch (bumper), 1 byte.
        Switch = 5,
    }
}

impl SensorType {
    /// The fixed `data_len` of this sensor type, `None` if unknown.
    pub fn data_len(self) -> Option<u8> {
        match self {
            SensorType::NavX => Some(36),
            SensorType::Encoder => Some(5),
            SensorType::Potentiometer | SensorType::Distance => Some(4),
            SensorType::Switch => Some(1),
            SensorType::Unknown(_) => None,
        }
    }
}

enum_with_unknown! {
    /// Health of one sensor.
    pub enum SensorStatus(u8) {
        /// 1: working.
        Operational = 1,
        /// 2: failed.
        Error = 2,
    }
}

enum_with_unknown! {
    /// Command ids (ours; the seed defines none).
    pub enum CommandId(u8) {
        /// 1: set the distance sampling period, parameter in ms.
        SetDistancePeriod = 1,
        /// 2: reset the encoder counts.
        ResetEncoders = 2,
        /// 3: zero the heading.
        ZeroHeading = 3,
    }
}

enum_with_unknown! {
    /// Direction byte of an encoder reading.
    pub enum EncoderDirection(u8) {
        /// 1: forward.
        Forward = 1,
        /// 2: reverse.
        Reverse = 2,
    }
}

enum_with_unknown! {
    /// Value of a switch reading.
    pub enum SwitchState(u8) {
        /// 1: pressed (the seed's "on").
        Pressed = 1,
        /// 2: released (the seed's "off").
        Released = 2,
    }
}

/// Errors from framing and parsing sensor frames.
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
    /// `TYPE` is not 1, 2 or 3.
    #[error("unknown packet type {raw}")]
    UnknownType {
        /// The `TYPE` byte.
        raw: u8,
    },
    /// `LEN` does not fit the type (and, for sensor data, the sensor type).
    #[error("bad length {actual} for packet type {packet_type:?}, expected {expected}")]
    BadLength {
        /// The packet type.
        packet_type: PacketType,
        /// The `LEN` this frame needs.
        expected: u8,
        /// The `LEN` field.
        actual: u8,
    },
    /// The sensor type is not 1..=5.
    #[error("unknown sensor type {raw}")]
    UnknownSensorType {
        /// The sensor type byte.
        raw: u8,
    },
    /// `data_len` does not match the sensor type.
    #[error("bad data length {actual} for sensor type {sensor_type:?}, expected {expected}")]
    BadDataLength {
        /// The sensor type.
        sensor_type: SensorType,
        /// Its fixed data length.
        expected: u8,
        /// The `data_len` field.
        actual: u8,
    },
}

/// A read/write view of one sensor frame over any byte buffer.
///
/// # Panics
/// Getters and setters index the buffer directly and panic if it is shorter than the field they
/// touch; [`Frame::check_len`] rules that out for the getters of the frame's own type, a buffer
/// of [`SensorPacket::buffer_len`] bytes for setters.
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

    /// Checks that the buffer holds the whole frame and that `LEN` covers the fixed fields of
    /// the frame's type (3 bytes for keep-state and command; 4 + `data_len` for sensor data).
    ///
    /// Unknown types pass (only their DATA is readable). Exact lengths are `parse`'s concern.
    pub fn check_len(&self) -> Result<(), DecodeError> {
        let got = self.buffer.as_ref().len();
        if got < field::HEADER_LEN {
            return Err(DecodeError::Truncated { need: field::HEADER_LEN, got });
        }
        let need = self.frame_len();
        if got < need {
            return Err(DecodeError::Truncated { need, got });
        }
        let packet_type = self.packet_type();
        let actual = self.len();
        let expected = match packet_type {
            PacketType::KeepState | PacketType::Command => FIXED_LEN,
            PacketType::SensorData if actual < field::SENSOR_HEADER_LEN => field::SENSOR_HEADER_LEN,
            PacketType::SensorData => field::SENSOR_HEADER_LEN.saturating_add(self.data_len()),
            PacketType::Unknown(_) => 0,
        };
        if actual < expected {
            return Err(DecodeError::BadLength { packet_type, expected, actual });
        }
        Ok(())
    }

    /// Gives the buffer back.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// The `TYPE` field.
    pub fn packet_type(&self) -> PacketType {
        PacketType::from(self.buffer.as_ref()[field::TYPE])
    }

    /// The `LEN` field: DATA bytes.
    pub fn len(&self) -> u8 {
        self.buffer.as_ref()[field::LEN]
    }

    /// True when `LEN` is 0.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Total frame length, `LEN + 2`.
    pub fn frame_len(&self) -> usize {
        usize::from(self.len()) + field::HEADER_LEN
    }

    /// The DATA bytes.
    pub fn data(&self) -> &[u8] {
        &self.buffer.as_ref()[field::data(self.len())]
    }

    /// Keep-state: status byte.
    pub fn status(&self) -> u8 {
        self.buffer.as_ref()[field::STATUS]
    }

    /// Keep-state: sequence number.
    pub fn sequence(&self) -> u16 {
        let b = &self.buffer.as_ref()[field::SEQUENCE];
        u16::from_be_bytes([b[0], b[1]])
    }

    /// Command: id.
    pub fn command_id(&self) -> CommandId {
        CommandId::from(self.buffer.as_ref()[field::COMMAND_ID])
    }

    /// Command: parameter.
    pub fn parameter(&self) -> i16 {
        let b = &self.buffer.as_ref()[field::PARAMETER];
        i16::from_be_bytes([b[0], b[1]])
    }

    /// Sensor data: sensor type.
    pub fn sensor_type(&self) -> SensorType {
        SensorType::from(self.buffer.as_ref()[field::SENSOR_TYPE])
    }

    /// Sensor data: sensor id.
    pub fn sensor_id(&self) -> u8 {
        self.buffer.as_ref()[field::SENSOR_ID]
    }

    /// Sensor data: sensor status.
    pub fn sensor_status(&self) -> SensorStatus {
        SensorStatus::from(self.buffer.as_ref()[field::SENSOR_STATUS])
    }

    /// Sensor data: the `data_len` field.
    pub fn data_len(&self) -> u8 {
        self.buffer.as_ref()[field::DATA_LEN]
    }

    /// Sensor data: the reading bytes (`data_len` of them).
    pub fn sensor_data(&self) -> &[u8] {
        &self.buffer.as_ref()[field::sensor_data(self.data_len())]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Frame<T> {
    /// Writes `TYPE`.
    pub fn set_packet_type(&mut self, packet_type: PacketType) {
        self.buffer.as_mut()[field::TYPE] = u8::from(packet_type);
    }

    /// Writes `LEN`.
    pub fn set_len(&mut self, len: u8) {
        self.buffer.as_mut()[field::LEN] = len;
    }

    /// The DATA bytes, mutable (the range follows the current `LEN`).
    pub fn data_mut(&mut self) -> &mut [u8] {
        let range = field::data(self.len());
        &mut self.buffer.as_mut()[range]
    }

    /// Keep-state: writes the status byte.
    pub fn set_status(&mut self, status: u8) {
        self.buffer.as_mut()[field::STATUS] = status;
    }

    /// Keep-state: writes the sequence number.
    pub fn set_sequence(&mut self, sequence: u16) {
        self.buffer.as_mut()[field::SEQUENCE].copy_from_slice(&sequence.to_be_bytes());
    }

    /// Command: writes the id.
    pub fn set_command_id(&mut self, id: CommandId) {
        self.buffer.as_mut()[field::COMMAND_ID] = u8::from(id);
    }

    /// Command: writes the parameter.
    pub fn set_parameter(&mut self, parameter: i16) {
        self.buffer.as_mut()[field::PARAMETER].copy_from_slice(&parameter.to_be_bytes());
    }

    /// Sensor data: writes the sensor type.
    pub fn set_sensor_type(&mut self, sensor_type: SensorType) {
        self.buffer.as_mut()[field::SENSOR_TYPE] = u8::from(sensor_type);
    }

    /// Sensor data: writes the sensor id.
    pub fn set_sensor_id(&mut self, id: u8) {
        self.buffer.as_mut()[field::SENSOR_ID] = id;
    }

    /// Sensor data: writes the sensor status.
    pub fn set_sensor_status(&mut self, status: SensorStatus) {
        self.buffer.as_mut()[field::SENSOR_STATUS] = u8::from(status);
    }

    /// Sensor data: writes `data_len`.
    pub fn set_data_len(&mut self, data_len: u8) {
        self.buffer.as_mut()[field::DATA_LEN] = data_len;
    }

    /// Sensor data: the reading bytes, mutable (the range follows the current `data_len`).
    pub fn sensor_data_mut(&mut self) -> &mut [u8] {
        let range = field::sensor_data(self.data_len());
        &mut self.buffer.as_mut()[range]
    }
}

impl<T: AsRef<[u8]>> AsRef<[u8]> for Frame<T> {
    fn as_ref(&self) -> &[u8] {
        self.buffer.as_ref()
    }
}

/// A NavX IMU reading.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NavX {
    /// Altitude, m.
    pub altitude: f32,
    /// Barometric pressure, mbar.
    pub pressure: f32,
    /// Fused heading, degrees 0–360, clockwise.
    pub heading_deg: f32,
    /// Temperature, °C.
    pub temperature: f32,
    /// Linear acceleration x, y, z, in g.
    pub accel: [f32; 3],
    /// Magnetometer x, y.
    pub mag: [f32; 2],
}

impl NavX {
    fn to_array(self) -> [f32; 9] {
        let [ax, ay, az] = self.accel;
        let [mx, my] = self.mag;
        [self.altitude, self.pressure, self.heading_deg, self.temperature, ax, ay, az, mx, my]
    }

    fn from_array(v: [f32; 9]) -> NavX {
        let [altitude, pressure, heading_deg, temperature, ax, ay, az, mx, my] = v;
        NavX { altitude, pressure, heading_deg, temperature, accel: [ax, ay, az], mag: [mx, my] }
    }
}

/// The value carried by a sensor-data frame; its variant fixes the sensor type.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorValue {
    /// Sensor type 1.
    NavX(NavX),
    /// Sensor type 2.
    Encoder {
        /// Signed tick count.
        count: i32,
        /// Direction byte.
        direction: EncoderDirection,
    },
    /// Sensor type 3.
    Potentiometer {
        /// Angle.
        angle: f32,
    },
    /// Sensor type 4.
    Distance {
        /// Distance, cm; −1.0 means no echo.
        cm: f32,
    },
    /// Sensor type 5.
    Switch(SwitchState),
}

impl SensorValue {
    /// The sensor type this value goes out as.
    pub fn sensor_type(&self) -> SensorType {
        match self {
            SensorValue::NavX(_) => SensorType::NavX,
            SensorValue::Encoder { .. } => SensorType::Encoder,
            SensorValue::Potentiometer { .. } => SensorType::Potentiometer,
            SensorValue::Distance { .. } => SensorType::Distance,
            SensorValue::Switch(_) => SensorType::Switch,
        }
    }

    /// Its `data_len`.
    pub fn data_len(&self) -> u8 {
        self.sensor_type().data_len().unwrap_or_default()
    }

    fn parse(sensor_type: SensorType, data: &[u8]) -> Option<SensorValue> {
        Some(match sensor_type {
            SensorType::NavX => {
                let mut values = [0.0; 9];
                for (value, chunk) in values.iter_mut().zip(data.get(..36)?.chunks_exact(4)) {
                    *value = f32::from_be_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
                }
                SensorValue::NavX(NavX::from_array(values))
            }
            SensorType::Encoder => match *data {
                [a, b, c, d, direction] => SensorValue::Encoder {
                    count: i32::from_be_bytes([a, b, c, d]),
                    direction: EncoderDirection::from(direction),
                },
                _ => return None,
            },
            SensorType::Potentiometer => {
                SensorValue::Potentiometer { angle: f32::from_be_bytes(data.try_into().ok()?) }
            }
            SensorType::Distance => SensorValue::Distance { cm: f32::from_be_bytes(data.try_into().ok()?) },
            SensorType::Switch => match *data {
                [state] => SensorValue::Switch(SwitchState::from(state)),
                _ => return None,
            },
            SensorType::Unknown(_) => return None,
        })
    }

    fn emit(&self, data: &mut [u8]) {
        match self {
            SensorValue::NavX(navx) => {
                for (value, chunk) in navx.to_array().iter().zip(data.chunks_exact_mut(4)) {
                    chunk.copy_from_slice(&value.to_be_bytes());
                }
            }
            SensorValue::Encoder { count, direction } => {
                data[..4].copy_from_slice(&count.to_be_bytes());
                data[4] = u8::from(*direction);
            }
            SensorValue::Potentiometer { angle: value } | SensorValue::Distance { cm: value } => {
                data.copy_from_slice(&value.to_be_bytes())
            }
            SensorValue::Switch(state) => data[0] = u8::from(*state),
        }
    }
}

/// One sensor reading (a type-3 frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorReading {
    /// Tells apart sensors of the same type (encoders 1–4 = FL, FR, RL, RR).
    pub sensor_id: u8,
    /// Sensor health.
    pub status: SensorStatus,
    /// The reading.
    pub value: SensorValue,
}

/// One sensor-board packet: the typed representation of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorPacket {
    /// TYPE 1: heartbeat. The board sends status 1, Carto status 2.
    KeepState {
        /// 1 = board, 2 = Carto (raw).
        status: u8,
        /// Starts at 1, wraps to 0 after 0xFFFF.
        sequence: u16,
    },
    /// TYPE 2: a command to the board.
    Command {
        /// Which command.
        id: CommandId,
        /// Its argument.
        parameter: i16,
    },
    /// TYPE 3: one sensor reading.
    Reading(SensorReading),
}

impl SensorPacket {
    /// The `TYPE` this packet goes out as.
    pub fn packet_type(&self) -> PacketType {
        match self {
            SensorPacket::KeepState { .. } => PacketType::KeepState,
            SensorPacket::Command { .. } => PacketType::Command,
            SensorPacket::Reading(_) => PacketType::SensorData,
        }
    }

    /// The `LEN` this packet goes out with.
    pub fn data_len(&self) -> u8 {
        match self {
            SensorPacket::KeepState { .. } | SensorPacket::Command { .. } => FIXED_LEN,
            SensorPacket::Reading(reading) => field::SENSOR_HEADER_LEN + reading.value.data_len(),
        }
    }

    /// Total frame length when emitted, `LEN + 2`.
    pub fn buffer_len(&self) -> usize {
        usize::from(self.data_len()) + field::HEADER_LEN
    }

    /// Parses a frame, requiring the exact length of its type. Never panics.
    pub fn parse<T: AsRef<[u8]> + ?Sized>(frame: &Frame<&T>) -> Result<SensorPacket, DecodeError> {
        frame.check_len()?;
        let packet_type = frame.packet_type();
        let actual = frame.len();
        let exact = |expected: u8| {
            if actual == expected {
                Ok(())
            } else {
                Err(DecodeError::BadLength { packet_type, expected, actual })
            }
        };
        match packet_type {
            PacketType::KeepState => {
                exact(FIXED_LEN)?;
                Ok(SensorPacket::KeepState { status: frame.status(), sequence: frame.sequence() })
            }
            PacketType::Command => {
                exact(FIXED_LEN)?;
                Ok(SensorPacket::Command { id: frame.command_id(), parameter: frame.parameter() })
            }
            PacketType::SensorData => {
                let sensor_type = frame.sensor_type();
                let Some(expected) = sensor_type.data_len() else {
                    return Err(DecodeError::UnknownSensorType { raw: u8::from(sensor_type) });
                };
                exact(field::SENSOR_HEADER_LEN + expected)?;
                if frame.data_len() != expected {
                    return Err(DecodeError::BadDataLength {
                        sensor_type,
                        expected,
                        actual: frame.data_len(),
                    });
                }
                let value = SensorValue::parse(sensor_type, frame.sensor_data())
                    .ok_or(DecodeError::BadDataLength { sensor_type, expected, actual: frame.data_len() })?;
                Ok(SensorPacket::Reading(SensorReading {
                    sensor_id: frame.sensor_id(),
                    status: frame.sensor_status(),
                    value,
                }))
            }
            PacketType::Unknown(raw) => Err(DecodeError::UnknownType { raw }),
        }
    }

    /// Writes the frame into the first [`SensorPacket::buffer_len`] bytes.
    ///
    /// Never panics when the buffer is at least `buffer_len()` bytes long.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]> + ?Sized>(&self, frame: &mut Frame<&mut T>) {
        frame.set_packet_type(self.packet_type());
        frame.set_len(self.data_len());
        match self {
            SensorPacket::KeepState { status, sequence } => {
                frame.set_status(*status);
                frame.set_sequence(*sequence);
            }
            SensorPacket::Command { id, parameter } => {
                frame.set_command_id(*id);
                frame.set_parameter(*parameter);
            }
            SensorPacket::Reading(reading) => {
                frame.set_sensor_type(reading.value.sensor_type());
                frame.set_sensor_id(reading.sensor_id);
                frame.set_sensor_status(reading.status);
                frame.set_data_len(reading.value.data_len());
                reading.value.emit(frame.sensor_data_mut());
            }
        }
    }

    /// The whole frame as bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut buffer = vec![0; self.buffer_len()];
        self.emit(&mut Frame::new_unchecked(&mut buffer[..]));
        buffer
    }
}

/// Counters kept by a [`Decoder`] since it was made: the shared engine's.
///
/// Every byte fed ends up in exactly one place: a decoded frame (`bytes_in_frames`), a dropped
/// byte (`bytes_skipped`) or the pending buffer ([`Decoder::buffered`]). `errors` counts losses of
/// sync reported (one `Err` each).
pub type DecoderStats = ResyncStats;

/// Sans-IO streaming decoder for sensor frames: the shared [`Resync`] engine with the sensor
/// framing. See the module doc for its recovery rules.
///
/// Its buffer holds at most one candidate frame ([`MAX_FRAME_LEN`] bytes).
#[derive(Debug, Clone, Default)]
pub struct Decoder {
    engine: Resync<SensorFraming>,
}

/// What the bytes at the current position say about a frame starting there.
enum Candidate {
    /// Consistent so far; more bytes needed.
    Partial,
    /// Consistent and `total` bytes long.
    Complete(usize),
    /// Cannot start a frame here.
    Reject(DecodeError),
}

/// Judges a candidate from its first bytes (looks at no more than 6).
fn candidate(prefix: &[u8]) -> Candidate {
    let Some(&raw_type) = prefix.first() else {
        return Candidate::Partial;
    };
    let packet_type = PacketType::from(raw_type);
    if let PacketType::Unknown(raw) = packet_type {
        return Candidate::Reject(DecodeError::UnknownType { raw });
    }
    let Some(&len) = prefix.get(field::LEN) else {
        return Candidate::Partial;
    };
    let expected = match packet_type {
        PacketType::SensorData => {
            let Some(&raw_sensor) = prefix.get(field::SENSOR_TYPE) else {
                return Candidate::Partial;
            };
            let sensor_type = SensorType::from(raw_sensor);
            let Some(data_len) = sensor_type.data_len() else {
                return Candidate::Reject(DecodeError::UnknownSensorType { raw: raw_sensor });
            };
            if len != field::SENSOR_HEADER_LEN + data_len {
                return Candidate::Reject(DecodeError::BadLength {
                    packet_type,
                    expected: field::SENSOR_HEADER_LEN + data_len,
                    actual: len,
                });
            }
            let Some(&actual) = prefix.get(field::DATA_LEN) else {
                return Candidate::Partial;
            };
            if actual != data_len {
                return Candidate::Reject(DecodeError::BadDataLength {
                    sensor_type,
                    expected: data_len,
                    actual,
                });
            }
            len
        }
        _ => FIXED_LEN,
    };
    if len != expected {
        return Candidate::Reject(DecodeError::BadLength { packet_type, expected, actual: len });
    }
    let total = usize::from(len) + field::HEADER_LEN;
    if prefix.len() >= total { Candidate::Complete(total) } else { Candidate::Partial }
}

/// The sensor framing for the [`Resync`] engine: a consistent header ([`candidate`]) or drop one
/// byte, one `Err` per loss of sync.
#[derive(Debug, Clone, Copy, Default)]
struct SensorFraming;

impl resync::Framing for SensorFraming {
    type Frame = SensorPacket;
    type Error = DecodeError;
    const MAX_FRAME_LEN: usize = MAX_FRAME_LEN;
    const REPORT: Report = Report::OncePerLossOfSync;

    fn head(&self, bytes: &[u8]) -> Head<DecodeError> {
        match candidate(bytes) {
            // `candidate` judges the header byte by byte: ask for one more.
            Candidate::Partial => Head::Partial { need: bytes.len() + 1 },
            Candidate::Complete(total) => Head::Complete(total),
            Candidate::Reject(error) => Head::Reject(error),
        }
    }

    fn parse(&self, frame: &[u8]) -> Result<SensorPacket, DecodeError> {
        // Never fails while `candidate` and `parse` agree; a failure is a rejection anyway.
        SensorPacket::parse(&Frame::new_unchecked(frame))
    }
}

impl Decoder {
    /// A decoder that assumes the stream starts on a frame boundary.
    pub fn new() -> Self {
        Decoder { engine: Resync::new(SensorFraming) }
    }

    /// Consumes all of `bytes` and returns every packet they complete, plus one error per loss
    /// of sync, in order.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Result<SensorPacket, DecodeError>> {
        self.engine.feed(bytes)
    }

    /// Counters since creation.
    pub fn stats(&self) -> DecoderStats {
        self.engine.stats()
    }

    /// Bytes of a candidate frame held, waiting for the rest.
    pub fn buffered(&self) -> usize {
        self.engine.buffered()
    }

    /// Drops any pending candidate and assumes the next byte starts a frame.
    pub fn reset(&mut self) {
        self.engine.reset();
    }
}

impl_decoder!(Decoder, SensorPacket, DecodeError, DecoderStats);

#[cfg(test)]
mod tests {
    use super::*;

    // ── Golden frames: protocols-research.md §3.5, produced by the original `ui` tool. The
    // protocol has no checksum.

    /// Keep-state: status 2, sequence 258.
    static KEEP_STATE_ROBORIO: [u8; 5] = [0x01, 0x03, 0x02, 0x01, 0x02];
    /// Keep-state: the Arduino's first, status 1, sequence 1.
    static KEEP_STATE_FIRST: [u8; 5] = [0x01, 0x03, 0x01, 0x00, 0x01];
    /// Command id 5 (not one of ours), parameter 1000.
    static COMMAND_5_1000: [u8; 5] = [0x02, 0x03, 0x05, 0x03, 0xE8];
    /// NavX id 7, operational: 1.5, 1013.25, 90, 20.25, accel 0.5/−0.5/9.81, mag 12/−3.
    static NAVX: [u8; 42] = [
        0x03, 0x28, 0x01, 0x07, 0x01, 0x24, //
        0x3F, 0xC0, 0x00, 0x00, 0x44, 0x7D, 0x50, 0x00, 0x42, 0xB4, 0x00, 0x00, 0x41, 0xA2, 0x00, 0x00, 0x3F,
        0x00, 0x00, 0x00, 0xBF, 0x00, 0x00, 0x00, 0x41, 0x1C, 0xF5, 0xC3, 0x41, 0x40, 0x00, 0x00, 0xC0, 0x40,
        0x00, 0x00,
    ];
    /// Encoder id 2, count −2, direction 1.
    static ENCODER: [u8; 11] = [0x03, 0x09, 0x02, 0x02, 0x01, 0x05, 0xFF, 0xFF, 0xFF, 0xFE, 0x01];
    /// Potentiometer id 3, angle 45.5.
    static POTENTIOMETER: [u8; 10] = [0x03, 0x08, 0x03, 0x03, 0x01, 0x04, 0x42, 0x36, 0x00, 0x00];
    /// Distance id 1, 123.25 cm.
    static DISTANCE: [u8; 10] = [0x03, 0x08, 0x04, 0x01, 0x01, 0x04, 0x42, 0xF6, 0x80, 0x00];
    /// Switch id 4, released ("off").
    static SWITCH: [u8; 7] = [0x03, 0x05, 0x05, 0x04, 0x01, 0x01, 0x02];

    fn reading(sensor_id: u8, value: SensorValue) -> SensorPacket {
        SensorPacket::Reading(SensorReading { sensor_id, status: SensorStatus::Operational, value })
    }

    fn golden() -> Vec<(&'static [u8], SensorPacket)> {
        vec![
            (&KEEP_STATE_ROBORIO, SensorPacket::KeepState { status: 2, sequence: 258 }),
            (&KEEP_STATE_FIRST, SensorPacket::KeepState { status: 1, sequence: 1 }),
            (&COMMAND_5_1000, SensorPacket::Command { id: CommandId::Unknown(5), parameter: 1000 }),
            (
                &NAVX,
                reading(
                    7,
                    SensorValue::NavX(NavX {
                        altitude: 1.5,
                        pressure: 1013.25,
                        heading_deg: 90.0,
                        temperature: 20.25,
                        accel: [0.5, -0.5, 9.81],
                        mag: [12.0, -3.0],
                    }),
                ),
            ),
            (&ENCODER, reading(2, SensorValue::Encoder { count: -2, direction: EncoderDirection::Forward })),
            (&POTENTIOMETER, reading(3, SensorValue::Potentiometer { angle: 45.5 })),
            (&DISTANCE, reading(1, SensorValue::Distance { cm: 123.25 })),
            (&SWITCH, reading(4, SensorValue::Switch(SwitchState::Released))),
        ]
    }

    #[test]
    fn test_deconstruct() {
        let frame = Frame::new_checked(&KEEP_STATE_ROBORIO[..]).unwrap();
        assert_eq!(frame.packet_type(), PacketType::KeepState);
        assert_eq!(frame.len(), 3);
        assert_eq!(frame.status(), 2);
        assert_eq!(frame.sequence(), 258);

        let frame = Frame::new_checked(&COMMAND_5_1000[..]).unwrap();
        assert_eq!(frame.packet_type(), PacketType::Command);
        assert_eq!(frame.command_id(), CommandId::Unknown(5));
        assert_eq!(frame.parameter(), 1000);

        let frame = Frame::new_checked(&ENCODER[..]).unwrap();
        assert_eq!(frame.packet_type(), PacketType::SensorData);
        assert_eq!(frame.len(), 9);
        assert_eq!(frame.frame_len(), 11);
        assert_eq!(frame.sensor_type(), SensorType::Encoder);
        assert_eq!(frame.sensor_id(), 2);
        assert_eq!(frame.sensor_status(), SensorStatus::Operational);
        assert_eq!(frame.data_len(), 5);
        assert_eq!(frame.sensor_data(), &[0xFF, 0xFF, 0xFF, 0xFE, 0x01]);
        assert_eq!(frame.data(), &ENCODER[2..]);
    }

    #[test]
    fn test_construct() {
        let mut bytes = vec![0xa5; 5];
        let mut frame = Frame::new_unchecked(&mut bytes);
        frame.set_packet_type(PacketType::Command);
        frame.set_len(3);
        frame.set_command_id(CommandId::Unknown(5));
        frame.set_parameter(1000);
        assert_eq!(frame.into_inner(), &COMMAND_5_1000);

        let mut bytes = vec![0xa5; 7];
        let mut frame = Frame::new_unchecked(&mut bytes);
        frame.set_packet_type(PacketType::SensorData);
        frame.set_len(5);
        frame.set_sensor_type(SensorType::Switch);
        frame.set_sensor_id(4);
        frame.set_sensor_status(SensorStatus::Operational);
        frame.set_data_len(1);
        frame.sensor_data_mut().copy_from_slice(&[u8::from(SwitchState::Released)]);
        assert_eq!(frame.into_inner(), &SWITCH);

        let mut bytes = vec![0xa5; 5];
        let mut frame = Frame::new_unchecked(&mut bytes);
        frame.set_packet_type(PacketType::KeepState);
        frame.set_len(3);
        frame.set_status(1);
        frame.set_sequence(1);
        assert_eq!(frame.into_inner(), &KEEP_STATE_FIRST);
    }

    #[test]
    fn test_deconstruct_construct_every_golden_frame() {
        for (bytes, _) in golden() {
            let frame = Frame::new_checked(bytes).unwrap();
            let mut out = vec![0xa5; bytes.len()];
            let mut built = Frame::new_unchecked(&mut out);
            built.set_packet_type(frame.packet_type());
            built.set_len(frame.len());
            built.data_mut().copy_from_slice(frame.data());
            assert_eq!(&out[..], bytes);
        }
    }

    #[test]
    fn test_parse() {
        for (bytes, packet) in golden() {
            let frame = Frame::new_checked(bytes).unwrap();
            assert_eq!(SensorPacket::parse(&frame), Ok(packet), "{bytes:02x?}");
        }
    }

    #[test]
    fn test_emit() {
        for (bytes, packet) in golden() {
            assert_eq!(packet.buffer_len(), bytes.len());
            let mut out = vec![0xa5; packet.buffer_len()];
            packet.emit(&mut Frame::new_unchecked(&mut out));
            assert_eq!(&out[..], bytes, "{packet:?}");
            assert_eq!(packet.to_bytes(), bytes);
        }
    }

    #[test]
    fn test_length_errors() {
        // Keep-state with LEN 2: too short for its fields.
        assert_eq!(
            Frame::new_checked(&[0x01, 0x02, 0x00, 0x01][..]),
            Err(DecodeError::BadLength { packet_type: PacketType::KeepState, expected: 3, actual: 2 })
        );
        // Keep-state with LEN 4: readable, but not the exact length.
        let frame = Frame::new_checked(&[0x01, 0x04, 0x01, 0x00, 0x01, 0x00][..]).unwrap();
        assert_eq!(
            SensorPacket::parse(&frame),
            Err(DecodeError::BadLength { packet_type: PacketType::KeepState, expected: 3, actual: 4 })
        );
        // Distance whose data_len says 5.
        let frame = Frame::new_checked(&[0x03, 0x09, 0x04, 0x01, 0x01, 0x05, 0, 0, 0, 0, 0][..]).unwrap();
        assert_eq!(
            SensorPacket::parse(&frame),
            Err(DecodeError::BadLength { packet_type: PacketType::SensorData, expected: 8, actual: 9 })
        );
        let frame = Frame::new_checked(&[0x03, 0x08, 0x04, 0x01, 0x01, 0x03, 0, 0, 0, 0][..]).unwrap();
        assert_eq!(
            SensorPacket::parse(&frame),
            Err(DecodeError::BadDataLength { sensor_type: SensorType::Distance, expected: 4, actual: 3 })
        );
        // Sensor data whose data_len runs past LEN.
        assert_eq!(
            Frame::new_checked(&[0x03, 0x05, 0x04, 0x01, 0x01, 0x04, 0x00][..]),
            Err(DecodeError::BadLength { packet_type: PacketType::SensorData, expected: 8, actual: 5 })
        );
        assert_eq!(Frame::new_checked(&SWITCH[..6]), Err(DecodeError::Truncated { need: 7, got: 6 }));
        assert_eq!(
            SensorPacket::parse(&Frame::new_unchecked(&[0x03][..])),
            Err(DecodeError::Truncated { need: 2, got: 1 })
        );
    }

    #[test]
    fn test_unknown_types_are_errors() {
        let frame = Frame::new_checked(&[0x07, 0x01, 0x00][..]).unwrap();
        assert_eq!(SensorPacket::parse(&frame), Err(DecodeError::UnknownType { raw: 7 }));
        let frame = Frame::new_checked(&[0x03, 0x05, 0x09, 0x01, 0x01, 0x01, 0x00][..]).unwrap();
        assert_eq!(SensorPacket::parse(&frame), Err(DecodeError::UnknownSensorType { raw: 9 }));
    }

    #[test]
    fn test_unknown_values_are_kept() {
        let bytes = [0x03, 0x05, 0x05, 0x01, 0x09, 0x01, 0x07];
        let packet = SensorPacket::parse(&Frame::new_checked(&bytes[..]).unwrap()).unwrap();
        assert_eq!(
            packet,
            SensorPacket::Reading(SensorReading {
                sensor_id: 1,
                status: SensorStatus::Unknown(9),
                value: SensorValue::Switch(SwitchState::Unknown(7)),
            })
        );
        assert_eq!(packet.to_bytes(), bytes);
    }

    #[test]
    fn test_candidate_judges_headers_early() {
        assert!(matches!(candidate(&[]), Candidate::Partial));
        assert!(matches!(candidate(&[0x00]), Candidate::Reject(DecodeError::UnknownType { raw: 0 })));
        assert!(matches!(candidate(&[0x01]), Candidate::Partial));
        assert!(matches!(candidate(&[0x01, 0x04]), Candidate::Reject(DecodeError::BadLength { .. })));
        assert!(matches!(candidate(&[0x03, 0x08]), Candidate::Partial));
        assert!(matches!(
            candidate(&[0x03, 0x08, 0x06]),
            Candidate::Reject(DecodeError::UnknownSensorType { raw: 6 })
        ));
        assert!(matches!(candidate(&DISTANCE[..9]), Candidate::Partial));
        assert!(matches!(candidate(&DISTANCE), Candidate::Complete(10)));
        for (bytes, _) in golden() {
            assert!(matches!(candidate(bytes), Candidate::Complete(n) if n == bytes.len()));
        }
    }

    #[test]
    fn test_decoder_reports_one_error_per_loss_of_sync() {
        let mut decoder = Decoder::new();
        let mut stream = vec![0xF0, 0xF1, 0xF2, 0xF3];
        stream.extend_from_slice(&SWITCH);
        stream.extend_from_slice(&[0x00, 0x00]);
        stream.extend_from_slice(&KEEP_STATE_FIRST);
        let out = decoder.feed(&stream);
        assert_eq!(out.len(), 4, "{out:?}");
        assert_eq!(out[0], Err(DecodeError::UnknownType { raw: 0xF0 }));
        assert_eq!(out[1], Ok(golden()[7].1));
        assert_eq!(out[2], Err(DecodeError::UnknownType { raw: 0x00 }));
        assert_eq!(out[3], Ok(golden()[1].1));
        let stats = decoder.stats();
        assert_eq!(stats.errors, 2);
        assert_eq!(stats.bytes_skipped, 6);
        assert_eq!(stats.frames, 2);
        assert_eq!(stats.bytes, stats.bytes_in_frames + stats.bytes_skipped);
    }
}
