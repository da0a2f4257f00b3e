//! Twenty generated rooms, four of each style, run end to end in CI (issue 10).
//!
//! They do not meet issue 10's pass criteria today (9 of 200 do; README, "Generated rooms"), so
//! this test does not assert them: it prints each room's verdict and asserts what must hold in
//! any room, touched or not: the run ends (mapped, or at the room's time limit), no link carries a
//! decode error (no fault is injected), Cute and Carto agree on the protocol (no mission error),
//! a run with a collision names its first contact and one without names none, the body never
//! moves faster than its wheels can drive it, and a second run of the same room gives the same
//! bytes.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use twin::oracle::Oracle;
use twin::report::{Heard, Report};
use twin::runner::Lockstep;
use twin::setup::RunSetup;
use twin_roomgen::{RoomStyle, generate};

/// The generated room run to its end.
fn run_room(style: RoomStyle, seed: u64) -> Lockstep {
    run_room_known(style, seed, Oracle::None)
}

/// The generated room run to its end, Carto given what `oracle` says ([`twin::oracle`]).
fn run_room_known(style: RoomStyle, seed: u64, oracle: Oracle) -> Lockstep {
    run_room_edited(style, seed, oracle, |ron| ron)
}

/// The generated room, its scenario text changed by `edit`, run to its end.
fn run_room_edited(style: RoomStyle, seed: u64, oracle: Oracle, edit: impl Fn(String) -> String) -> Lockstep {
    let room = generate(style, seed).unwrap();
    let loaded = RunSetup::from_ron_str(&edit(room.to_ron()), "generated.ron", std::path::Path::new("."))
        .unwrap()
        .with_oracle(oracle);
    let mut run = Lockstep::new(loaded, None).unwrap();
    run.run_to_end(|_| {});
    run
}

fn run(style: RoomStyle, seed: u64) -> Report {
    run_room(style, seed).report(1.0)
}

#[test]
fn twenty_generated_rooms_run_to_their_end_with_clean_links() {
    let mut passed = 0;
    for style in RoomStyle::ALL {
        for seed in 1..=4 {
            let r = run(style, seed);
            let label = format!("{} seed {seed}", style.name());
            let limit = r.checks.iter().any(|c| c.name == "finish_within_s" && !c.pass);
            assert!(r.mission_complete || limit, "{label}: neither mapped nor at its time limit: {r:?}");
            assert!(r.mission_errors.is_empty(), "{label}: {:?}", r.mission_errors);
            for l in &r.links {
                assert_eq!((l.outbound.errors, l.inbound.errors), (0, 0), "{label}: link {}", l.name);
            }
            assert_eq!(r.collisions > 0, r.first_contact.is_some(), "{label}: {:?}", r.first_contact);
            assert_eq!(r.unphysical.steps, 0, "{label}: {}", r.unphysical.describe());
            println!(
                "{label}: {} — coverage {:.0} %, accuracy {:.0} %, {} collisions, first contact {}",
                if r.passed { "pass" } else { "fail" },
                100.0 * r.coverage,
                100.0 * r.map_accuracy,
                r.collisions,
                r.first_contact.as_ref().map_or("none".to_string(), |c| c.cause.describe().to_string())
            );
            passed += usize::from(r.passed);
        }
    }
    println!("{passed} of 20 generated rooms meet issue 10's pass criteria");
}

#[test]
fn a_generated_room_runs_the_same_twice() {
    let (a, b) = (run(RoomStyle::ALL[0], 3), run(RoomStyle::ALL[0], 3));
    assert_eq!(a.link_log_sha256, b.link_log_sha256);
    assert_eq!((a.collisions, a.first_contact.clone()), (b.collisions, b.first_contact.clone()));
}

/// Generated warehouse seed 19: after collisions had pushed the robot about, an echo point lay
/// inside the body where Carto believed it stood, so inside every turning circle, and Carto
/// refused every turn Cute asked for: 21,842 moves and 43 simulated minutes, until the room's
/// time limit. The body now clears the points it stands on (`carto::surroundings`), and the run
/// ends on its own after a few hundred moves (343 today). It still fails issue 10's criteria.
#[test]
fn a_point_under_the_body_does_not_make_carto_refuse_every_turn() {
    let r = run(RoomStyle::Warehouse, 19);
    println!("warehouse seed 19: {} moves, {:.0} s, {} collisions", r.moves, r.sim_time_s, r.collisions);
    assert!(r.moves < 2_000, "warehouse seed 19: {} moves", r.moves);
}

/// Generated irregular seed 9, started facing north (the room starts the robot facing south,
/// and Cute's detours, turns counted, no longer turn it round first): the first FORWARDs north
/// run along a box turned 22° from the grid, which the sonar does not hear; the body stops
/// against it, pinned, while the wheels spin on. By the wheels Carto once drove four cells
/// north and told Cute so, and the run ended with 7 % of the room mapped and Cute's robot
/// 1.6 m from the real one. The sonar's range held while the wheels drove
/// (`carto/src/control/pilot/stall.rs`): Carto now stops, reports the cell ahead as blocked and
/// drives back, and the room is mapped.
#[test]
fn a_forward_pinned_against_an_unseen_box_is_stopped_and_the_room_still_mapped() {
    let north = |ron: String| {
        ron.replace("start: (row: 5, col: 4, heading: South)", "start: (row: 5, col: 4, heading: North)")
    };
    let run = run_room_edited(RoomStyle::Irregular, 9, Oracle::None, north);
    let stalls = run.carto().stats().pilot.stalls;
    let r = run.report(1.0);
    println!(
        "irregular seed 9: {stalls} stalls, coverage {:.0} %, position error {:.2} m, Cute {:?}, true {:?}",
        100.0 * r.coverage,
        r.localisation.position_error_max_m,
        r.cute_cell,
        r.final_cell
    );
    assert!(stalls >= 1, "no stall seen");
    assert_eq!(
        r.final_cell.map(|(row, col)| (row as u8, col as u8)),
        Some(r.cute_cell),
        "Cute lost the robot"
    );
    assert!(r.localisation.position_error_max_m < 0.5, "{:?}", r.localisation);
    assert!(r.coverage >= 0.9, "coverage {:.2}", r.coverage);
}

/// Generated office seed 28: at 528 s a turn in (8, 8) beside a floor lamp (29 cm across),
/// which the sonar had heard only from 2.2 m away, touches it once, so the run fails. Given the
/// room's surfaces (`--known-room`, README "Perfect perception"), Carto shifts clear of the lamp
/// before that turn and the same Carto and Cute meet every criterion: what failed was
/// perception, not the rest. The report says the room was known.
#[test]
fn a_room_known_beforehand_is_mapped_without_the_touch_the_sonar_missed() {
    let blind = run_room_known(RoomStyle::Office, 28, Oracle::None).report(1.0);
    assert!(blind.collisions > 0 && !blind.known_room, "office seed 28 without the plan: {blind:?}");
    let known = run_room_known(RoomStyle::Office, 28, Oracle::Room).report(1.0);
    assert!(known.known_room);
    assert_eq!(known.collisions, 0, "{:?}", known.first_contact);
    assert!(known.passed, "{:?}", known.checks);
    assert!(known.to_text().contains("known room      Carto was given every surface of the room"));
}

/// Generated office seed 25: at 402 s a FORWARD runs into a table leg 5.4 cm across that the
/// sonar had heard from 83 s on, from 0.13 m at the nearest; Carto's nearest echo point then lay
/// 0.51 m from the spot (and its belief 8 cm off). (Office seeds 8 and 16 showed the same until
/// their tours changed: journal world-model, rounds 4 and 13.) Given every point the sonar heard,
/// where it lies and never forgotten (`--known-echoes`, README "Perfect memory of the echoes"),
/// the same Carto and Cute pass: what failed there was Carto's memory of an echo, not the sonar.
#[test]
fn a_perfect_memory_of_the_echoes_avoids_the_leg_the_sonar_had_heard() {
    let blind = run_room_known(RoomStyle::Office, 25, Oracle::None).report(1.0);
    assert!(blind.collisions > 0 && !blind.known_echoes, "office seed 25 as the robot runs it: {blind:?}");
    let contact = blind.first_contact.as_ref().expect("a first contact");
    assert!(
        matches!(contact.touched_heard, Some(Heard::Before { nearest_m, .. }) if nearest_m < 1.0),
        "{contact:?}"
    );
    assert!(contact.touched_held_m.is_some_and(|m| m > 0.1), "{contact:?}");
    let echoes = run_room_known(RoomStyle::Office, 25, Oracle::Echoes).report(1.0);
    assert!(echoes.known_echoes && !echoes.known_room);
    assert_eq!(echoes.collisions, 0, "{:?}", echoes.first_contact);
    assert!(echoes.passed, "{:?}", echoes.checks);
}
