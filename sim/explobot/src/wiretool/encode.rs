//! The messages `explobot encode` builds: one clap subcommand per message of the three protocols,
//! with typed, range-checked fields.

use super::*;

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
    /// Drive v2: VX VY OMEGA \[SPEED_RATIO\], percent.
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
pub(super) fn number<T: std::str::FromStr + TryFrom<i64>>(text: &str) -> Result<T, BadValue> {
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
pub(super) fn code<T: Copy + From<u8>>(text: &str, named: &[(&str, T)]) -> Result<T, BadValue> {
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
