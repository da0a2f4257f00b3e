//! Screenshot of `explobot window` (feature `window`): the default room after a few sim seconds,
//! checked against a headless run of the same scenario to the same step (the runner is
//! deterministic, the window only paces it).
//!
//! Run: `xvfb-run -a -s "-screen 0 1280x800x24" env WGPU_BACKEND=vulkan \
//!       cargo test --release -p explobot --features window --test window_screenshot`
#![cfg(feature = "window")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;
use std::process::Command;

use bevy::math::{Rect, Vec2};
use cute::CellValue;
use cute::gui::{CuteView, MapLayout, cell_rgb};
use robot_model::time::Instant;
use twin::runner::Lockstep;
use twin::setup::RunSetup;
use twin_app::window::{OBSTACLE_RGB, ROBOT_RGB, STATUS_HEIGHT, WINDOW_SIZE, WorldLayout};

const AFTER_S: f64 = 240.0;

fn close(a: [u8; 3], b: [u8; 3], tol: u8) -> bool {
    a.iter().zip(b).all(|(&x, y)| x.abs_diff(y) <= tol)
}

#[test]
fn window_screenshot_shows_world_and_map_side_by_side() {
    if std::env::var_os("DISPLAY").is_none() {
        println!(
            "SKIPPED window_screenshot_shows_world_and_map_side_by_side: no display (DISPLAY is unset); run under xvfb-run"
        );
        return;
    }
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("explobot-window.png");
    let _ = std::fs::remove_file(&path);
    let out = Command::new(env!("CARGO_BIN_EXE_explobot"))
        .args(["window", "--screenshot"])
        .arg(&path)
        .args(["--screenshot-after", &AFTER_S.to_string()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "explobot window failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&path).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), WINDOW_SIZE);
    let px = |p: Vec2| img.get_pixel(p.x as u32, p.y as u32).0;

    // The same run, headless, to the step the window stopped at.
    let mut run = Lockstep::new(RunSetup::builtin_default().unwrap(), None).unwrap();
    let at = Instant::from_secs_f64(AFTER_S);
    while run.now() < at && run.step() {}
    let window = Vec2::new(WINDOW_SIZE.0 as f32, WINDOW_SIZE.1 as f32);

    // World view, left half: the robot's body is where the physics put it.
    let scenario = &run.loaded().scenario;
    let world = WorldLayout::compute(window, &scenario.room);
    let pose = run.body().pose();
    let centre = world.to_logical(pose.x, pose.y);
    assert!(centre.x < window.x * 0.5, "robot drawn at {centre}");
    let r = 0.07 * world.scale;
    let (mut blue, mut total) = (0, 0);
    for dy in -(r as i32)..=(r as i32) {
        for dx in -(r as i32)..=(r as i32) {
            let p = centre + Vec2::new(dx as f32, dy as f32);
            if p.distance(centre) <= r {
                total += 1;
                if close(px(p), ROBOT_RGB, 30) {
                    blue += 1;
                }
            }
        }
    }
    assert!(blue * 2 > total, "robot blue at {blue} of {total} pixels around {centre}");
    // The sofa (a box centred at (1.55, 0.35)), sampled between the grid lines.
    let sofa = px(world.to_logical(1.45, 0.45));
    assert!(close(sofa, OBSTACLE_RGB, 20), "sofa {sofa:?}");

    // Map panel, right half: Cute's map as the session holds it.
    let view = CuteView { region: Rect::new(0.5, 0.0, 1.0, 1.0), inset_bottom: STATUS_HEIGHT };
    let map = run.cute().map();
    let layout = MapLayout::compute(window, &view, map.rows(), map.cols());
    assert!(layout.map_rect().min.x >= window.x * 0.5);
    let mut seen = [0usize; 6];
    for ((row, col), value) in map.iter() {
        let p = layout.cell_rect(usize::from(row), usize::from(col)).min + Vec2::splat(layout.cell * 0.2);
        let got = px(p);
        assert!(close(got, cell_rgb(value), 12), "map cell ({row}, {col}) {value:?}: got {got:?}");
        seen[usize::from(value.as_u8())] += 1;
    }
    assert!(seen[usize::from(CellValue::Free.as_u8())] > 0, "{seen:?}");
    assert_eq!(seen[usize::from(CellValue::Robot.as_u8())], 1);
    println!("screenshot: {} (cells per value {seen:?})", path.display());
}
