//! Screenshot of the standalone `CutePlugin` (feature `window`): a map learnt over the wire from
//! a grid-only robot, a pending trajectory, rendered in a real window (Xvfb in CI) and checked
//! pixel by pixel against the session's map.
//!
//! Run: `xvfb-run -a -s "-screen 0 1280x800x24" env WGPU_BACKEND=vulkan \
//!       cargo test --release -p cute --features window --test gui_screenshot`
#![cfg(feature = "window")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;

use bevy::app::{App, AppExit, Startup};
use bevy::math::Vec2;
use bevy::prelude::ClearColor;
use cute::gridsim::{FakeRobot, World};
use cute::gui::{
    AutoScreenshot, BACKGROUND, CutePlugin, CuteSession, CuteView, MapLayout, cell_rgb, continuous_updates,
    setup_camera, window_plugins,
};
use cute::{CellValue, Cute, CuteConfig, MoveResult, Status};
use protocol::link::{Decoder, GuiMessage, MsgOrder};
use robot_model::grid::{Heading, Move};
use robot_model::time::Instant;

const ROOM: &str = "
............
..##........
..##....#...
........#...
.....#...###
.........#..
.........#..
.........#..
";

/// Plays Carto for `cute` with a grid-only robot, over the real link bytes, until `done`.
fn serve(cute: &mut Cute, robot: &mut FakeRobot, mut done: impl FnMut(&Cute) -> bool) {
    let mut decoder = Decoder::default();
    let mut t = 0;
    cute.on_connected(Instant::from_millis(t));
    for _ in 0..5000 {
        if done(cute) {
            return;
        }
        t += 10;
        let mut reply = Vec::new();
        for msg in decoder.feed(&cute.take_outgoing()) {
            match msg.unwrap() {
                GuiMessage::SendRobotPosition { .. } => reply.push(GuiMessage::RobotPositionReceived),
                GuiMessage::SendMoveCartography { command } => {
                    let command = Move::try_from(command).unwrap();
                    match robot.execute(command) {
                        MoveResult::Moved { x, y } => reply.push(GuiMessage::SetRobotPosition { x, y }),
                        MoveResult::Blocked { x, y } => reply.push(GuiMessage::SetObstaclePosition { x, y }),
                        _ => {}
                    }
                    reply.push(GuiMessage::MoveDone);
                }
                _ => {}
            }
        }
        let bytes: Vec<u8> = reply.iter().flat_map(|m| m.to_bytes(MsgOrder::BigEndian)).collect();
        cute.on_bytes(Instant::from_millis(t), &bytes);
        cute.poll(Instant::from_millis(t));
    }
    panic!("the session did not finish");
}

fn sample_session() -> Cute {
    let world = World::parse(ROOM).unwrap();
    let mut robot = FakeRobot::new(world.clone(), (0, 0), Heading::East);
    let mut cute = Cute::new(CuteConfig {
        rows: world.rows(),
        cols: world.cols(),
        start: (0, 0),
        heading: Heading::East,
        ..CuteConfig::default()
    })
    .unwrap();
    cute.start_cartography().unwrap();
    serve(&mut cute, &mut robot, |c| c.status() == Status::Done);
    // A trajectory in flight: waypoints and the destination show on the map.
    cute.go_to(7, 7).unwrap();
    assert_eq!(cute.status(), Status::Moving);
    cute
}

fn pixel(img: &image::RgbImage, p: Vec2) -> [u8; 3] {
    img.get_pixel(p.x as u32, p.y as u32).0
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter().zip(b).all(|(&x, y)| x.abs_diff(y) <= 12)
}

#[test]
fn cute_plugin_screenshot_shows_the_sessions_map() {
    if std::env::var_os("DISPLAY").is_none() {
        println!(
            "SKIPPED cute_plugin_screenshot_shows_the_sessions_map: no display (DISPLAY is unset); run under xvfb-run"
        );
        return;
    }
    let cute = sample_session();
    let map = cute.map().clone();
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cute-gui.png");
    let _ = std::fs::remove_file(&path);
    let (w, h) = (1024u32, 768u32);
    let mut shot = AutoScreenshot::new(path.clone());
    shot.ready = true;
    let mut app = App::new();
    app.add_plugins(window_plugins("cute screenshot test", w, h, true))
        .insert_resource(continuous_updates())
        .insert_resource(ClearColor(BACKGROUND))
        .insert_resource(CuteSession(cute))
        .add_plugins(CutePlugin::<CuteSession>::new())
        .add_systems(Startup, setup_camera)
        .insert_resource(shot);
    assert_eq!(app.run(), AppExit::Success);

    let img = image::open(&path).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (w, h));
    let layout =
        MapLayout::compute(Vec2::new(w as f32, h as f32), &CuteView::default(), map.rows(), map.cols());
    assert!(layout.cell >= 40.0, "cells of {} px", layout.cell);
    // Away from the grid lines and the robot/destination markers drawn on top.
    let inside = |row: usize, col: usize| layout.cell_rect(row, col).min + Vec2::splat(layout.cell * 0.2);
    let mut seen = [0usize; 6];
    for ((row, col), value) in map.iter() {
        let got = pixel(&img, inside(usize::from(row), usize::from(col)));
        assert!(
            close(got, cell_rgb(value)),
            "cell ({row}, {col}) is {value:?}: expected ~{:?}, got {got:?}",
            cell_rgb(value)
        );
        seen[usize::from(value.as_u8())] += 1;
    }
    // The sample has every kind of cell (the walled-in corner stays unknown).
    assert!(seen.iter().all(|&n| n > 0), "cells per value: {seen:?}");
    // A known obstacle of the room is dark, a free cell light.
    assert_eq!(map.get(1, 2), Some(CellValue::Obstacle));
    let dark = pixel(&img, layout.cell_rect(1, 2).center());
    assert!(dark.iter().all(|&c| c < 60), "obstacle (1, 2): {dark:?}");
    let free = map.iter().find(|&(_, v)| v == CellValue::Free).map(|(c, _)| c).unwrap();
    let light = pixel(&img, layout.cell_rect(usize::from(free.0), usize::from(free.1)).center());
    assert!(light.iter().all(|&c| c > 150), "free {free:?}: {light:?}");
    // Outside the map is the window background, not map colours.
    let bg = pixel(&img, layout.map_rect().min - Vec2::splat(8.0));
    assert!(bg.iter().all(|&c| c < 80), "background {bg:?}");
    println!("screenshot: {}", path.display());
}
