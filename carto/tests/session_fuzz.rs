//! Issue 45: the whole-daemon fuzz property ([`carto::fuzzing::run`]) in CI, on stable: a bounded
//! number of random sessions — client bytes, board bytes, reconnects, link losses, time — and
//! none may panic, grow a buffer without bound, or drive the wheels after a STOP or a lost client
//! before the next move. The libFuzzer target (`carto/fuzz/`) and the stable mutation runner
//! (`examples/session_fuzz.rs`) run the same function for longer.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use carto::fuzzing::{Op, decode, encode, run};
use proptest::prelude::*;

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => proptest::collection::vec(any::<u8>(), 1..40).prop_map(Op::Client),
        2 => proptest::collection::vec(any::<u8>(), 1..40).prop_map(Op::Motor),
        2 => proptest::collection::vec(any::<u8>(), 1..40).prop_map(Op::Sensor),
        6 => (1u32..300).prop_map(Op::Advance),
        1 => Just(Op::Disconnect),
        2 => Just(Op::Connect),
        1 => Just(Op::MotorToggle),
        1 => Just(Op::SensorToggle),
        8 => (0u8..16).prop_map(Op::Dict),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn issue_45_random_sessions_keep_the_wheels_still_after_stop_and_stay_bounded(
        ops in proptest::collection::vec(op(), 1..120)
    ) {
        let input = encode(&ops);
        if let Err(v) = run(&input) {
            panic!("{v}\ninput: {input:02x?}");
        }
    }

    #[test]
    fn issue_45_any_bytes_are_a_valid_input(data in proptest::collection::vec(any::<u8>(), 0..2048)) {
        if let Err(v) = run(&data) {
            panic!("{v}\ninput: {data:02x?}");
        }
    }
}

#[test]
fn encode_and_decode_round_trip() {
    let ops = vec![
        Op::Connect,
        Op::Client(vec![7; 70]),
        Op::Advance(100),
        Op::Motor(vec![0xAA]),
        Op::Sensor(vec![1, 3]),
        Op::Disconnect,
        Op::MotorToggle,
        Op::SensorToggle,
        Op::Dict(5),
    ];
    let back = decode(&encode(&ops));
    // long byte ops and advances come back split, in order, with the same content
    let flat = |ops: &[Op]| -> (Vec<u8>, u32, usize) {
        let mut bytes = Vec::new();
        let mut ms = 0;
        let mut other = 0;
        for op in ops {
            match op {
                Op::Client(b) | Op::Motor(b) | Op::Sensor(b) => bytes.extend(b),
                Op::Advance(n) => ms += n,
                _ => other += 1,
            }
        }
        (bytes, ms, other)
    };
    assert_eq!(flat(&back), flat(&ops));
    assert_eq!(back.first(), Some(&Op::Connect));
    assert_eq!(back.last(), Some(&Op::Dict(5)));
}

#[test]
fn a_stop_then_silence_is_checked_over_every_step() {
    // A connected client sends a position and STOP; 3 s pass with the sensor board's keep-state.
    let mut ops = vec![Op::Connect, Op::Dict(0), Op::Dict(6)];
    for _ in 0..6 {
        ops.extend([Op::Dict(8), Op::Advance(500)]);
    }
    let outcome = run(&encode(&ops)).unwrap();
    assert_eq!(outcome.steps, 3002);
    assert!(outcome.drives >= 6, "the idle zero drive is resent every 500 ms: {outcome:?}");
    assert_eq!(outcome.moving_drives, 0);
}
