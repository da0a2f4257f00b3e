//! A status file the window rewrites a few times a second (`--status-file FILE`): what a person
//! sees, as JSON, for tests that drive the window with real X input and for scripts.
//!
//! Concept: every [`STATUS_EVERY_S`] of wall time the file is written whole to `FILE.tmp` and
//! renamed over `FILE`, so a reader never sees half a file. It holds the sim time, the speed, the
//! script's state and verdict, the robot's true pose and cell, Cute's status, cell and map (one
//! string per row: `.` known free, `#` obstacle, `?` unknown), whether the "Carto's map" layer is
//! shown and how many of Carto's grid cells are occupied and free, the pop-ups waiting, where the map
//! and every button are drawn (logical pixels, origin top-left) and the window's scale factor.
//!
//! Invariants: writing never stops the window: an error is reported once on stderr, and the
//! window goes on.

use std::path::{Path, PathBuf};

use bevy::ecs::system::{Query, Res, ResMut};
use bevy::prelude::{Resource, With};
use bevy::time::{Real, Time};
use bevy::window::{PrimaryWindow, Window};
use cute::CellValue;
use cute::gui::{ButtonRects, CuteUiState, CuteView, MapLayout};
use serde_json::{Value, json};

use super::carto_layer::CartoLayer;
use super::session::{Handover, ScriptState};
use crate::pacing::{Pacing, Speed};
use crate::plugin::Sim;
use twin::carto_map::{CartoMap, Occupancy};

/// How often the status file is rewritten, wall seconds.
pub const STATUS_EVERY_S: f64 = 0.2;

/// Where the status goes and when it was last written.
#[derive(Resource, Debug)]
pub struct StatusFile {
    path: PathBuf,
    written_at_s: Option<f64>,
    writes: u64,
    failed: bool,
}

impl StatusFile {
    /// A status file at `path`, not written yet.
    pub fn new(path: PathBuf) -> StatusFile {
        StatusFile { path, written_at_s: None, writes: 0, failed: false }
    }
}

fn cell_char(v: CellValue) -> char {
    match v {
        CellValue::Unknown => '?',
        CellValue::Obstacle => '#',
        _ => '.',
    }
}

fn rect_json(r: bevy::math::Rect) -> Value {
    json!([r.min.x, r.min.y, r.max.x, r.max.y])
}

/// Writes `text` to `path` through a temporary file in the same folder.
fn write_atomically(path: &Path, text: &str) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, path)
}

#[allow(clippy::too_many_arguments)]
pub(super) fn write_status(
    mut file: ResMut<StatusFile>,
    sim: Res<Sim>,
    pacing: Res<Pacing>,
    handover: Res<Handover>,
    rects: Res<ButtonRects>,
    ui: Res<CuteUiState>,
    view: Res<CuteView>,
    layer: Res<CartoLayer>,
    time: Res<Time<Real>>,
    window: Query<&Window, With<PrimaryWindow>>,
) {
    let wall = time.elapsed_secs_f64();
    if file.written_at_s.is_some_and(|t| wall - t < STATUS_EVERY_S) {
        return;
    }
    let Ok(window) = window.single() else {
        return;
    };
    let run = &sim.0;
    let cute = run.cute();
    let map = cute.map();
    let size = window.size();
    let layout = MapLayout::compute(size, &view, map.rows(), map.cols());
    let rows: Vec<String> = (0..map.rows())
        .map(|r| (0..map.cols()).map(|c| map.get(r, c).map_or('?', cell_char)).collect())
        .collect();
    let pose = run.body().pose();
    let (cx, cy, heading) = cute.robot();
    let script = ScriptState::of(run);
    let buttons: serde_json::Map<String, Value> =
        rects.0.iter().map(|(k, r)| (k.clone(), rect_json(*r))).collect();
    let carto_map = CartoMap::of(run.carto(), &run.frame());
    file.writes += 1;
    let status = json!({
        "writes": file.writes,
        "wall_s": wall,
        "t_s": run.now().as_secs_f64(),
        "speed": pacing.speed.label(),
        "paused": pacing.speed == Speed::Paused,
        "achieved": pacing.achieved,
        "script": {
            "text": script.text(),
            "user_drives": script.user_drives(),
            "headless_end_s": run.headless_end().map(|t| t.as_secs_f64()),
        },
        "verdict": handover.verdict.as_ref().map(|r| json!({
            "passed": r.passed,
            "line": handover.verdict_line(),
        })),
        "robot": {
            "x": pose.x,
            "y": pose.y,
            "theta_deg": pose.theta.to_degrees(),
            "cell": run.frame().cell_at(pose.x, pose.y).map(|(r, c)| [r, c]),
        },
        "cute": {
            "status": format!("{:?}", cute.status()),
            "cell": [cx, cy],
            "heading": format!("{heading:?}"),
            "known_free": map.cells().iter().filter(|v| v.is_known_free()).count(),
            "map": rows,
        },
        "carto_layer": {
            "shown": layer.shown,
            "occupied": carto_map.cells_that_are(Occupancy::Occupied).count(),
            "free": carto_map.cells_that_are(Occupancy::Free).count(),
        },
        "popups": ui.popups.len(),
        "window": { "width": size.x, "height": size.y, "scale_factor": window.scale_factor() },
        "map_layout": {
            "origin": [layout.origin.x, layout.origin.y],
            "cell": layout.cell,
            "rows": layout.rows,
            "cols": layout.cols,
        },
        "buttons": buttons,
    });
    file.written_at_s = Some(wall);
    if let Err(e) = write_atomically(&file.path, &format!("{status}\n"))
        && !std::mem::replace(&mut file.failed, true)
    {
        eprintln!("explobot: cannot write the status file {}: {e}", file.path.display());
    }
}
