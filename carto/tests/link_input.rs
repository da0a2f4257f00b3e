//! Carto against malformed input on the link, with the scripted boards of `fake/`: fatal sizes,
//! unknown ids, both byte orders, split frames, bad lengths.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod fake;

use carto::motor::Drive;
use carto::{Carto, CartoConfig};
use fake::{Harness, POSE};
use protocol::link::{Command, Direction, GuiMessage};
use robot_model::time::Instant;

fn ready() -> Harness {
    Harness::ready()
}

#[test]
fn size_zero_is_fatal_closes_the_connection_and_the_next_client_is_served() {
    let mut h = ready();
    h.send_bytes(&[0x00, 0x00, 0x02, 0x00]);
    assert!(h.carto.should_close_client());
    assert_eq!(h.carto.stats().fatal_errors, 1);
    // Bytes after a fatal error are ignored.
    h.send(POSE);
    assert!(h.replies.is_empty());
    h.carto.on_client_disconnected(h.now);
    h.carto.on_client_connected(h.now, "test:2");
    assert!(!h.carto.should_close_client());
    h.send(POSE);
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
}

#[test]
fn size_9000_is_fatal() {
    let mut h = ready();
    h.send_bytes(&[0x23, 0x28, 0x01, 0x00, 1, 0]);
    assert!(h.carto.should_close_client());
    assert_eq!(h.carto.stats().protocol_errors, 1);
}

#[test]
fn replies_before_a_fatal_error_in_the_same_segment_are_kept() {
    let mut h = ready();
    let mut bytes = POSE.to_bytes(protocol::link::MsgOrder::BigEndian);
    bytes.extend([0x00, 0x01, 0xFF]);
    h.send_bytes(&bytes);
    assert!(h.carto.should_close_client());
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
}

#[test]
fn unknown_msg_is_ignored_and_the_session_continues() {
    let mut h = ready();
    h.send_bytes(&[0x00, 0x04, 0x09, 0x00, 0xAB, 0xCD]);
    h.send(POSE);
    assert!(!h.carto.should_close_client());
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
    assert_eq!(h.carto.stats().unknown_messages, 1);
}

#[test]
fn little_endian_msg_is_accepted_and_answered_big_endian() {
    let mut h = Harness::new();
    h.warm_up();
    // SEND_ROBOT_POSITION (1, 2) WEST with Msg 00 07
    h.send_bytes(&[0x00, 0x05, 0x00, 0x07, 1, 2, 2]);
    let c = h.carto.take_client_bytes();
    assert!(c.is_empty(), "pump already moved them");
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
    let p = h.carto.status().pose.unwrap();
    assert_eq!((p.x, p.y, p.heading), (1, 2, robot_model::grid::Heading::West));
}

#[test]
fn reply_bytes_are_big_endian_on_the_wire() {
    let mut carto = Carto::new(CartoConfig::default());
    carto.on_client_connected(Instant::ZERO, "raw");
    carto.on_client_bytes(Instant::ZERO, &[0x00, 0x05, 0x07, 0x00, 1, 2, 2]);
    assert_eq!(carto.take_client_bytes(), vec![0x00, 0x02, 0x08, 0x00]);
}

#[test]
fn a_frame_split_into_single_bytes_is_reassembled() {
    let mut h = ready();
    let mut bytes = GuiMessage::SendRobotPosition { x: 7, y: 8, direction: Direction::South }
        .to_bytes(protocol::link::MsgOrder::BigEndian);
    bytes.extend(
        GuiMessage::SendMoveCartography { command: Command::Right }
            .to_bytes(protocol::link::MsgOrder::LittleEndian),
    );
    for b in bytes {
        h.send_bytes(&[b]);
        h.tick();
    }
    assert!(h.run_until(8000, |h| h.move_done_count() == 1));
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived, GuiMessage::MoveDone]);
    assert_eq!(h.carto.status().pose.unwrap().heading, robot_model::grid::Heading::West);
}

#[test]
fn bad_length_frame_is_skipped_without_closing() {
    let mut h = ready();
    // SEND_MOVE_CARTOGRAPHY with Size 2 (no data byte), then a valid pose
    h.send_bytes(&[0x00, 0x02, 0x02, 0x00]);
    h.send(POSE);
    assert!(!h.carto.should_close_client());
    assert_eq!(h.reply_msgs(), vec![GuiMessage::RobotPositionReceived]);
    assert_eq!(h.carto.stats().protocol_errors, 1);
}

#[test]
fn idle_carto_sends_zero_drive_and_never_moves() {
    let mut h = Harness::new();
    h.run_ms(3000);
    assert!(!h.robot.drives.is_empty());
    assert!(h.robot.drives.iter().all(|(_, d)| *d == Drive::STOP));
    assert!(h.robot.drives.len() >= 6, "zero drive repeated while idle");
}
