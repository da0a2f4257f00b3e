//! Issue 14 (Cute side): our Cute against a scripted peer that behaves like the original 2024
//! Carto, byte for byte, as `shared/spec/protocols-research.md` §1.2 and §1.5 record it.
//!
//! Cute runs in its sans-IO runtime ([`CuteRuntime`]) over in-memory links; every test passes the
//! time in. The peer reads what Cute wrote in each step as one chunk, the way the original reads a
//! segment, and reports a frame split across chunks, a batch over 50, SEND_ROBOT_POSITION or
//! SEND_MOVE_CARTOGRAPHY (which crash the original) as failures.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cute::map::CellValue;
use cute::notices::describe;
use cute::session::{COMPAT_HINT, Compat, Cute, CuteConfig, CuteEvent, Status, Waiting};
use cute::{CuteRuntime, Map, load_map};
use protocol::link::{GuiMessage, MsgOrder};
use robot_model::grid::{Heading, Move};
use robot_model::time::Instant;
use transport::{Link, Listener, MemConnector, MemLink, MemListener, MockClock, mem_listener};

/// The original Cute's bytes for robot (0, 0) facing EAST and destination (2, 3): F F F R F F,
/// six frames `00 04 00 01 06 cc` (research §1.6, observed from the original GUI).
const ORIGINAL_CUTE_0_0_TO_2_3: [u8; 36] = [
    0x00, 0x04, 0x00, 0x01, 0x06, 0x00, //
    0x00, 0x04, 0x00, 0x01, 0x06, 0x00, //
    0x00, 0x04, 0x00, 0x01, 0x06, 0x00, //
    0x00, 0x04, 0x00, 0x01, 0x06, 0x01, //
    0x00, 0x04, 0x00, 0x01, 0x06, 0x00, //
    0x00, 0x04, 0x00, 0x01, 0x06, 0x00, //
];

/// The original Cute's STOP button: `00 02 00 06` (research §1.6, observed).
const ORIGINAL_STOP: [u8; 4] = [0x00, 0x02, 0x00, 0x06];

/// The original Carto (research §1.5): it decodes `Msg` as `ntohs((b2 << 8) | b3)` so only
/// little-endian ids match; trajectories fill a list of 50 with a counter and run when a frame's
/// `n` completes it, silently; STOP_ROBOT makes it skip the next complete batch; nothing is ever
/// answered. The robot is the grid pose the motors would reach (no obstacle check).
struct OriginalCarto {
    link: MemLink,
    list: [u8; 50],
    counter: usize,
    skip_next: bool,
    robot: ((u8, u8), Heading),
    rows: usize,
    cols: usize,
    /// Every byte received.
    raw: Vec<u8>,
    executed: Vec<Vec<u8>>,
    skipped: Vec<Vec<u8>>,
    /// Big-endian (or unknown) ids, ignored as the original does.
    ignored: Vec<[u8; 2]>,
    /// What would have crashed or desynchronised the original.
    failures: Vec<String>,
}

impl OriginalCarto {
    fn new(link: MemLink, robot: ((u8, u8), Heading), rows: usize, cols: usize) -> OriginalCarto {
        OriginalCarto {
            link,
            list: [0; 50],
            counter: 0,
            skip_next: false,
            robot,
            rows,
            cols,
            raw: Vec::new(),
            executed: Vec::new(),
            skipped: Vec::new(),
            ignored: Vec::new(),
            failures: Vec::new(),
        }
    }

    /// Reads one chunk (what Cute wrote since the last call) and handles its frames.
    fn pump(&mut self) {
        let mut chunk = Vec::new();
        // A link Cute closed reads as an error; the bytes before it are in `chunk`.
        let _closed = self.link.read_available(&mut chunk).is_err();
        self.raw.extend_from_slice(&chunk);
        let mut rest = &chunk[..];
        while !rest.is_empty() {
            if rest.len() < 2 {
                self.failures.push(format!("half a Size field at the end of a chunk: {rest:02x?}"));
                return;
            }
            let size = i16::from_be_bytes([rest[0], rest[1]]);
            if !(2..=22).contains(&size) {
                self.failures.push(format!("Size {size} overflows the original's buffers"));
                return;
            }
            let end = 2 + size as usize;
            if rest.len() < end {
                self.failures.push(format!("frame split across chunks: {rest:02x?}"));
                return;
            }
            self.frame([rest[2], rest[3]], &rest[4..end]);
            rest = &rest[end..];
        }
    }

    fn frame(&mut self, msg: [u8; 2], data: &[u8]) {
        // ntohs((b2 << 8) | b3) on a little-endian host.
        match u16::from_le_bytes(msg) {
            0x0100 => self.trajectory(data[0], data[1]),
            0x0600 => self.skip_next = true,
            0x0200 | 0x0700 => self.failures.push(format!("{msg:02x?} crashes the original (NULL pose)")),
            _ => self.ignored.push(msg),
        }
    }

    fn trajectory(&mut self, n: u8, command: u8) {
        if self.counter >= self.list.len() || usize::from(n) > self.list.len() {
            self.failures.push(format!("batch of {n} overflows the list of 50"));
            return;
        }
        self.list[self.counter] = command;
        if (self.counter as i32) < i32::from(n) - 1 {
            self.counter += 1;
            return;
        }
        self.counter = 0;
        let batch = self.list[..usize::from(n)].to_vec();
        if std::mem::take(&mut self.skip_next) {
            self.skipped.push(batch);
            return;
        }
        for &c in &batch {
            let (cell, h) = self.robot;
            self.robot = match Move::from_u8(c) {
                Some(Move::Forward) => match h.step(cell, self.rows, self.cols) {
                    Some(next) => (next, h),
                    None => {
                        self.failures.push(format!("drove off the map from {cell:?}"));
                        (cell, h)
                    }
                },
                Some(turn) => (cell, h.after(turn)),
                None => (cell, h), // 3 = STOP: PWM 0
            };
        }
        self.executed.push(batch);
    }
}

fn at_ms(ms: u64) -> Instant {
    Instant::from_millis(ms)
}

/// A runtime for `config` and the original Carto it dialled at 0 ms.
fn connect(config: CuteConfig) -> (CuteRuntime<MemConnector>, OriginalCarto, MemListener) {
    let robot = (config.start, config.heading);
    let (rows, cols) = (config.rows, config.cols);
    let (mut listener, connector) = mem_listener(None, MockClock::new());
    let mut rt = CuteRuntime::new(Cute::new(config).unwrap(), connector);
    rt.step(Instant::ZERO);
    let (link, _) = listener.accept().unwrap().expect("Cute dials at once");
    let mut carto = OriginalCarto::new(link, robot, rows, cols);
    carto.pump();
    (rt, carto, listener)
}

fn compat(rows: usize, cols: usize) -> CuteConfig {
    CuteConfig {
        rows,
        cols,
        start: (0, 0),
        heading: Heading::East,
        compat: Compat::Explobot2024,
        ..Default::default()
    }
}

/// One step at `ms` running `act`, then the original reads what was written.
fn act(rt: &mut CuteRuntime<MemConnector>, carto: &mut OriginalCarto, ms: u64, act: impl FnOnce(&mut Cute)) {
    rt.step_with(at_ms(ms), act);
    carto.pump();
}

fn believed(rt: &CuteRuntime<MemConnector>) -> ((u8, u8), Heading) {
    let (x, y, h) = rt.cute().robot();
    ((x, y), h)
}

#[test]
fn issue_14_compat_click_on_an_unknown_map_sends_the_originals_bytes() {
    let (mut rt, mut carto, _l) = connect(compat(20, 20));
    assert!(carto.raw.is_empty(), "nothing on connect: no SEND_ROBOT_POSITION to the original");
    assert_eq!(rt.cute().map().count(CellValue::Unknown), 399);
    act(&mut rt, &mut carto, 10, |c| c.go_to(2, 3).unwrap());
    assert_eq!(carto.raw, ORIGINAL_CUTE_0_0_TO_2_3);
    assert_eq!(carto.failures, Vec::<String>::new());
    assert_eq!(carto.executed, [vec![0, 0, 0, 1, 0, 0]]);
    assert_eq!(carto.robot, ((2, 3), Heading::South));
    assert_eq!(believed(&rt), carto.robot);
    let events = rt.cute_mut().take_events();
    let warning = CuteEvent::PlannedThroughUnknown { x: 2, y: 3, cells: 5 };
    assert_eq!(events, [CuteEvent::Connected, warning.clone(), CuteEvent::TrajectorySent { commands: 6 }]);
    assert!(describe(&warning).contains("through 5 unknown cells planned as free"));
    // The path is shown, then the cells it crossed are unknown again: nobody has seen them.
    assert_eq!(rt.cute().map().count(CellValue::Waypoint), 4);
    act(&mut rt, &mut carto, 20, |c| c.go_to(2, 3).unwrap()); // the robot's cell: nothing to send
    let map = rt.cute().map();
    assert_eq!((map.count(CellValue::Waypoint), map.count(CellValue::Unknown)), (0, 398));
    assert_eq!(
        (map.get(0, 0), map.get(0, 2), map.robot()),
        (Some(CellValue::Free), Some(CellValue::Unknown), Some((2, 3)))
    );
}

#[test]
fn issue_14_compat_long_trajectories_go_in_complete_batches_of_at_most_50() {
    let (mut rt, mut carto, _l) = connect(compat(3, 70));
    act(&mut rt, &mut carto, 10, |c| c.go_to(2, 69).unwrap());
    assert_eq!(carto.failures, Vec::<String>::new());
    let sizes: Vec<usize> = carto.executed.iter().map(Vec::len).collect();
    let total: usize = sizes.iter().sum();
    assert!(total > 71 && total <= 100, "71 FORWARDs and a turn or two: {total}");
    assert_eq!(sizes, [50, total - 50]);
    assert_eq!(carto.robot.0, (2, 69));
    assert_eq!(believed(&rt), carto.robot);
    // Every frame is Size 4, Msg 0x0100 little-endian, and repeats its batch's length.
    assert_eq!(carto.raw.len(), 6 * total);
    for (i, frame) in carto.raw.chunks(6).enumerate() {
        assert_eq!(frame[..4], [0x00, 0x04, 0x00, 0x01], "frame {i}");
        assert_eq!(usize::from(frame[4]), if i < 50 { 50 } else { total - 50 }, "frame {i}");
    }
    // Once the path is cleared, only the start (left) and the robot's cell are known.
    act(&mut rt, &mut carto, 20, |c| c.go_to(2, 69).unwrap());
    assert_eq!(rt.cute().map().count(CellValue::Unknown), 3 * 70 - 2);
}

#[test]
fn issue_14_compat_stop_then_the_next_batch_is_dropped_and_the_pose_kept() {
    let known = Map::parse("5111\n1111\n").unwrap();
    let config = compat(0, 0).with_map(known, None).unwrap();
    let (mut rt, mut carto, _l) = connect(config);
    act(&mut rt, &mut carto, 10, |c| c.go_to(0, 3).unwrap());
    assert_eq!((carto.robot, believed(&rt)), (((0, 3), Heading::East), ((0, 3), Heading::East)));
    assert!(!rt.cute().batch_drop_pending());

    let before = carto.raw.len();
    act(&mut rt, &mut carto, 20, Cute::stop);
    assert_eq!(carto.raw[before..], ORIGINAL_STOP);
    assert!(rt.cute().batch_drop_pending());
    rt.cute_mut().take_events();

    let before = carto.raw.len();
    act(&mut rt, &mut carto, 30, |c| c.go_to(1, 0).unwrap());
    assert_eq!(carto.skipped.len(), 1, "the batch goes out, so that the original re-arms");
    let commands = carto.skipped[0].len();
    assert_eq!(carto.raw.len() - before, 6 * commands);
    assert_eq!(carto.skipped[0].iter().filter(|c| **c == 0).count(), 4, "4 FORWARDs");
    assert_eq!(carto.robot, ((0, 3), Heading::East), "the original did not move");
    assert_eq!(believed(&rt), carto.robot, "Cute keeps the pose");
    let events = rt.cute_mut().take_events();
    assert_eq!(events, [CuteEvent::BatchDropped { commands, x: 0, y: 3 }]);
    assert!(
        describe(&events[0]).contains(&format!("the 2024 Carto drops this batch of {commands} commands"))
    );
    assert_eq!(rt.cute().map().count(CellValue::Waypoint) + rt.cute().map().count(CellValue::Destination), 0);
    assert_eq!(rt.cute().status(), Status::Idle);
    assert!(!rt.cute().batch_drop_pending());

    // Clicked again, the same trajectory runs, and belief and robot agree.
    act(&mut rt, &mut carto, 40, |c| c.go_to(1, 0).unwrap());
    assert_eq!(carto.executed.len(), 2);
    assert_eq!(carto.robot.0, (1, 0));
    assert_eq!(believed(&rt), carto.robot);
    assert_eq!(carto.failures, Vec::<String>::new());
}

#[test]
fn issue_14_compat_a_dropped_long_trajectory_sends_only_its_first_batch() {
    let (mut rt, mut carto, _l) = connect(compat(1, 80));
    act(&mut rt, &mut carto, 10, Cute::stop);
    act(&mut rt, &mut carto, 20, |c| c.go_to(0, 79).unwrap());
    // 79 FORWARDs would be two batches; the second would run from the wrong cell.
    assert_eq!(carto.raw.len(), 4 + 50 * 6);
    assert_eq!((carto.skipped.len(), carto.executed.len()), (1, 0));
    assert_eq!(believed(&rt), ((0, 0), Heading::East));
    assert_eq!(carto.robot, ((0, 0), Heading::East));
    act(&mut rt, &mut carto, 30, |c| c.go_to(0, 79).unwrap());
    assert_eq!(carto.robot, ((0, 79), Heading::East));
    assert_eq!(believed(&rt), carto.robot);
}

/// Steps every 100 ms up to `end_ms`; returns `(ms, event)` for every event.
fn run(rt: &mut CuteRuntime<MemConnector>, carto: &mut OriginalCarto, end_ms: u64) -> Vec<(u64, CuteEvent)> {
    run_from(rt, carto, 100, end_ms)
}

/// Steps every 100 ms from `from_ms` to `end_ms`; returns `(ms, event)` for every event.
fn run_from(
    rt: &mut CuteRuntime<MemConnector>,
    carto: &mut OriginalCarto,
    from_ms: u64,
    end_ms: u64,
) -> Vec<(u64, CuteEvent)> {
    let mut out = Vec::new();
    for ms in (from_ms..=end_ms).step_by(100) {
        act(rt, carto, ms, |_| {});
        out.extend(rt.cute_mut().take_events().into_iter().map(|e| (ms, e)));
    }
    out
}

#[test]
fn issue_14_default_mode_hints_at_compat_after_three_unanswered_position_requests() {
    let config = CuteConfig { rows: 20, cols: 20, ..Default::default() };
    let (mut rt, mut carto, _l) = connect(config);
    let events = run(&mut rt, &mut carto, 25_000);
    let timeouts: Vec<u64> = events
        .iter()
        .filter(|(_, e)| *e == CuteEvent::MoveTimeout { waiting_for: Waiting::PositionAck })
        .map(|(ms, _)| *ms)
        .collect();
    assert_eq!(timeouts, [5_000, 10_000, 15_000, 20_000, 25_000]);
    let hints: Vec<u64> =
        events.iter().filter(|(_, e)| *e == CuteEvent::CompatHint).map(|(ms, _)| *ms).collect();
    assert_eq!(hints, [15_000], "once, when the third request goes unanswered");
    assert_eq!(
        describe(&CuteEvent::CompatHint),
        "no answer to SEND_ROBOT_POSITION — if this is the 2024 Carto, start Cute with --compat explobot-2024"
    );
    assert_eq!(describe(&CuteEvent::CompatHint), COMPAT_HINT);
    // The original ignored all six big-endian SEND_ROBOT_POSITION frames (and did not crash).
    assert_eq!(carto.ignored, [[0x07, 0x00]; 6]);
    assert_eq!(carto.failures, Vec::<String>::new());
}

#[test]
fn issue_14_an_answer_restarts_the_count_before_the_hint() {
    let config = CuteConfig { rows: 20, cols: 20, ..Default::default() };
    let (mut rt, mut carto, mut listener) = connect(config);
    let mut events = run(&mut rt, &mut carto, 12_000); // two requests unanswered
    carto.link.write(&GuiMessage::RobotPositionReceived.to_bytes(MsgOrder::BigEndian)).unwrap();
    events.extend(run_from(&mut rt, &mut carto, 12_100, 13_000));
    assert!(rt.cute().is_ready());
    // The link drops; on the next connection the server never answers again.
    rt.disconnect(at_ms(13_000));
    let mut hint_at = None;
    for ms in (13_100..=30_000).step_by(100) {
        rt.step(at_ms(ms));
        if let Some((link, _)) = listener.accept().unwrap() {
            carto.link = link;
        }
        carto.pump();
        for e in rt.cute_mut().take_events() {
            if e == CuteEvent::CompatHint {
                assert_eq!(hint_at.replace(ms), None, "one hint");
            }
        }
    }
    assert!(!events.iter().any(|(_, e)| *e == CuteEvent::CompatHint), "{events:?}");
    // Reconnected at 13.3 s (250 ms back-off, 100 ms steps): timeouts at 18.3, 23.3, 28.3 s.
    assert_eq!(hint_at, Some(28_300), "three more unanswered requests, not one");
}

#[test]
fn issue_14_map_file_good_and_bad() {
    let dir = std::env::temp_dir().join(format!("compat-cute-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("room.map");
    std::fs::write(&good, "# a wall in column 1, open at the bottom\n5 0 1\n1 0 1\n1 1 1\n").unwrap();
    let map = load_map(&good).unwrap();
    let (mut rt, mut carto, _l) = connect(compat(0, 0).with_map(map, None).unwrap());
    act(&mut rt, &mut carto, 10, |c| c.go_to(0, 2).unwrap());
    assert_eq!(carto.executed, [vec![1, 0, 0, 2, 0, 0, 2, 0, 0]], "around the known wall");
    assert_eq!(believed(&rt), carto.robot);
    assert!(
        !rt.cute_mut().take_events().iter().any(|e| matches!(e, CuteEvent::PlannedThroughUnknown { .. }))
    );

    let bad = dir.join("bad.map");
    std::fs::write(&bad, "111\n101\n1 1 7\n").unwrap();
    let err = load_map(&bad).unwrap_err().to_string();
    assert_eq!(err, format!("{}:3:5: '7' is not a cell value (0..=5)", bad.display()));
    std::fs::write(&bad, "1111\n111\n").unwrap();
    let err = load_map(&bad).unwrap_err().to_string();
    assert!(err.ends_with("bad.map:2:4: 3 cells on this row, expected 4 as on the first row"), "{err}");
    let err = load_map(&dir).unwrap_err().to_string();
    assert!(err.contains("not a regular file"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
