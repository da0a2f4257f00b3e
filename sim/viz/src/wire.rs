//! Link traffic as Foxglove messages: every byte each traced endpoint moved, and every frame (or
//! decode error) the receiving end decoded, through the same `protocol` decoders as
//! `explobot decode` and as Carto, Cute and the board twins themselves.
//!
//! Which stream is decoded: the one the receiver read, so the frame counts are the receiver's
//! (the report's). Carto's end of the Cute link is not traced in the lockstep runner; what Cute
//! wrote stands for it (the same bytes unless the scenario injects faults on `gui`).
//!
//! | topic | schema | one message per |
//! |---|---|---|
//! | `/links/{motor,sensor,gui}/bytes` | `LinkBytes` | link and [`super::BYTES_EVERY`] steps: each endpoint's bytes read and written, with the time of each chunk |
//! | `/links/motor/out`, `/links/motor/in` | `MotorFrame` | frame the board (out) or Carto (in) decoded, or error |
//! | `/links/sensor/out`, `/links/sensor/in` | `SensorFrame` | the same on the sensor link |
//! | `/links/gui/out`, `/links/gui/in` | `GuiFrame` | frame Carto (out, from Cute) or Cute (in) decoded, or error |

use std::sync::Arc;

use foxglove::bytes::Bytes;
use foxglove::{Context, Encode};
use protocol::link::{self, GuiMessage};
use protocol::motor::{self, ChecksumPolicy, MotorCommand, MotorPacket};
use protocol::sensor::{self, SensorPacket, SensorValue};
use transport::{Direction, TraceRecord};

use super::{Outbox, Topic};
use twin::runner::Endpoint;

/// Which end of a link recorded the bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Encode)]
pub enum Side {
    /// Carto.
    Carto = 0,
    /// A board twin.
    Board = 1,
    /// Cute (one connection, see `connection`).
    Cute = 2,
}

/// Which way the bytes went through that end.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Encode)]
pub enum Flow {
    /// Read: they came in.
    Read = 0,
    /// Written: they went out.
    Written = 1,
}

/// The bytes one end moved one way during one batch.
#[derive(Debug, Clone, PartialEq, Encode)]
pub struct ByteStream {
    /// The end that recorded them.
    pub side: Side,
    /// Cute's connection number (0 for the board links).
    pub connection: u32,
    /// In or out.
    pub flow: Flow,
    /// The bytes, chunk after chunk.
    pub data: Bytes,
    /// Sim time of each chunk, µs.
    pub at_us: Vec<u64>,
    /// Length of each chunk, bytes.
    pub lengths: Vec<u32>,
}

/// A link's traffic over one batch of steps.
#[derive(Debug, Clone, PartialEq, Encode)]
pub struct LinkBytes {
    /// One entry per end and way that moved bytes.
    pub streams: Vec<ByteStream>,
}

/// One frame (or decode error) on the motor link.
#[derive(Debug, Clone, PartialEq, Default, Encode)]
pub struct MotorFrame {
    /// `drive_v1`, `drive_v2`, `telemetry`, `unknown`, or `error`.
    pub kind: &'static str,
    /// The decoder's error, empty for a frame.
    pub error: String,
    /// The TYPE byte.
    pub packet_type: u32,
    /// v1: strafe axis, offset binary.
    pub dir_x: u32,
    /// v1: forward axis, offset binary.
    pub dir_y: u32,
    /// v1: speed scale.
    pub gear: u32,
    /// v2: forward, %.
    pub vx: i32,
    /// v2: left, %.
    pub vy: i32,
    /// v2: counter-clockwise, %.
    pub omega: i32,
    /// Telemetry: wheel speeds FL, FR, RL, RR, rpm (empty for other frames).
    pub wheel_rpm: Vec<f32>,
    /// Telemetry: motor power, % (empty for other frames).
    pub motor_power: Vec<f32>,
}

/// One frame (or decode error) on the sensor link.
#[derive(Debug, Clone, PartialEq, Default, Encode)]
pub struct SensorFrame {
    /// `keep_state`, `command`, `reading`, or `error`.
    pub kind: &'static str,
    /// The decoder's error, empty for a frame.
    pub error: String,
    /// Reading: `navx`, `encoder`, `potentiometer`, `distance`, `switch`.
    pub sensor: &'static str,
    /// Reading: sensor id (encoders 1–4 = FL, FR, RL, RR).
    pub sensor_id: u32,
    /// Reading: status byte (1 operational, 2 error); keep-state: its status.
    pub status: u32,
    /// Reading: distance cm (−1 no echo), encoder count, potentiometer angle, switch state,
    /// NavX heading in degrees.
    pub value: f64,
    /// Keep-state: sequence number.
    pub sequence: u32,
    /// Command: its id (1 distance period, 2 reset encoders, 3 zero heading).
    pub command: u32,
    /// Command: its parameter.
    pub parameter: i32,
}

/// One frame (or decode error) on the Cute ⇄ Carto link.
#[derive(Debug, Clone, PartialEq, Default, Encode)]
pub struct GuiFrame {
    /// Cute's connection number.
    pub connection: u32,
    /// The message as `explobot decode` prints it, or the decoder's error.
    pub text: String,
    /// Whether it is an error.
    pub is_error: bool,
    /// The `Msg` id.
    pub msg: u32,
    /// Row, where the message has one.
    pub x: u32,
    /// Column, where the message has one.
    pub y: u32,
}

/// The decoder of one received stream.
enum Decoding {
    Motor(motor::Decoder),
    Sensor(sensor::Decoder),
    Link(link::Decoder),
}

/// One traced end and way, its batch of bytes and, when it is a received stream, its decoder.
struct Stream {
    link: usize,
    side: Side,
    connection: u32,
    flow: Flow,
    /// `true` when the frames it decodes go out (Carto → board, Cute → Carto).
    outbound: bool,
    decoding: Option<Decoding>,
    data: Vec<u8>,
    at_us: Vec<u64>,
    lengths: Vec<u32>,
}

/// The decoders' settings: what the receivers are configured with.
#[derive(Debug, Clone, Copy)]
pub struct WireConfig {
    /// The motor board's accepted checksums.
    pub board_checksum: ChecksumPolicy,
    /// Carto's accepted motor checksums.
    pub carto_checksum: ChecksumPolicy,
    /// Largest link frame Carto and Cute accept.
    pub max_frame: usize,
    /// Decode what the boards write (the served twin, whose Carto runs elsewhere and is not
    /// traced); the lockstep runner decodes what Carto read instead.
    pub decode_board_writes: bool,
}

const LINKS: [&str; 3] = ["motor", "sensor", "gui"];

/// Byte batches and decoders for every traced stream, and the channels they log to.
pub struct WireTap {
    config: WireConfig,
    streams: Vec<Stream>,
    bytes: [Topic<LinkBytes>; 3],
    motor: [Topic<MotorFrame>; 2],
    sensor: [Topic<SensorFrame>; 2],
    gui: [Topic<GuiFrame>; 2],
}

impl WireTap {
    /// The channels of the three links on `context`.
    pub fn new(context: &Arc<Context>, outbox: &Outbox, config: WireConfig) -> WireTap {
        WireTap {
            config,
            streams: Vec::new(),
            bytes: LINKS.map(|l| outbox.topic(context, format!("/links/{l}/bytes"))),
            motor: pair(context, outbox, "motor"),
            sensor: pair(context, outbox, "sensor"),
            gui: pair(context, outbox, "gui"),
        }
    }

    /// Takes one record of `at`: batches its bytes and logs what they complete, at `ns`.
    pub fn record(&mut self, at: Endpoint<'_>, r: &TraceRecord, ns: u64) {
        let Some(link) = LINKS.iter().position(|l| *l == at.link) else { return };
        let side = match at.endpoint {
            "carto" => Side::Carto,
            "board" => Side::Board,
            _ => Side::Cute,
        };
        let connection = at.connection.map_or(0, |n| n as u32);
        let flow = match r.direction {
            Direction::Read => Flow::Read,
            Direction::Written => Flow::Written,
        };
        let i = match self
            .streams
            .iter()
            .position(|s| (s.link, s.side, s.connection, s.flow) == (link, side, connection, flow))
        {
            Some(i) => i,
            None => {
                self.streams.push(self.stream(link, side, connection, flow));
                self.streams.len() - 1
            }
        };
        let s = &mut self.streams[i];
        s.data.extend_from_slice(&r.bytes);
        s.at_us.push(r.at.total_micros());
        s.lengths.push(r.bytes.len() as u32);
        let out = usize::from(!s.outbound);
        match &mut s.decoding {
            None => {}
            Some(Decoding::Motor(d)) => {
                for item in d.feed(&r.bytes) {
                    self.motor[out].log(&motor_frame(item), ns);
                }
            }
            Some(Decoding::Sensor(d)) => {
                for item in d.feed(&r.bytes) {
                    self.sensor[out].log(&sensor_frame(item), ns);
                }
            }
            Some(Decoding::Link(d)) => {
                for item in d.feed(&r.bytes) {
                    self.gui[out].log(&gui_frame(connection, item), ns);
                }
            }
        }
    }

    /// A new stream, with a decoder when it is one a receiver reads.
    fn stream(&self, link: usize, side: Side, connection: u32, flow: Flow) -> Stream {
        let c = self.config;
        // (outbound, decoder) of the frames this stream carries to its receiver.
        let decoding = match (LINKS[link], side, flow) {
            ("motor", Side::Board, Flow::Read) => {
                Some((true, Decoding::Motor(motor::Decoder::new(c.board_checksum))))
            }
            ("motor", Side::Carto, Flow::Read) => {
                Some((false, Decoding::Motor(motor::Decoder::new(c.carto_checksum))))
            }
            ("motor", Side::Board, Flow::Written) if c.decode_board_writes => {
                Some((false, Decoding::Motor(motor::Decoder::new(c.carto_checksum))))
            }
            ("sensor", Side::Board, Flow::Read) => Some((true, Decoding::Sensor(sensor::Decoder::new()))),
            ("sensor", Side::Carto, Flow::Read) => Some((false, Decoding::Sensor(sensor::Decoder::new()))),
            ("sensor", Side::Board, Flow::Written) if c.decode_board_writes => {
                Some((false, Decoding::Sensor(sensor::Decoder::new())))
            }
            ("gui", Side::Cute, Flow::Read) => Some((false, Decoding::Link(link::Decoder::new(c.max_frame)))),
            ("gui", Side::Cute, Flow::Written) => {
                Some((true, Decoding::Link(link::Decoder::new(c.max_frame))))
            }
            _ => None,
        };
        let (outbound, decoding) = match decoding {
            Some((o, d)) => (o, Some(d)),
            None => (false, None),
        };
        Stream {
            link,
            side,
            connection,
            flow,
            outbound,
            decoding,
            data: Vec::new(),
            at_us: Vec::new(),
            lengths: Vec::new(),
        }
    }

    /// Logs each link's batch of bytes (if it moved any) at `ns` and starts new batches.
    pub fn flush(&mut self, ns: u64) {
        for (link, channel) in self.bytes.iter().enumerate() {
            let streams: Vec<ByteStream> = self
                .streams
                .iter_mut()
                .filter(|s| s.link == link && !s.data.is_empty())
                .map(|s| ByteStream {
                    side: s.side,
                    connection: s.connection,
                    flow: s.flow,
                    data: Bytes::from(std::mem::take(&mut s.data)),
                    at_us: std::mem::take(&mut s.at_us),
                    lengths: std::mem::take(&mut s.lengths),
                })
                .collect();
            if !streams.is_empty() {
                channel.log(&LinkBytes { streams }, ns);
            }
        }
    }

    /// Forgets every stream (a restarted run starts new ones).
    pub fn reset(&mut self) {
        self.streams.clear();
    }
}

/// The `out` and `in` channels of a link's frames.
fn pair<T: Encode>(context: &Arc<Context>, outbox: &Outbox, link: &str) -> [Topic<T>; 2] {
    ["out", "in"].map(|way| outbox.topic(context, format!("/links/{link}/{way}")))
}

fn motor_frame(item: Result<MotorPacket, motor::DecodeError>) -> MotorFrame {
    let packet = match item {
        Ok(p) => p,
        Err(e) => return MotorFrame { kind: "error", error: e.to_string(), ..MotorFrame::default() },
    };
    let packet_type = u32::from(u8::from(packet.packet_type()));
    match packet {
        MotorPacket::Drive(MotorCommand::V1 { dir_x, dir_y, gear }) => MotorFrame {
            kind: "drive_v1",
            packet_type,
            dir_x: dir_x.into(),
            dir_y: dir_y.into(),
            gear: gear.into(),
            ..MotorFrame::default()
        },
        MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, .. }) => MotorFrame {
            kind: "drive_v2",
            packet_type,
            vx: vx.into(),
            vy: vy.into(),
            omega: omega.into(),
            ..MotorFrame::default()
        },
        MotorPacket::Telemetry(t) => MotorFrame {
            kind: "telemetry",
            packet_type,
            wheel_rpm: t.wheel_rpm.to_vec(),
            motor_power: t.motor_power.to_vec(),
            ..MotorFrame::default()
        },
        MotorPacket::Unknown { .. } => MotorFrame { kind: "unknown", packet_type, ..MotorFrame::default() },
    }
}

fn sensor_frame(item: Result<SensorPacket, sensor::DecodeError>) -> SensorFrame {
    match item {
        Err(e) => SensorFrame { kind: "error", error: e.to_string(), ..SensorFrame::default() },
        Ok(SensorPacket::KeepState { status, sequence }) => SensorFrame {
            kind: "keep_state",
            status: status.into(),
            sequence: sequence.into(),
            ..SensorFrame::default()
        },
        Ok(SensorPacket::Command { id, parameter }) => SensorFrame {
            kind: "command",
            command: u8::from(id).into(),
            parameter: parameter.into(),
            ..SensorFrame::default()
        },
        Ok(SensorPacket::Reading(r)) => {
            let (sensor, value) = match r.value {
                SensorValue::NavX(n) => ("navx", f64::from(n.heading_deg)),
                SensorValue::Encoder { count, .. } => ("encoder", f64::from(count)),
                SensorValue::Potentiometer { angle } => ("potentiometer", f64::from(angle)),
                SensorValue::Distance { cm } => ("distance", f64::from(cm)),
                SensorValue::Switch(state) => ("switch", f64::from(u8::from(state))),
            };
            SensorFrame {
                kind: "reading",
                sensor,
                sensor_id: r.sensor_id.into(),
                status: u8::from(r.status).into(),
                value,
                ..SensorFrame::default()
            }
        }
    }
}

fn gui_frame(connection: u32, item: Result<GuiMessage, link::DecodeError>) -> GuiFrame {
    match item {
        Err(e) => GuiFrame { connection, text: e.to_string(), is_error: true, ..GuiFrame::default() },
        Ok(m) => {
            let (x, y) = match &m {
                GuiMessage::SetObstaclePosition { x, y }
                | GuiMessage::SetRobotPosition { x, y }
                | GuiMessage::SendRobotPosition { x, y, .. } => (u32::from(*x), u32::from(*y)),
                _ => (0, 0),
            };
            let msg = u32::from(u16::from(m.msg_type()));
            GuiFrame { connection, text: format!("{m:?}"), is_error: false, msg, x, y }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn frames_keep_their_fields_and_errors_their_message() {
        let drive = MotorPacket::Drive(MotorCommand::V2 {
            vx: 50,
            vy: -20,
            omega: 6,
            speed_ratio: 0,
            reserved: [0; 2],
        });
        let f = motor_frame(Ok(drive));
        assert_eq!((f.kind, f.vx, f.vy, f.omega, f.packet_type), ("drive_v2", 50, -20, 6, 0x10));
        let bad = motor::Decoder::new(ChecksumPolicy::Sum).feed(&[0xAA, 0x03, 0x01, 0x80, 0x80, 0x06, 0x00]);
        let e = motor_frame(bad.into_iter().next().unwrap());
        assert_eq!(e.kind, "error");
        assert!(e.error.contains("checksum"), "{}", e.error);
        let distance = sensor_frame(Ok(SensorPacket::Reading(sensor::SensorReading {
            sensor_id: 1,
            status: sensor::SensorStatus::Operational,
            value: SensorValue::Distance { cm: 42.0 },
        })));
        assert_eq!((distance.kind, distance.sensor, distance.value), ("reading", "distance", 42.0));
        let g = gui_frame(2, Ok(GuiMessage::SetRobotPosition { x: 3, y: 4 }));
        assert_eq!((g.connection, g.x, g.y, g.is_error), (2, 3, 4, false));
        assert!(g.text.contains("SetRobotPosition"));
    }
}
