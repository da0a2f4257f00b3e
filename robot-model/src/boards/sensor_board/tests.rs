use super::*;

fn decode(bytes: &[u8]) -> Vec<SensorPacket> {
    Decoder::new().feed(bytes).into_iter().map(|r| r.unwrap()).collect()
}

fn cmd(id: CommandId, parameter: i16) -> Vec<u8> {
    SensorPacket::Command { id, parameter }.to_bytes()
}

fn keep(sequence: u16) -> Vec<u8> {
    SensorPacket::KeepState { status: 2, sequence }.to_bytes()
}

#[test]
fn default_rates_fit_9600_baud() {
    let b = SensorBoard::new(&RobotProfile::default());
    // keep 2×5 + distance 10×10 + NavX 10×42 + encoders 5×4×11 + bumper 1×7 = 757
    assert!((b.planned_bytes_per_sec() - 757.0).abs() < 0.01, "{}", b.planned_bytes_per_sec());
    assert_eq!(b.budget_bytes_per_sec(), 960.0);
    assert!(!b.budget_exceeded() && !b.budget_warned());
}

#[test]
fn streams_keep_their_rates_over_ten_seconds() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    let mut counts = [0usize; 5]; // keep, distance, navx, encoder, switch
    for ms in (0..10_000).step_by(5) {
        for p in decode(&b.poll(Instant::from_millis(ms), &SensorInputs::default())) {
            let i = match p {
                SensorPacket::KeepState { .. } => 0,
                SensorPacket::Reading(SensorReading { value: SensorValue::Distance { .. }, .. }) => 1,
                SensorPacket::Reading(SensorReading { value: SensorValue::NavX(_), .. }) => 2,
                SensorPacket::Reading(SensorReading { value: SensorValue::Encoder { .. }, .. }) => 3,
                SensorPacket::Reading(SensorReading { value: SensorValue::Switch(_), .. }) => 4,
                other => panic!("unexpected {other:?}"),
            };
            counts[i] += 1;
        }
    }
    assert_eq!(counts, [20, 100, 100, 200, 10]);
}

#[test]
fn bumper_reports_changes_at_once_and_heartbeats_at_1_hz() {
    let p = RobotProfile {
        sensor_board: crate::profile::SensorBoardParams {
            keep_state_hz: 0.0,
            distance_hz: 0.0,
            navx_hz: 0.0,
            encoder_hz: 0.0,
            bumper_heartbeat_hz: 1.0,
            peer_lost_timeout_ms: 1500,
        },
        ..RobotProfile::default()
    };
    let mut b = SensorBoard::new(&p);
    let mut inputs = SensorInputs::default();
    let switch = |bytes: Vec<u8>| -> Vec<SwitchState> {
        decode(&bytes)
            .into_iter()
            .map(|p| match p {
                SensorPacket::Reading(SensorReading { value: SensorValue::Switch(s), .. }) => s,
                other => panic!("{other:?}"),
            })
            .collect()
    };
    assert_eq!(switch(b.poll(Instant::ZERO, &inputs)), [SwitchState::Released]);
    assert!(switch(b.poll(Instant::from_millis(999), &inputs)).is_empty());
    assert_eq!(switch(b.poll(Instant::from_millis(1000), &inputs)), [SwitchState::Released]);
    inputs.bumper_pressed = true;
    assert_eq!(switch(b.poll(Instant::from_millis(1200), &inputs)), [SwitchState::Pressed]);
    assert!(switch(b.poll(Instant::from_millis(2000), &inputs)).is_empty()); // restarted at 1200
    assert_eq!(switch(b.poll(Instant::from_millis(2200), &inputs)), [SwitchState::Pressed]);
}

#[test]
fn no_echo_is_minus_one_and_heading_is_sent() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    let inputs = SensorInputs { distance_cm: None, heading_deg: 271.5, ..Default::default() };
    let packets = decode(&b.poll(Instant::ZERO, &inputs));
    assert!(packets.contains(&reading(1, SensorValue::Distance { cm: -1.0 })));
    assert!(packets.iter().any(|p| matches!(p,
        SensorPacket::Reading(SensorReading { value: SensorValue::NavX(n), status: SensorStatus::Operational, .. })
            if n.heading_deg == 271.5)));
}

#[test]
fn reset_and_zero_commands_apply_from_the_next_poll() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    let mut inputs = SensorInputs {
        distance_cm: Some(50.0),
        heading_deg: 30.0,
        encoder_counts: [100, -20, 7, 0],
        encoder_forward: [true, false, true, true],
        bumper_pressed: false,
    };
    b.poll(Instant::ZERO, &inputs);
    b.receive(
        Instant::from_millis(10),
        &[cmd(CommandId::ResetEncoders, 0), cmd(CommandId::ZeroHeading, 0)].concat(),
    );
    inputs.encoder_counts = [110, -25, 7, 1];
    inputs.heading_deg = 20.0;
    let packets = decode(&b.poll(Instant::from_millis(200), &inputs));
    let encoders: Vec<(u8, i32, EncoderDirection)> = packets
        .iter()
        .filter_map(|p| match p {
            SensorPacket::Reading(SensorReading {
                sensor_id,
                value: SensorValue::Encoder { count, direction },
                ..
            }) => Some((*sensor_id, *count, *direction)),
            _ => None,
        })
        .collect();
    assert_eq!(
        encoders,
        [
            (1, 0, EncoderDirection::Forward),
            (2, 0, EncoderDirection::Reverse),
            (3, 0, EncoderDirection::Forward),
            (4, 0, EncoderDirection::Forward)
        ]
    );
    let heading = packets.iter().find_map(|p| match p {
        SensorPacket::Reading(SensorReading { value: SensorValue::NavX(n), .. }) => Some(n.heading_deg),
        _ => None,
    });
    assert_eq!(heading, Some(0.0));
    // Later polls are relative to the values at the reset.
    inputs.heading_deg = 15.0;
    inputs.encoder_counts = [120, -30, 7, 1];
    let packets = decode(&b.poll(Instant::from_millis(400), &inputs));
    assert!(
        packets
            .contains(&reading(1, SensorValue::Encoder { count: 10, direction: EncoderDirection::Forward }))
    );
    assert!(
        packets
            .contains(&reading(2, SensorValue::Encoder { count: -5, direction: EncoderDirection::Reverse }))
    );
    assert!(packets.iter().any(|p| matches!(p,
        SensorPacket::Reading(SensorReading { value: SensorValue::NavX(n), .. }) if n.heading_deg == 355.0)));
    assert_eq!(b.counters().commands_applied, 2);
}

#[test]
fn distance_period_command_changes_the_rate() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    b.receive(Instant::ZERO, &cmd(CommandId::SetDistancePeriod, 250));
    assert_eq!(b.distance_period(), Some(Duration::from_millis(250)));
    b.receive(Instant::ZERO, &cmd(CommandId::SetDistancePeriod, 0));
    b.receive(Instant::ZERO, &cmd(CommandId::SetDistancePeriod, -5));
    b.receive(Instant::ZERO, &cmd(CommandId::Unknown(9), 1));
    let c = b.counters();
    assert_eq!((c.commands_applied, c.commands_rejected, c.unknown_commands), (1, 2, 1));
    assert_eq!(b.distance_period(), Some(Duration::from_millis(250)));
    let n = (0..2000)
        .step_by(5)
        .flat_map(|ms| decode(&b.poll(Instant::from_millis(ms), &SensorInputs::default())))
        .filter(|p| {
            matches!(p, SensorPacket::Reading(SensorReading { value: SensorValue::Distance { .. }, .. }))
        })
        .count();
    assert_eq!(n, 8);
}

#[test]
fn peer_lost_after_timeout_and_cleared_by_keep_state() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    let none = SensorInputs::default();
    b.poll(Instant::ZERO, &none);
    b.receive(Instant::from_millis(400), &keep(1));
    b.poll(Instant::from_millis(1900), &none);
    assert!(!b.peer_lost()); // exactly 1.5 s: not yet
    b.poll(Instant::from_millis(1905), &none);
    assert!(b.peer_lost());
    b.poll(Instant::from_millis(3000), &none);
    assert_eq!(b.counters().peer_lost_events, 1);
    b.receive(Instant::from_millis(3100), &keep(2));
    assert!(!b.peer_lost());
    b.receive(Instant::from_millis(3600), &keep(5)); // 3, 4 missing
    assert_eq!(b.counters().peer_sequence_gaps, 1);
    b.poll(Instant::from_millis(5200), &none);
    assert!(b.peer_lost());
    assert_eq!(b.counters().peer_lost_events, 2);
}

#[test]
fn board_without_any_keep_state_loses_its_peer() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    b.poll(Instant::from_millis(1000), &SensorInputs::default());
    b.poll(Instant::from_millis(2501), &SensorInputs::default());
    assert!(b.peer_lost());
}

#[test]
fn next_deadline_is_the_earliest_stream() {
    let mut b = SensorBoard::new(&RobotProfile::default());
    assert_eq!(b.next_deadline(), None);
    b.poll(Instant::ZERO, &SensorInputs::default());
    assert_eq!(b.next_deadline(), Some(Instant::from_millis(100)));
}
