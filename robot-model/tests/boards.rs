//! Exchange tests: a scripted Carto-side peer talks to the board twins with protocol bytes only.

use std::collections::BTreeSet;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use protocol::motor::{self, ChecksumPolicy, MotorCommand, MotorPacket};
use protocol::sensor::{self, CommandId, SensorPacket};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot_model::boards::{MotorBoard, SensorBoard, SensorInputs};
use robot_model::motor::MotorModel;
use robot_model::profile::RobotProfile;
use robot_model::time::{Duration, Instant};

const STEP: Duration = Duration::from_millis(5);

fn drive_v2(vx: i8, vy: i8, omega: i8) -> Vec<u8> {
    MotorPacket::Drive(MotorCommand::V2 { vx, vy, omega, speed_ratio: 6, reserved: [0; 2] }).to_bytes()
}

/// Carto's side of the motor line: decodes telemetry frames.
fn telemetry(decoder: &mut motor::Decoder, bytes: &[u8]) -> Vec<motor::Telemetry> {
    decoder
        .feed(bytes)
        .into_iter()
        .map(|r| match r {
            Ok(MotorPacket::Telemetry(t)) => t,
            other => unreachable!("carto expected telemetry, got {other:?}"),
        })
        .collect()
}

#[test]
fn drive_v2_forward_50_percent_reports_settled_wheel_rpm() {
    let profile = RobotProfile::default();
    let mut board = MotorBoard::new(&profile);
    let mut motors: [MotorModel; 4] = core::array::from_fn(|_| MotorModel::from_profile(&profile));
    let mut carto = motor::Decoder::new(ChecksumPolicy::Sum);
    let mut reports = Vec::new();
    let mut now = Instant::ZERO;
    while now < Instant::from_millis(1000) {
        if now.total_micros().is_multiple_of(100_000) {
            board.receive(now, &drive_v2(50, 0, 0)); // Carto refreshes the command at 10 Hz
        }
        for t in telemetry(&mut carto, &board.poll(now)) {
            reports.push((now, t));
        }
        // Physics step from `now` to `now + STEP`, reported back for the next telemetry.
        let setpoints = board.wheel_setpoints_rpm();
        let measured: [f32; 4] = core::array::from_fn(|i| motors[i].step(setpoints[i], STEP));
        board.set_measured(measured);
        now += STEP;
    }
    // 20 Hz for 1 s.
    assert_eq!(reports.len(), 20);
    // Expected: 50 % of 300 rpm on every wheel, reached through the 80 ms first-order lag.
    let (_, first) = &reports[0];
    assert_eq!(first.wheel_rpm, [0.0; 4], "first report, at the command: wheels still at rest");
    let (_, settled) = reports.last().unwrap();
    for rpm in settled.wheel_rpm {
        assert!((rpm - 150.0).abs() < 0.01, "settled rpm {rpm}");
    }
    assert_eq!(settled.motor_power, [50.0; 4]);
    // Monotonic rise towards the setpoint.
    for pair in reports.windows(2) {
        assert!(pair[1].1.wheel_rpm[0] >= pair[0].1.wheel_rpm[0]);
    }
    // After 80 ms (τ) the model is at 63 %: the report at 100 ms shows 150·(1 − e^(−100/80)).
    let (t, at_100) = &reports[2];
    assert_eq!(*t, Instant::from_millis(100));
    let want = 150.0 * (1.0 - (-100.0f32 / 80.0).exp());
    assert!((at_100.wheel_rpm[0] - want).abs() < 0.01, "{} vs {want}", at_100.wheel_rpm[0]);
}

#[test]
fn watchdog_zeroes_setpoints_after_600_ms_without_drive_frames() {
    let profile = RobotProfile::default();
    let mut board = MotorBoard::new(&profile);
    let mut carto = motor::Decoder::new(ChecksumPolicy::Sum);
    board.receive(Instant::ZERO, &drive_v2(30, 20, -10));
    let mut now = Instant::ZERO;
    let mut last_power = [f32::NAN; 4];
    while now <= Instant::from_millis(600) {
        for t in telemetry(&mut carto, &board.poll(now)) {
            last_power = t.motor_power;
        }
        if now == Instant::from_millis(495) {
            assert_ne!(board.wheel_setpoints_rpm(), [0.0; 4], "still driving before the timeout");
        }
        now += STEP;
    }
    assert_eq!(board.wheel_setpoints_rpm(), [0.0; 4]);
    assert_eq!(last_power, [0.0; 4], "telemetry reports the stop");
    assert!(board.watchdog_tripped());
    assert_eq!(board.counters().watchdog_trips, 1);
    // A new drive frame re-arms it.
    board.receive(now, &drive_v2(30, 0, 0));
    assert_eq!(board.wheel_setpoints_rpm(), [90.0; 4]);
    assert!(!board.watchdog_tripped());
}

#[test]
fn keep_state_sequence_wraps_ffff_to_0() {
    let mut profile = RobotProfile::default();
    let sb = &mut profile.sensor_board;
    (sb.distance_hz, sb.navx_hz, sb.encoder_hz, sb.bumper_heartbeat_hz) = (0.0, 0.0, 0.0, 0.0);
    let mut board = SensorBoard::new(&profile);
    let mut carto = sensor::Decoder::new();
    let inputs = SensorInputs::default();
    let mut sequences = Vec::new();
    let mut now = Instant::ZERO;
    while sequences.len() < 65_537 {
        for p in carto.feed(&board.poll(now, &inputs)) {
            match p {
                Ok(SensorPacket::KeepState { status: 1, sequence }) => sequences.push(sequence),
                Ok(SensorPacket::Reading(_)) => {} // the bumper's first report
                other => panic!("{other:?}"),
            }
        }
        now += Duration::from_millis(500);
    }
    assert_eq!(sequences[0], 1);
    assert_eq!(sequences[65_533..], [0xFFFE, 0xFFFF, 0, 1]);
    assert!(sequences.windows(2).all(|w| w[1] == w[0].wrapping_add(1)));
}

#[test]
fn one_percent_corrupted_bytes_are_counted_and_dropped_good_frames_applied() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5EED_0003);
    let mut board = MotorBoard::new(&RobotProfile::default());
    let mut intact = BTreeSet::new();
    let mut sent_cmds = BTreeSet::new();
    let (mut sent, mut corrupted_frames, mut sync_hits) = (0usize, 0usize, 0usize);
    let mut applied_seen = Vec::new();
    for i in 0..3000u32 {
        // Unique command per frame; every value in 0..=100 so no payload byte is 0xAA.
        let cmd = ((i % 101) as i8, ((i / 101) % 101) as i8, ((i * 7) % 101) as i8);
        let mut bytes = drive_v2(cmd.0, cmd.1, cmd.2);
        let mut hit = false;
        for (k, b) in bytes.iter_mut().enumerate() {
            if rng.random_bool(0.01) {
                *b ^= 1 << rng.random_range(0..8);
                hit = true;
                sync_hits += usize::from(k == 0);
            }
        }
        sent_cmds.insert(cmd);
        if hit {
            corrupted_frames += 1;
        } else {
            intact.insert(cmd);
        }
        sent += 1;
        let now = Instant::from_millis(u64::from(i) * 10);
        for b in bytes {
            let before = board.counters().drive_frames;
            board.receive(now, &[b]);
            if board.counters().drive_frames == before + 1
                && let Some(MotorCommand::V2 { vx, vy, omega, .. }) = board.last_command()
            {
                applied_seen.push((vx, vy, omega));
            }
        }
    }
    // A final clean stop frame is applied.
    board.receive(Instant::from_secs(31), &drive_v2(0, 0, 0));
    assert_eq!(board.wheel_setpoints_rpm(), [0.0; 4]);

    let c = board.counters();
    let bad = c.bad_checksums + c.framing_errors;
    eprintln!(
        "sent {sent}, corrupted {corrupted_frames} ({sync_hits} on the start byte), intact {}, \
         bad checksums {}, framing errors {}, drive frames applied {}",
        intact.len(),
        c.bad_checksums,
        c.framing_errors,
        c.drive_frames - 1
    );
    assert!(corrupted_frames > 200 && corrupted_frames < 400, "{corrupted_frames} of {sent}");
    // Every corrupted frame whose start byte survived is rejected (a sum checksum catches any
    // single-bit error); a hit start byte just loses the frame.
    assert!(
        bad as usize >= (corrupted_frames - sync_hits) * 9 / 10,
        "bad {bad}, corrupted {corrupted_frames}"
    );
    // Good frames still get through; corrupted ones almost never do (see below).
    let applied = c.drive_frames as usize - 1;
    assert!(
        applied + 2 >= intact.len() && applied <= intact.len() + 2,
        "applied {applied}, intact {}",
        intact.len()
    );
    // No corrupted motion value is ever applied: every applied (vx, vy, omega) was sent as such.
    assert!(applied_seen.iter().all(|cmd| sent_cmds.contains(cmd)));
    // The sum checksum's blind spot: two flips of the same bit that cancel in the sum. With this
    // seed it happens twice, both times in bytes the board ignores (speed_ratio, reserved) plus
    // the checksum byte, so the motion values were intact.
    let undetected: Vec<_> = applied_seen.iter().filter(|cmd| !intact.contains(cmd)).collect();
    eprintln!("accepted although corrupted: {undetected:?}");
    assert!(undetected.len() <= 2, "{undetected:?}");
    assert!(applied_seen.len() * 10 >= intact.len() * 9);
}

/// Counts WARN events (a minimal tracing subscriber; no extra dependency).
struct WarnCounter(Arc<AtomicUsize>);

impl tracing::Subscriber for WarnCounter {
    fn enabled(&self, _: &tracing::Metadata<'_>) -> bool {
        true
    }
    fn new_span(&self, _: &tracing::span::Attributes<'_>) -> tracing::span::Id {
        tracing::span::Id::from_u64(1)
    }
    fn record(&self, _: &tracing::span::Id, _: &tracing::span::Record<'_>) {}
    fn record_follows_from(&self, _: &tracing::span::Id, _: &tracing::span::Id) {}
    fn event(&self, event: &tracing::Event<'_>) {
        if *event.metadata().level() == tracing::Level::WARN {
            self.0.fetch_add(1, Ordering::SeqCst);
        }
    }
    fn enter(&self, _: &tracing::span::Id) {}
    fn exit(&self, _: &tracing::span::Id) {}
}

fn bytes_per_sec_over(board: &mut SensorBoard, secs: u64) -> f32 {
    let before = board.counters().bytes_sent;
    let inputs = SensorInputs { distance_cm: Some(80.0), heading_deg: 12.0, ..Default::default() };
    let mut now = Instant::ZERO;
    let mut keep_seq = 1u16;
    while now < Instant::from_secs(secs) {
        if now.total_micros().is_multiple_of(500_000) {
            // Carto's keep-state at 2 Hz, so the peer never counts as lost.
            board.receive(now, &SensorPacket::KeepState { status: 2, sequence: keep_seq }.to_bytes());
            keep_seq = keep_seq.wrapping_add(1);
        }
        board.poll(now, &inputs);
        now += STEP;
    }
    (board.counters().bytes_sent - before) as f32 / secs as f32
}

#[test]
fn default_sensor_rates_fit_9600_baud_when_measured() {
    let mut board = SensorBoard::new(&RobotProfile::default());
    let measured = bytes_per_sec_over(&mut board, 20);
    eprintln!(
        "default rates: planned {} B/s, measured {measured} B/s, budget {} B/s",
        board.planned_bytes_per_sec(),
        board.budget_bytes_per_sec()
    );
    assert!((measured - board.planned_bytes_per_sec()).abs() < 5.0, "measured {measured} B/s");
    assert!(measured < board.budget_bytes_per_sec());
    assert!(!board.peer_lost());
}

#[test]
fn sensor_rates_above_9600_baud_fire_one_warning() {
    let warnings = Arc::new(AtomicUsize::new(0));
    let mut profile = RobotProfile::default();
    profile.sensor_board.navx_hz = 25.0; // 25 × 42 B alone = 1050 B/s > 960 B/s
    let mut board = tracing::subscriber::with_default(WarnCounter(warnings.clone()), || {
        let mut board = SensorBoard::new(&profile);
        // Making it worse does not warn again.
        board.receive(
            Instant::ZERO,
            &SensorPacket::Command { id: CommandId::SetDistancePeriod, parameter: 20 }.to_bytes(),
        );
        board
    });
    assert_eq!(warnings.load(Ordering::SeqCst), 1);
    assert!(board.budget_exceeded() && board.budget_warned());
    let measured = bytes_per_sec_over(&mut board, 10);
    eprintln!(
        "navx 25 Hz + distance 50 Hz: planned {} B/s, measured {measured} B/s, budget {} B/s",
        board.planned_bytes_per_sec(),
        board.budget_bytes_per_sec()
    );
    assert!(measured > board.budget_bytes_per_sec(), "measured {measured} B/s");
    assert!((measured - board.planned_bytes_per_sec()).abs() < 5.0);
}

#[test]
fn distance_period_command_can_push_the_rates_over_budget() {
    let warnings = Arc::new(AtomicUsize::new(0));
    let board = tracing::subscriber::with_default(WarnCounter(warnings.clone()), || {
        let mut board = SensorBoard::new(&RobotProfile::default());
        assert_eq!(warnings.load(Ordering::SeqCst), 0);
        // 5 ms → 200 Hz × 10 B = 2000 B/s of distance frames.
        board.receive(
            Instant::ZERO,
            &SensorPacket::Command { id: CommandId::SetDistancePeriod, parameter: 5 }.to_bytes(),
        );
        board
    });
    assert_eq!(warnings.load(Ordering::SeqCst), 1);
    assert!(board.budget_exceeded());
}

#[test]
fn peer_lost_when_carto_keep_state_stops_and_back_when_it_resumes() {
    let mut board = SensorBoard::new(&RobotProfile::default());
    let inputs = SensorInputs::default();
    let mut seq = 1u16;
    let mut lost_at = None;
    let mut now = Instant::ZERO;
    while now < Instant::from_secs(6) {
        let ms = now.total_millis();
        let carto_alive = !(2000..4000).contains(&ms); // Carto silent from 2 s to 4 s
        if carto_alive && now.total_micros().is_multiple_of(500_000) {
            board.receive(now, &SensorPacket::KeepState { status: 2, sequence: seq }.to_bytes());
            seq = seq.wrapping_add(1);
        }
        board.poll(now, &inputs);
        if board.peer_lost() && lost_at.is_none() {
            lost_at = Some(now);
        }
        if ms >= 4000 {
            assert!(!board.peer_lost(), "cleared by the keep-state at 4 s");
        }
        now += STEP;
    }
    // Last keep-state at 1.5 s; lost once more than 1.5 s passed.
    assert_eq!(lost_at, Some(Instant::from_millis(3005)));
    assert_eq!(board.counters().peer_lost_events, 1);
    assert_eq!(board.counters().peer_sequence_gaps, 0);
}
