//! The only place where Carto meets the `protocol` crate: typed wire messages in, Carto's own
//! [`Request`]/[`SensorEvent`] out, and [`Reply`]/[`Drive`]/keep-state back to bytes.
//!
//! Keeping the translation here lets the state machines ([`crate::pilot`], [`crate::motor`],
//! [`crate::sensors`]) be tested without bytes, and pins down the few conventions in one file:
//! replies always go out big-endian; drive frames are v2 (`0x10`) with the sum checksum; the stop
//! frame is all zero; keep-state goes out with status 2; sensor ids 1–4 of the encoder type are
//! the wheels FL, FR, RL, RR; sensors other than NavX 1, encoders 1–4, distance 1 and switch 1 are
//! ignored.
//!
//! ```
//! use carto::wire;
//! use carto::pilot::Reply;
//! assert_eq!(wire::encode_reply(Reply::MoveDone), vec![0x00, 0x02, 0x03, 0x00]);
//! assert_eq!(wire::encode_keep_state(258), vec![0x01, 0x03, 0x02, 0x01, 0x02]);
//! ```

use protocol::link::{GuiMessage, MsgOrder};
use protocol::motor::{MotorCommand, MotorPacket};
use protocol::sensor::{SensorPacket, SensorReading, SensorStatus, SensorValue, SwitchState};
use robot_model::grid::{Heading, Move};

use crate::motor::Drive;
use crate::pilot::{Reply, Request};
use crate::sensors::SensorEvent;

/// Keep-state status Carto sends ("controller still on").
pub const KEEP_STATE_STATUS: u8 = 2;

/// Translates a decoded link message into a pilot request.
pub fn request_from(msg: &GuiMessage) -> Request {
    match msg {
        GuiMessage::SendMovesTrajectory { n_total, command } => {
            Request::Trajectory { n_total: *n_total, command: Move::try_from(*command) }
        }
        GuiMessage::SendMoveCartography { command } => {
            Request::Cartography { command: Move::try_from(*command) }
        }
        GuiMessage::StopRobot => Request::Stop,
        GuiMessage::SendRobotPosition { x, y, direction } => {
            Request::SetPose { x: *x, y: *y, direction: Heading::try_from(*direction) }
        }
        other => Request::Ignored { msg: u16::from(other.msg_type()) },
    }
}

/// The link message for a reply.
pub fn reply_message(reply: Reply) -> GuiMessage {
    match reply {
        Reply::PositionReceived => GuiMessage::RobotPositionReceived,
        Reply::Obstacle { x, y } => GuiMessage::SetObstaclePosition { x, y },
        Reply::RobotPosition { x, y } => GuiMessage::SetRobotPosition { x, y },
        Reply::MoveDone => GuiMessage::MoveDone,
    }
}

/// A reply as bytes on the wire (big-endian `Msg`).
pub fn encode_reply(reply: Reply) -> Vec<u8> {
    reply_message(reply).to_bytes(MsgOrder::BigEndian)
}

/// A drive setpoint as a drive v2 frame; the stop frame is all zero.
pub fn encode_drive(drive: Drive, speed_ratio: u8) -> Vec<u8> {
    let cmd = if drive.is_stop() {
        MotorCommand::STOP_V2
    } else {
        MotorCommand::V2 { vx: drive.vx, vy: drive.vy, omega: drive.omega, speed_ratio, reserved: [0; 2] }
    };
    MotorPacket::Drive(cmd).to_bytes()
}

/// A motor board packet in Carto's terms (telemetry → wheel rpm, anything else ignored).
pub fn motor_event(packet: &MotorPacket) -> SensorEvent {
    match packet {
        MotorPacket::Telemetry(t) => SensorEvent::WheelRpm { rpm: t.wheel_rpm },
        _ => SensorEvent::Ignored,
    }
}

/// Carto's keep-state frame with `sequence`.
pub fn encode_keep_state(sequence: u16) -> Vec<u8> {
    SensorPacket::KeepState { status: KEEP_STATE_STATUS, sequence }.to_bytes()
}

/// A sensor board packet in Carto's terms.
pub fn sensor_event(packet: &SensorPacket) -> SensorEvent {
    match packet {
        SensorPacket::KeepState { status, sequence } => {
            SensorEvent::KeepState { status: *status, sequence: *sequence }
        }
        SensorPacket::Reading(r) => reading_event(r),
        _ => SensorEvent::Ignored,
    }
}

fn reading_event(r: &SensorReading) -> SensorEvent {
    let ok = r.status == SensorStatus::Operational;
    match (&r.value, r.sensor_id) {
        (SensorValue::NavX(n), 1) if ok => SensorEvent::Heading { cw_deg: f64::from(n.heading_deg) },
        (SensorValue::Encoder { count, .. }, id @ 1..=4) if ok => {
            SensorEvent::Encoder { wheel: usize::from(id - 1), count: *count }
        }
        // Distance readings with an error status are passed on so the ultrasound counts them.
        (SensorValue::Distance { cm }, 1) => {
            if ok {
                SensorEvent::Distance { cm: *cm }
            } else {
                SensorEvent::Distance { cm: f32::NAN }
            }
        }
        (SensorValue::Switch(state), 1) if ok => match state {
            SwitchState::Pressed => SensorEvent::Bumper { pressed: true },
            SwitchState::Released => SensorEvent::Bumper { pressed: false },
            SwitchState::Unknown(_) => SensorEvent::Ignored,
        },
        _ => SensorEvent::Ignored,
    }
}
