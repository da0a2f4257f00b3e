//! Issue 45: the whole-daemon fuzz property ([`carto::fuzzing::run`]) over recorded traffic.
//! Lockstep runs of four scenarios (a STOP mid-trajectory, a client reconnect, a lossy motor
//! link, a GoTo) give, per run, what Carto received from Cute and from both boards with its
//! times; cut into windows of at most [`MAX_INPUT`] bytes, each becomes a fuzz input. Every one
//! must hold the property, and together they must drive the wheels (so the "no drive after STOP"
//! check is not vacuous) and contain a STOP. They are also the fuzzers' seed corpus: with
//! `EXPLOBOT_FUZZ_SEEDS=DIR` the test writes them to DIR (`carto/fuzz/seed-corpus.sh` does it).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use carto::fuzzing::{MAX_INPUT, Op, encode, run};
use twin::record::{Dir, EndpointLog};
use twin::runner::Lockstep;
use twin::setup::RunSetup;

const SCENARIOS: [&str; 4] = ["stop-trajectory", "reconnect", "lossy-motor", "goto"];
/// Simulated time per run (5 ms steps).
const MAX_STEPS: u64 = 40_000;

fn logs(name: &str) -> Vec<EndpointLog> {
    let path = format!("../scenarios/{name}.ron");
    let loaded = RunSetup::load(std::path::Path::new(&path)).unwrap();
    let mut run = Lockstep::new(loaded, None).unwrap();
    let mut n = 0;
    while n < MAX_STEPS && run.step() {
        n += 1;
    }
    run.link_logs().to_vec()
}

/// What Carto received, in time order: (µs, op).
fn received(logs: &[EndpointLog]) -> Vec<(u64, Op)> {
    let mut events = Vec::new();
    for log in logs {
        let make: fn(Vec<u8>) -> Op = match (log.link.as_str(), log.endpoint.as_str()) {
            ("motor", "board") => Op::Motor,
            ("sensor", "board") => Op::Sensor,
            ("gui", e) if e.starts_with("cute") => Op::Client,
            _ => continue,
        };
        let is_client = log.link == "gui";
        let mut first = true;
        let mut last = 0;
        for c in log.chunks.iter().filter(|c| c.direction == Dir::Written) {
            let at = c.at.total_micros();
            if is_client && first {
                events.push((at, Op::Connect));
                first = false;
            }
            last = at;
            events.push((at, make(c.bytes.clone())));
        }
        if is_client && !first {
            events.push((last + 1, Op::Disconnect));
        }
    }
    events.sort_by_key(|(t, _)| *t);
    events
}

/// Cuts the events into inputs of at most MAX_INPUT bytes, time passing between events.
fn seeds(events: &[(u64, Op)]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut ops = Vec::new();
    let mut now_ms = 0;
    let mut client_open = false;
    for (at, op) in events {
        let at_ms = at / 1000;
        if at_ms > now_ms {
            ops.push(Op::Advance((at_ms - now_ms).min(5000) as u32));
            now_ms = at_ms;
        }
        match op {
            Op::Connect => client_open = true,
            Op::Disconnect => client_open = false,
            _ => {}
        }
        ops.push(op.clone());
        if encode(&ops).len() > MAX_INPUT - 1024 {
            out.push(encode(&ops));
            // the next window starts with the client connected again, if it was
            ops = if client_open { vec![Op::Connect] } else { Vec::new() };
        }
    }
    if !ops.is_empty() {
        out.push(encode(&ops));
    }
    out
}

#[test]
fn issue_45_recorded_sessions_hold_the_fuzz_property_and_seed_the_fuzzers() {
    let write_to = std::env::var_os("EXPLOBOT_FUZZ_SEEDS").map(std::path::PathBuf::from);
    let (mut moving, mut stops, mut total) = (0, 0, 0);
    for name in SCENARIOS {
        let events = received(&logs(name));
        stops += events
            .iter()
            .filter(
                |(_, op)| matches!(op, Op::Client(b) if b.windows(4).any(|w| w == [0x00, 0x02, 0x06, 0x00])),
            )
            .count();
        for (i, seed) in seeds(&events).into_iter().enumerate() {
            let outcome = run(&seed).unwrap_or_else(|v| panic!("{name} window {i}: {v}"));
            moving += outcome.moving_drives;
            total += 1;
            if let Some(dir) = &write_to {
                std::fs::create_dir_all(dir).unwrap();
                std::fs::write(dir.join(format!("{name}-{i:02}")), &seed).unwrap();
            }
        }
    }
    eprintln!("{total} seeds, {moving} moving drive frames, {stops} STOP frames");
    assert!(moving > 100, "the recorded sessions never drove the wheels: the property is vacuous");
    assert!(stops >= 1, "no recorded STOP");
}
