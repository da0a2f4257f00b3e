//! The Cute session against a scripted Carto that speaks bytes only.
//!
//! `ScriptedCarto` implements Carto's side of `protocols.md` §1 on a grid world (no physics):
//! it decodes Cute's frames with `protocol::link::Decoder` and answers with big-endian frames.
//! Bytes travel in arbitrary chunks (split and merged by a seeded xorshift).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cute::gridsim::World;
use cute::map::CellValue;
use cute::session::{Compat, Cute, CuteConfig, CuteEvent, MAX_BATCH_COMPAT, RECONNECT_MAX, Status, Waiting};
use cute::trajectory::PlanError;
use protocol::link::{self, Decoder, GuiMessage, MsgOrder};
use robot_model::grid::{Heading, Move};
use robot_model::time::{Duration, Instant};

/// Carto's behaviour on a grid world.
struct ScriptedCarto {
    world: World,
    pose: Option<((u8, u8), Heading)>,
    decoder: Decoder,
    out: Vec<u8>,
    batch: Vec<Move>,
    /// Like the original: ROBOT_POSITION_RECEIVED before every cartography move.
    unsolicited_rpr: bool,
    /// Answer trajectories with positions and MOVE_DONE (our Carto) or silently (the original).
    silent_trajectories: bool,
    /// Turns to refuse from now on (answered with MOVE_DONE only, heading unchanged), as our
    /// Carto does with a turn whose swept body would touch an echo it knows.
    refuse_turns: u32,
    /// Moves between neighbours (either way) whose way is not clear: a FORWARD along one is
    /// refused as our Carto refuses a corridor that is too narrow, SET_OBSTACLE_POSITION with
    /// the cell ahead then SET_ROBOT_POSITION with the robot's own cell.
    narrow: Vec<((u8, u8), (u8, u8))>,
    /// Frames received, for assertions.
    seen: Vec<GuiMessage>,
    orders: Vec<MsgOrder>,
}

impl ScriptedCarto {
    fn new(world: &str) -> ScriptedCarto {
        ScriptedCarto {
            world: World::parse(world).unwrap(),
            pose: None,
            decoder: Decoder::default(),
            out: Vec::new(),
            batch: Vec::new(),
            unsolicited_rpr: false,
            silent_trajectories: false,
            refuse_turns: 0,
            narrow: Vec::new(),
            seen: Vec::new(),
            orders: Vec::new(),
        }
    }

    fn reply(&mut self, msg: GuiMessage) {
        self.out.extend(msg.to_bytes(MsgOrder::BigEndian));
    }

    /// One FORWARD or turn; returns false if a FORWARD met an obstacle.
    fn execute(&mut self, c: Move) -> bool {
        let Some((cell, h)) = self.pose else {
            return true;
        };
        match c {
            Move::Forward => {
                let ahead = h.step(cell, self.world.rows(), self.world.cols());
                match ahead {
                    Some(n)
                        if self.narrow.iter().any(|&(a, b)| (a, b) == (cell, n) || (b, a) == (cell, n)) =>
                    {
                        self.reply(GuiMessage::SetObstaclePosition { x: n.0, y: n.1 });
                        self.reply(GuiMessage::SetRobotPosition { x: cell.0, y: cell.1 });
                        false
                    }
                    Some(n) if !self.world.is_blocked(n.0.into(), n.1.into()) => {
                        self.pose = Some((n, h));
                        self.reply(GuiMessage::SetRobotPosition { x: n.0, y: n.1 });
                        true
                    }
                    _ => {
                        let (dx, dy) = h.delta();
                        let x = (i32::from(cell.0) + dx) as u8;
                        let y = (i32::from(cell.1) + dy) as u8;
                        self.reply(GuiMessage::SetObstaclePosition { x, y });
                        false
                    }
                }
            }
            _ if self.refuse_turns > 0 => {
                self.refuse_turns -= 1;
                true
            }
            turn => {
                self.pose = Some((cell, h.after(turn)));
                true
            }
        }
    }

    fn feed(&mut self, bytes: &[u8]) {
        for item in self.decoder.feed(bytes) {
            let msg = item.expect("Cute sends valid frames");
            if let Some(order) = self.decoder.last_order() {
                self.orders.push(order);
            }
            self.seen.push(msg.clone());
            match msg {
                GuiMessage::SendRobotPosition { x, y, direction } => {
                    let h = Heading::try_from(direction).unwrap();
                    self.pose = Some(((x, y), h));
                    self.reply(GuiMessage::RobotPositionReceived);
                }
                GuiMessage::SendMoveCartography { command } => {
                    if self.unsolicited_rpr {
                        self.reply(GuiMessage::RobotPositionReceived);
                    }
                    if let Ok(c) = Move::try_from(command) {
                        self.execute(c);
                    }
                    self.reply(GuiMessage::MoveDone);
                }
                GuiMessage::SendMovesTrajectory { n_total, command } => {
                    if let Ok(c) = Move::try_from(command) {
                        self.batch.push(c);
                    }
                    if self.batch.len() == usize::from(n_total) {
                        let batch = std::mem::take(&mut self.batch);
                        if !self.silent_trajectories {
                            for c in batch {
                                if !self.execute(c) {
                                    break;
                                }
                            }
                            self.reply(GuiMessage::MoveDone);
                        }
                    }
                }
                GuiMessage::StopRobot => self.batch.clear(),
                _ => {}
            }
        }
    }

    fn true_pose(&self) -> ((u8, u8), Heading) {
        self.pose.unwrap()
    }
}

/// A seeded xorshift for chunking.
struct Chunker(u64);

impl Chunker {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Splits `bytes` into random chunks of 1..=7 bytes (or one chunk when `merge`).
    fn chunks(&mut self, bytes: &[u8]) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            let n = (1 + (self.next() % 7) as usize).min(rest.len());
            out.push(rest[..n].to_vec());
            rest = &rest[n..];
        }
        out
    }
}

/// Runs both ends until nothing moves; the clock advances 1 ms per exchange.
fn exchange(cute: &mut Cute, carto: &mut ScriptedCarto, now: &mut Instant, chunker: &mut Chunker) {
    for _ in 0..100_000 {
        let to_carto = cute.take_outgoing();
        if !to_carto.is_empty() {
            for chunk in chunker.chunks(&to_carto) {
                carto.feed(&chunk);
            }
        }
        let to_cute = std::mem::take(&mut carto.out);
        if to_carto.is_empty() && to_cute.is_empty() {
            return;
        }
        *now += Duration::from_millis(1);
        // Alternate between byte-sized splits and whole merged bursts.
        if chunker.next().is_multiple_of(2) {
            for chunk in chunker.chunks(&to_cute) {
                cute.on_bytes(*now, &chunk);
            }
        } else {
            cute.on_bytes(*now, &to_cute);
        }
        cute.poll(*now);
    }
    panic!("the exchange never settled");
}

const ROOM: &str = "\
........
..##....
..##..#.
........
.#......
";

fn config(start: (u8, u8), heading: Heading) -> CuteConfig {
    CuteConfig { rows: 5, cols: 8, start, heading, ..CuteConfig::default() }
}

#[test]
fn handshake_sends_position_first_and_waits_for_the_ack() {
    let mut cute = Cute::new(config((2, 5), Heading::West)).unwrap();
    assert_eq!(cute.next_connect_at(Instant::ZERO), Some(Instant::ZERO));
    cute.start_cartography().unwrap();
    assert!(cute.take_outgoing().is_empty(), "nothing before the connection");
    cute.on_connected(Instant::from_millis(1));
    // SEND_ROBOT_POSITION x=2 y=5 WEST, Msg big-endian.
    assert_eq!(cute.take_outgoing(), [0x00, 0x05, 0x07, 0x00, 0x02, 0x05, 0x02]);
    cute.poll(Instant::from_millis(2));
    assert!(cute.take_outgoing().is_empty(), "no move before ROBOT_POSITION_RECEIVED");
    cute.on_bytes(Instant::from_millis(3), &[0x00, 0x02, 0x08]);
    assert!(cute.take_outgoing().is_empty());
    cute.on_bytes(Instant::from_millis(4), &[0x00]);
    // First cartography move, towards the route's start (0, 0): the detour leaves West, ahead.
    assert_eq!(cute.take_outgoing(), [0x00, 0x03, 0x02, 0x00, 0x00]);
    assert_eq!(cute.take_events(), vec![CuteEvent::Connected, CuteEvent::PositionAcknowledged]);
}

#[test]
fn cartography_over_bytes_maps_every_reachable_cell() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    let mut carto = ScriptedCarto::new(ROOM);
    carto.unsolicited_rpr = true; // the original's extra ROBOT_POSITION_RECEIVED per move
    let (mut now, mut ch) = (Instant::ZERO, Chunker(0x9E37_79B9_7F4A_7C15));
    cute.on_connected(now);
    cute.start_cartography().unwrap();
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Done);
    let world = World::parse(ROOM).unwrap();
    for ((x, y), v) in cute.map().iter() {
        let blocked = world.is_blocked(x.into(), y.into());
        assert_eq!(v.is_known_free(), !blocked, "cell ({x}, {y}) is {v:?}");
    }
    let (x, y, h) = cute.robot();
    assert_eq!(((x, y), h), carto.true_pose());
    let events = cute.take_events();
    let done = events.iter().find_map(|e| match e {
        CuteEvent::MappingDone { free, obstacles, unreachable, moves } => {
            Some((*free, *obstacles, *unreachable, *moves))
        }
        _ => None,
    });
    let (free, obstacles, unreachable, moves) = done.expect("MappingDone reported");
    assert_eq!((free, obstacles, unreachable), (34, 6, 0));
    let c = cute.counters();
    assert_eq!(c.moves_sent, moves);
    assert_eq!(c.frames_out, moves + 1); // one SEND_ROBOT_POSITION
    assert_eq!(c.decode_errors, 0);
    assert_eq!(c.unsolicited, moves, "one unsolicited ROBOT_POSITION_RECEIVED per move");
    println!("session cartography: {moves} moves, {} frames in, {} out", c.frames_in, c.frames_out);
    // Every cartography frame was one move, answered before the next was sent.
    assert!(carto.seen.iter().skip(1).all(|m| matches!(m, GuiMessage::SendMoveCartography { .. })));
}

#[test]
fn a_turn_carto_refuses_is_noticed_from_the_next_reply_and_mapping_still_ends_right() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    let mut carto = ScriptedCarto::new(ROOM);
    carto.refuse_turns = 1;
    let (mut now, mut ch) = (Instant::ZERO, Chunker(7));
    cute.on_connected(now);
    cute.start_cartography().unwrap();
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(carto.refuse_turns, 0, "a turn was refused");
    assert_eq!(cute.status(), Status::Done);
    let world = World::parse(ROOM).unwrap();
    for ((x, y), v) in cute.map().iter() {
        assert_eq!(v.is_known_free(), !world.is_blocked(x.into(), y.into()), "cell ({x}, {y}) is {v:?}");
    }
    let (x, y, h) = cute.robot();
    assert_eq!(((x, y), h), carto.true_pose(), "Cute follows the heading Carto's replies show");
    let events = cute.take_events();
    assert_eq!(events.iter().filter(|e| matches!(e, CuteEvent::TurnNotMade { .. })).count(), 1, "{events:?}");
}

fn mapped_session(world: &str, rows: usize, cols: usize) -> (Cute, ScriptedCarto, Instant, Chunker) {
    let mut cute =
        Cute::new(CuteConfig { rows, cols, start: (0, 0), heading: Heading::East, ..CuteConfig::default() })
            .unwrap();
    let mut carto = ScriptedCarto::new(world);
    let (mut now, mut ch) = (Instant::ZERO, Chunker(42));
    cute.on_connected(now);
    cute.start_cartography().unwrap();
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Done);
    cute.take_events();
    (cute, carto, now, ch)
}

#[test]
fn go_to_sends_one_frame_per_command_and_reaches_the_cell() {
    let (mut cute, mut carto, mut now, mut ch) = mapped_session(ROOM, 5, 8);
    let frames_before = carto.seen.len();
    cute.go_to(1, 1).unwrap();
    assert_eq!(cute.status(), Status::Moving);
    assert_eq!(cute.map().destination(), Some((1, 1)));
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Idle);
    assert_eq!(cute.take_events(), vec![CuteEvent::Reached { x: 1, y: 1 }]);
    let (x, y, h) = cute.robot();
    assert_eq!(((x, y), h), carto.true_pose());
    assert_eq!((x, y), (1, 1));
    assert_eq!(cute.map().get(1, 1), Some(CellValue::Robot));
    assert_eq!(cute.map().count(CellValue::Waypoint), 0, "waypoints cleared on arrival");
    // One SEND_MOVES_TRAJECTORY per command, each repeating n_total.
    let frames: Vec<_> = carto.seen[frames_before..].to_vec();
    let n = frames.len();
    assert!(n >= 1);
    for f in &frames {
        assert!(matches!(f, GuiMessage::SendMovesTrajectory { n_total, .. } if usize::from(*n_total) == n));
    }
}

#[test]
fn obstacle_during_a_trajectory_aborts_and_is_marked() {
    let (mut cute, mut carto, mut now, mut ch) = mapped_session(ROOM, 5, 8);
    let (rx, ry, _) = cute.robot();
    cute.go_to(3, 0).unwrap();
    // Someone puts a box on the planned path after mapping.
    let path: Vec<(u8, u8)> =
        cute.map().iter().filter(|(_, v)| *v == CellValue::Waypoint).map(|(c, _)| c).collect();
    let block = if path.contains(&(3, 4)) { (3, 4) } else { path[path.len() / 2] };
    let mut rows: Vec<Vec<u8>> = ROOM.lines().map(|l| l.as_bytes().to_vec()).collect();
    rows[usize::from(block.0)][usize::from(block.1)] = b'#';
    let text: String = rows.iter().map(|r| format!("{}\n", String::from_utf8_lossy(r))).collect();
    carto.world = World::parse(&text).unwrap();
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Idle);
    let events = cute.take_events();
    assert!(events.contains(&CuteEvent::ObstacleMet { x: block.0, y: block.1 }), "{events:?}");
    assert_eq!(cute.map().get(block.0.into(), block.1.into()), Some(CellValue::Obstacle));
    assert_eq!(cute.map().count(CellValue::Waypoint), 0);
    let (x, y, h) = cute.robot();
    assert_eq!(((x, y), h), carto.true_pose());
    assert_ne!((x, y), (rx, ry), "the robot moved before meeting the box");
}

/// A FORWARD refused because the way is not clear (issue 42, item 4): Cute blocks that move,
/// keeps the cell unknown, maps it from another side and never marks it as an obstacle.
#[test]
fn a_way_not_clear_blocks_the_move_and_the_cell_is_mapped_another_way() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    let mut carto = ScriptedCarto::new(ROOM);
    carto.narrow = vec![((0, 0), (0, 1))];
    let (mut now, mut ch) = (Instant::ZERO, Chunker(11));
    cute.on_connected(now);
    cute.start_cartography().unwrap();
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Done);
    let events = cute.take_events();
    assert!(events.contains(&CuteEvent::WayNotClear { x: 0, y: 1 }), "{events:?}");
    let world = World::parse(ROOM).unwrap();
    for ((x, y), v) in cute.map().iter() {
        assert_eq!(v.is_known_free(), !world.is_blocked(x.into(), y.into()), "cell ({x}, {y}) is {v:?}");
    }
    assert!(cute.map().is_move_blocked((0, 0), (0, 1)));
    assert_eq!(cute.counters().unsolicited, 0, "the pair answers the FORWARD");
    let (x, y, h) = cute.robot();
    assert_eq!(((x, y), h), carto.true_pose());
}

/// The same refusal during a trajectory ends it, as an obstacle does, but the cell keeps what
/// the map held (free) and only the move is blocked.
#[test]
fn a_way_not_clear_ends_a_trajectory_without_marking_the_cell() {
    let (mut cute, mut carto, mut now, mut ch) = mapped_session(ROOM, 5, 8);
    let (rx, ry, _) = cute.robot();
    cute.go_to(3, 0).unwrap();
    let path: Vec<(u8, u8)> =
        cute.map().iter().filter(|(_, v)| *v == CellValue::Waypoint).map(|(c, _)| c).collect();
    assert!(path.len() >= 2, "{path:?}");
    // the way into the second waypoint is not clear; the robot stops in the first
    let (first, second) = (path_order(&path, (rx, ry))[0], path_order(&path, (rx, ry))[1]);
    carto.narrow = vec![(first, second)];
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Idle);
    let events = cute.take_events();
    assert!(events.contains(&CuteEvent::WayNotClear { x: second.0, y: second.1 }), "{events:?}");
    assert_eq!(cute.map().get(second.0.into(), second.1.into()), Some(CellValue::Free));
    assert!(cute.map().is_move_blocked(first, second));
    let (x, y, h) = cute.robot();
    assert_eq!(((x, y), h), carto.true_pose());
    assert_eq!((x, y), first);
}

/// The waypoints of `path` in the order a robot starting at `from` meets them (each next to
/// the one before).
fn path_order(path: &[(u8, u8)], from: (u8, u8)) -> Vec<(u8, u8)> {
    let mut order = Vec::new();
    let mut at = from;
    while let Some(&n) = path.iter().find(|&&c| !order.contains(&c) && Heading::between(at, c).is_some()) {
        order.push(n);
        at = n;
    }
    order
}

#[test]
fn stop_sends_stop_robot_and_goes_idle() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    cute.on_connected(Instant::ZERO);
    cute.on_bytes(Instant::ZERO, &[0x00, 0x02, 0x08, 0x00]);
    cute.start_cartography().unwrap();
    cute.take_outgoing();
    cute.stop();
    assert_eq!(cute.take_outgoing(), [0x00, 0x02, 0x06, 0x00]);
    assert_eq!(cute.status(), Status::Idle);
    assert!(cute.take_events().contains(&CuteEvent::Stopped));
    // A late answer to the cancelled move is tolerated and still tracked.
    cute.on_bytes(Instant::from_millis(9), &[0x00, 0x04, 0x05, 0x00, 0x00, 0x01, 0x00, 0x02, 0x03, 0x00]);
    assert_eq!((cute.robot().0, cute.robot().1), (0, 1));
    assert_eq!(cute.status(), Status::Idle);
    assert!(cute.take_outgoing().is_empty());
}

#[test]
fn disconnect_keeps_the_mission_and_reconnects_with_backoff() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    let mut carto = ScriptedCarto::new(ROOM);
    let (mut now, mut ch) = (Instant::ZERO, Chunker(7));
    cute.on_connected(now);
    cute.start_cartography().unwrap();
    // Run a few moves, then cut the line with a move in flight.
    for _ in 0..5 {
        let out = cute.take_outgoing();
        carto.feed(&out);
        now += Duration::from_millis(1);
        let back = std::mem::take(&mut carto.out);
        cute.on_bytes(now, &back);
    }
    let in_flight = cute.take_outgoing();
    assert!(!in_flight.is_empty());
    cute.on_disconnected(now);
    assert!(cute.take_events().contains(&CuteEvent::ConnectionLost));
    assert_eq!(cute.status(), Status::Mapping);
    // Back-off: 0.25 s, then doubling per failed attempt up to 4 s.
    let t0 = now;
    assert_eq!(cute.next_connect_at(now), Some(t0 + Duration::from_millis(250)));
    let mut delays = Vec::new();
    for _ in 0..7 {
        let at = cute.next_connect_at(now).unwrap();
        now = at;
        cute.on_connect_failed(now);
        delays.push((cute.next_connect_at(now).unwrap() - now).total_millis());
    }
    assert_eq!(delays, [500, 1000, 2000, 4000, 4000, 4000, 4000]);
    assert_eq!(RECONNECT_MAX, Duration::from_secs(4));
    // The new Carto knows nothing: Cute sends the position again and resumes mapping.
    let mut carto2 = ScriptedCarto::new(ROOM);
    cute.on_connected(now);
    assert!(cute.next_connect_at(now).is_none());
    exchange(&mut cute, &mut carto2, &mut now, &mut ch);
    assert!(matches!(carto2.seen[0], GuiMessage::SendRobotPosition { .. }));
    assert_eq!(cute.status(), Status::Done);
    assert_eq!(cute.counters().reconnects, 1);
    let world = World::parse(ROOM).unwrap();
    for ((x, y), v) in cute.map().iter() {
        assert_eq!(v.is_known_free(), !world.is_blocked(x.into(), y.into()));
    }
}

#[test]
fn interrupted_trajectory_is_replanned_after_reconnect() {
    let (mut cute, mut carto, mut now, mut ch) = mapped_session(ROOM, 5, 8);
    // Mapping ends at the serpentine's last cell, (4, 7); go back to the top-left corner.
    assert_eq!(carto.true_pose().0, (4, 7));
    cute.go_to(0, 0).unwrap();
    let frames = cute.take_outgoing();
    assert!(!frames.is_empty());
    cute.on_disconnected(now); // the batch never reached Carto
    cute.on_connected(now + Duration::from_millis(250));
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert_eq!(cute.status(), Status::Idle);
    assert!(cute.take_events().contains(&CuteEvent::Reached { x: 0, y: 0 }));
    assert_eq!(carto.true_pose().0, (0, 0));
}

#[test]
fn compat_explobot_2024_little_endian_trajectories_only_batches_of_50() {
    // A 1 x 120 corridor, already known free.
    let mut cute = Cute::new(CuteConfig {
        rows: 1,
        cols: 120,
        start: (0, 0),
        heading: Heading::East,
        compat: Compat::Explobot2024,
        ..CuteConfig::default()
    })
    .unwrap();
    assert!(cute.start_cartography().is_err());
    cute.on_connected(Instant::ZERO);
    assert!(cute.take_outgoing().is_empty(), "never SEND_ROBOT_POSITION to the original");
    assert!(cute.is_ready());
    // Make the corridor known (the original cannot map): simulate a previous map.
    for y in 1..120u8 {
        cute.on_bytes(Instant::ZERO, &GuiMessage::SetRobotPosition { x: 0, y }.to_bytes(MsgOrder::BigEndian));
    }
    cute.on_bytes(Instant::ZERO, &GuiMessage::SetRobotPosition { x: 0, y: 0 }.to_bytes(MsgOrder::BigEndian));
    cute.go_to(0, 119).unwrap();
    let bytes = cute.take_outgoing();
    let mut d = Decoder::default();
    let msgs: Vec<GuiMessage> = d.feed(&bytes).into_iter().map(Result::unwrap).collect();
    assert_eq!(d.last_order(), Some(MsgOrder::LittleEndian));
    assert_eq!(&bytes[..6], &[0x00, 0x04, 0x00, 0x01, 50, 0x00]);
    let n_totals: Vec<u8> = msgs
        .iter()
        .map(|m| match m {
            GuiMessage::SendMovesTrajectory { n_total, command } => {
                assert_eq!(*command, link::Command::Forward);
                *n_total
            }
            other => panic!("unexpected {other:?}"),
        })
        .collect();
    assert_eq!(n_totals.len(), 119);
    assert!(n_totals[..50].iter().all(|n| usize::from(*n) == MAX_BATCH_COMPAT));
    assert!(n_totals[50..100].iter().all(|n| *n == 50));
    assert!(n_totals[100..].iter().all(|n| *n == 19));
    assert_eq!(cute.take_events().last(), Some(&CuteEvent::TrajectorySent { commands: 119 }));
    assert_eq!(cute.status(), Status::Idle);
    assert_eq!(cute.robot().1, 119);
}

#[test]
fn compat_original_carto_silent_batches_are_fire_and_forget() {
    let world = "....\n";
    let mut cute = Cute::new(CuteConfig {
        rows: 1,
        cols: 4,
        compat: Compat::Explobot2024,
        ..CuteConfig { start: (0, 0), heading: Heading::East, ..CuteConfig::default() }
    })
    .unwrap();
    let mut carto = ScriptedCarto::new(world);
    carto.silent_trajectories = true;
    carto.pose = Some(((0, 0), Heading::East));
    cute.on_connected(Instant::ZERO);
    for y in [1u8, 2, 3, 0] {
        cute.on_bytes(
            Instant::ZERO,
            &GuiMessage::SetRobotPosition { x: 0, y }.to_bytes(MsgOrder::LittleEndian),
        );
    }
    cute.go_to(0, 3).unwrap();
    let (mut now, mut ch) = (Instant::ZERO, Chunker(3));
    exchange(&mut cute, &mut carto, &mut now, &mut ch);
    assert!(carto.orders.iter().all(|o| *o == MsgOrder::LittleEndian));
    assert_eq!(cute.status(), Status::Idle);
    assert_eq!(cute.robot().1, 3);
    // No MOVE_DONE ever comes, and no timeout is reported for it.
    cute.poll(now + Duration::from_secs(60));
    assert!(!cute.take_events().iter().any(|e| matches!(e, CuteEvent::MoveTimeout { .. })));
}

#[test]
fn move_timeout_is_reported_and_stops_the_robot() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    cute.on_connected(Instant::ZERO);
    cute.on_bytes(Instant::ZERO, &[0x00, 0x02, 0x08, 0x00]);
    cute.take_outgoing();
    cute.start_cartography().unwrap();
    assert_eq!(cute.take_outgoing(), [0x00, 0x03, 0x02, 0x00, 0x00]);
    // 50 s: a mapping turn may be six motions, each ended by Carto's own 8 s limit.
    cute.poll(Instant::from_millis(49_999));
    assert!(cute.take_outgoing().is_empty());
    cute.poll(Instant::from_millis(50_000));
    assert_eq!(cute.take_outgoing(), [0x00, 0x02, 0x06, 0x00]);
    assert_eq!(cute.status(), Status::Idle);
    assert!(cute.take_events().contains(&CuteEvent::MoveTimeout { waiting_for: Waiting::MoveDone }));
    assert_eq!(cute.counters().timeouts, 1);
}

#[test]
fn position_ack_timeout_resends_the_position() {
    let mut cute = Cute::new(config((1, 2), Heading::South)).unwrap();
    cute.on_connected(Instant::ZERO);
    let first = cute.take_outgoing();
    cute.poll(Instant::from_secs(5));
    assert_eq!(cute.take_outgoing(), first);
    assert!(cute.take_events().contains(&CuteEvent::MoveTimeout { waiting_for: Waiting::PositionAck }));
}

#[test]
fn unsolicited_and_unknown_frames_are_tolerated_and_fatal_errors_close() {
    let mut cute = Cute::new(config((0, 0), Heading::East)).unwrap();
    cute.on_connected(Instant::ZERO);
    cute.take_outgoing();
    // ACK, an extra ACK, a stray MOVE_DONE and an unknown id 0x0900, in one segment.
    let mut burst = vec![0x00, 0x02, 0x08, 0x00, 0x00, 0x02, 0x08, 0x00, 0x00, 0x02, 0x03, 0x00];
    burst.extend([0x00, 0x03, 0x09, 0x00, 0x7f]);
    cute.on_bytes(Instant::ZERO, &burst);
    let c = cute.counters();
    assert_eq!((c.frames_in, c.unsolicited, c.unknown_frames), (4, 2, 1));
    assert!(cute.is_ready());
    // Size 1 is a fatal framing error: the session drops the link and asks for a close.
    cute.on_bytes(Instant::ZERO, &[0x00, 0x01, 0x00]);
    assert!(cute.close_requested());
    assert!(!cute.is_connected());
    assert!(cute.take_events().iter().any(|e| matches!(e, CuteEvent::ProtocolError { fatal: true, .. })));
}

#[test]
fn go_to_refuses_unknown_cells_and_reports_no_path() {
    let (mut cute, _carto, _now, _ch) = mapped_session("..#.\n..#.\n", 2, 4);
    assert!(matches!(cute.go_to(0, 2), Err(PlanError::DestinationNotFree { .. })));
    assert!(matches!(cute.go_to(9, 9), Err(PlanError::OutOfBounds { .. })));
    // (0, 3) is unreachable, so it stays unknown: not a valid destination either.
    assert!(matches!(cute.go_to(0, 3), Err(PlanError::DestinationNotFree { value: CellValue::Unknown, .. })));
    // A known-free but disconnected cell gives NoPath.
    let mut cute2 = Cute::new(CuteConfig { rows: 1, cols: 3, ..CuteConfig::default() }).unwrap();
    cute2.on_connected(Instant::ZERO);
    cute2.on_bytes(Instant::ZERO, &GuiMessage::SetRobotPosition { x: 0, y: 2 }.to_bytes(MsgOrder::BigEndian));
    cute2.on_bytes(Instant::ZERO, &GuiMessage::SetRobotPosition { x: 0, y: 0 }.to_bytes(MsgOrder::BigEndian));
    cute2.on_bytes(
        Instant::ZERO,
        &GuiMessage::SetObstaclePosition { x: 0, y: 1 }.to_bytes(MsgOrder::BigEndian),
    );
    assert_eq!(cute2.go_to(0, 2), Err(PlanError::NoPath { from_x: 0, from_y: 0, to_x: 0, to_y: 2 }));
    assert!(cute2.take_events().contains(&CuteEvent::NoPath { x: 0, y: 2 }));
    // Busy while mapping.
    let mut cute3 = Cute::new(config((0, 0), Heading::East)).unwrap();
    cute3.start_cartography().unwrap();
    assert_eq!(cute3.go_to(0, 0), Err(PlanError::Busy));
}

#[test]
fn reset_map_sets_unknown_and_keeps_the_robot() {
    let (mut cute, _carto, _now, _ch) = mapped_session(ROOM, 5, 8);
    cute.reset_map();
    let (x, y, _) = cute.robot();
    assert_eq!(cute.map().count(CellValue::Unknown), 5 * 8 - 1);
    assert_eq!(cute.map().get(x.into(), y.into()), Some(CellValue::Robot));
}
