//! The cost of Carto's world model on this machine: one sonar update of the evidence grid (an
//! echo near, at mid range and at the sonar's limit, and a reading with no echo), the shape
//! queries the pilot asks before a move (the corridor of one FORWARD, the turning circle), and
//! one step of the pose filter (a prediction, and a correction from a range against the grid),
//! and the local planner's sliding way for a FORWARD past a chair leg and its place for a turn.
//!
//! Carto's control cycle is 60 ms and the Raspberry Pi 4 is about 5–8 times slower than a
//! desktop core, so an update must stay well under a millisecond here.
//!
//! `cargo bench -p carto --bench estimate`

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

use carto::estimate::grid::{EvidenceGrid, GridParams};
use carto::estimate::pose::{MotionNoise, PoseFilter, RangeUpdate};
use carto::estimate::sonar::{Reading, SonarModel};
use carto::surroundings::Pose2;

/// A grid that has seen a 4 × 4 m room from its middle, every 10°.
fn seen_room() -> EvidenceGrid {
    let (mut grid, model) = (EvidenceGrid::new(GridParams::default()), SonarModel::default());
    for k in 0..36 {
        let pose = Pose2 { x: 2.0, y: 2.0, yaw_deg: f64::from(k) * 10.0 };
        model.update(&mut grid, pose, Reading::Echo(1.9));
    }
    grid
}

fn sonar_update(c: &mut Criterion) {
    let model = SonarModel::default();
    let mut grid = seen_room();
    let pose = Pose2 { x: 2.0, y: 2.0, yaw_deg: 30.0 };
    let mut group = c.benchmark_group("sonar_update");
    for (name, reading) in [
        ("echo_0.5m", Reading::Echo(0.5)),
        ("echo_2m", Reading::Echo(2.0)),
        ("echo_4m", Reading::Echo(4.0)),
        ("no_echo", Reading::NoEcho),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| model.update(&mut grid, black_box(pose), black_box(reading)))
        });
    }
    group.finish();
}

fn queries(c: &mut Criterion) {
    let grid = seen_room();
    let pose = Pose2 { x: 2.0, y: 2.0, yaw_deg: 90.0 };
    let mut group = c.benchmark_group("query");
    // One FORWARD of a 0.45 m cell: front face to front face, body 24 cm wide plus 2 cm a side.
    group.bench_function("corridor", |b| {
        b.iter(|| grid.first_occupied_in_rect(black_box(pose), 0.13, 0.58, 0.14))
    });
    // The turning circle: half the body's diagonal plus 2 cm.
    group.bench_function("turning_circle", |b| b.iter(|| grid.classify_circle(black_box((2.0, 2.0)), 0.19)));
    group.finish();
}

fn filter_step(c: &mut Criterion) {
    let mut grid = seen_room();
    grid.pin_segment((3.9, 0.0), (3.9, 4.0)); // the east wall, mapped
    let applied = PoseFilter::new(Pose2 { x: 2.0, y: 2.0, yaw_deg: 0.0 }, 0.02, 1.0)
        .correct_range(&grid, 0.13, 1.77, 0.005);
    assert!(
        matches!(applied, RangeUpdate::Applied { .. }),
        "the benchmark must measure a correction: {applied:?}"
    );
    let noise = MotionNoise::default();
    let start = PoseFilter::new(Pose2 { x: 2.0, y: 2.0, yaw_deg: 0.0 }, 0.02, 1.0);
    let mut group = c.benchmark_group("pose_filter");
    group.bench_function("predict", |b| {
        let mut f = start.clone();
        b.iter(|| f.predict(black_box(0.02), 0.0, black_box(0.001), 0.06, &noise))
    });
    // the sonar 13 cm ahead of the centre ranges the east wall
    group.bench_function("correct_range", |b| {
        b.iter(|| start.clone().correct_range(&grid, 0.13, black_box(1.77), 0.005))
    });
    group.finish();
}

/// A FORWARD past a chair leg in its corridor (its outline every centimetre, a wall beside), and
/// a turn whose circle holds the leg, over a complete floor plan.
fn local_motion(c: &mut Criterion) {
    let g = carto::slide::SlideGeometry::from_config(&carto::CartoConfig {
        cell_size_m: 0.45,
        ..Default::default()
    });
    let leg = (0..12)
        .map(|k| f64::from(k) * std::f64::consts::TAU / 12.0)
        .map(|t| (0.20 + 0.015 * t.cos(), 0.10 + 0.015 * t.sin()));
    let wall = (-40..=100).map(|k| (f64::from(k) * 0.01, -0.33));
    let points: Vec<(f64, f64)> = leg.chain(wall).collect();
    let free = |_: (f64, f64), _: (f64, f64)| true;
    assert!(carto::slide::plan(&g, (0.0, 0.0), &points, &free).is_some_and(|w| !w.legs.is_empty()));
    let mut group = c.benchmark_group("local_motion");
    group.bench_function("forward_slide", |b| {
        b.iter(|| carto::slide::plan(&g, black_box((0.0, 0.0)), &points, &free))
    });
    group.bench_function("turn_place", |b| {
        b.iter(|| carto::slide::plan_turn(&g, black_box((0.0, 0.0)), &points, &free))
    });
    group.finish();
}

criterion_group!(benches, sonar_update, queries, filter_step, local_motion);
criterion_main!(benches);
