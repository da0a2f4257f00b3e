//! A* benchmark: our planner against `pathfinding::directed::astar::astar` on the shared grids.
//!
//! Usage: `cargo bench -p cute --bench astar [-- GRID_DIR]`, or set `CUTE_BENCH_GRIDS`.
//! Default directory: `../../shared/bench/grids` from the crate (the workspace's sibling
//! `shared/`). Every `NAME.grid` with a `NAME.queries` beside it is run. Each query is solved by
//! our A* (fast order, then the original's `(f, row, col)` order) and by `pathfinding`; every
//! cost must equal the file's optimal cost, or the run exits with status 1. One row per grid:
//! median µs per query for each planner, the speed-up of ours (fast) over `pathfinding`, and
//! nodes expanded per second.

use std::cell::Cell;
use std::fmt::Write as _;
use std::path::{Path as FsPath, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use cute::astar::{AStar, Grid, TieBreak};

/// Timing repetitions per query; the fastest is kept (removes scheduler noise on a busy machine).
const REPS: usize = 3;

struct GridFile {
    name: String,
    width: usize,
    height: usize,
    free: Vec<bool>,
}

struct Query {
    start: (usize, usize),
    goal: (usize, usize),
    cost: u32,
}

fn parse_grid(path: &FsPath) -> Result<GridFile, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let err = |line: usize, msg: &str| format!("{}:{}: {msg}", path.display(), line + 1);
    let mut lines = text.lines().enumerate();
    let (mut name, mut width, mut height) = (None, None, None);
    for (n, line) in lines.by_ref() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line == "data" {
            break;
        }
        let (key, value) = line.split_once(' ').ok_or_else(|| err(n, "expected `key value`"))?;
        match key {
            "name" => name = Some(value.to_string()),
            "width" => width = Some(value.parse::<usize>().map_err(|e| err(n, &e.to_string()))?),
            "height" => height = Some(value.parse::<usize>().map_err(|e| err(n, &e.to_string()))?),
            _ => {}
        }
    }
    let width = width.ok_or_else(|| format!("{}: no width", path.display()))?;
    let height = height.ok_or_else(|| format!("{}: no height", path.display()))?;
    let mut free = Vec::with_capacity(width * height);
    let mut rows = 0;
    for (n, line) in lines {
        if rows == height {
            if !line.trim().is_empty() {
                return Err(err(n, "extra data line"));
            }
            continue;
        }
        let line = line.trim_end();
        if line.len() != width {
            return Err(err(n, &format!("{} characters, expected {width}", line.len())));
        }
        for (c, ch) in line.chars().enumerate() {
            match ch {
                '.' => free.push(true),
                '#' => free.push(false),
                other => return Err(err(n, &format!("column {c}: unexpected {other:?}"))),
            }
        }
        rows += 1;
    }
    if rows != height {
        return Err(format!("{}: {rows} data lines, expected {height}", path.display()));
    }
    let fallback = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(GridFile { name: name.unwrap_or(fallback), width, height, free })
}

fn parse_queries(path: &FsPath, grid: &GridFile) -> Result<Vec<Query>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let err = |msg: String| format!("{}:{}: {msg}", path.display(), n + 1);
        let v: Vec<u64> = line
            .split_whitespace()
            .map(|t| t.parse::<u64>().map_err(|e| err(format!("{t:?}: {e}"))))
            .collect::<Result<_, _>>()?;
        let [sx, sy, gx, gy, cost] = v[..] else {
            return Err(err(format!("expected 5 numbers, got {}", v.len())));
        };
        // `sx sy gx gy`: column then row.
        let (start, goal) = ((sy as usize, sx as usize), (gy as usize, gx as usize));
        for (r, c) in [start, goal] {
            if r >= grid.height || c >= grid.width || !grid.free[r * grid.width + c] {
                return Err(err(format!("cell (row {r}, col {c}) is off the grid or blocked")));
            }
        }
        out.push(Query { start, goal, cost: cost as u32 });
    }
    Ok(out)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

fn grid_dir() -> PathBuf {
    if let Some(arg) = std::env::args().skip(1).find(|a| !a.starts_with("--")) {
        return PathBuf::from(arg);
    }
    if let Ok(dir) = std::env::var("CUTE_BENCH_GRIDS") {
        return PathBuf::from(dir);
    }
    std::env::current_dir().unwrap_or_default().join("../../shared/bench/grids")
}

fn main() -> ExitCode {
    let dir = grid_dir();
    let mut names: Vec<PathBuf> = match std::fs::read_dir(&dir) {
        Ok(rd) => rd
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "grid"))
            .collect(),
        Err(e) => {
            eprintln!("cannot read grid directory {}: {e}", dir.display());
            return ExitCode::FAILURE;
        }
    };
    names.sort();
    if names.is_empty() {
        eprintln!("no *.grid files in {}", dir.display());
        return ExitCode::FAILURE;
    }
    println!("grids: {}  (best of {REPS} runs per query, median over queries)", dir.display());
    let header = format!(
        "| {:<14} | {:>7} | {:>10} | {:>12} | {:>11} | {:>8} | {:>13} | {:>12} |",
        "grid",
        "queries",
        "ours µs",
        "ours-ref µs",
        "pathfind µs",
        "speed-up",
        "ours Mnodes/s",
        "pf Mnodes/s"
    );
    println!("{header}");
    println!(
        "|{}|",
        header[1..header.len() - 1]
            .split('|')
            .map(|c| "-".repeat(c.chars().count()))
            .collect::<Vec<_>>()
            .join("|")
    );
    let mut failures = 0usize;
    let mut report = String::new();
    let mut planner = AStar::new();
    let mut expansions = Vec::new();
    for grid_path in &names {
        let gf = match parse_grid(grid_path) {
            Ok(g) => g,
            Err(e) => {
                eprintln!("parse error: {e}");
                failures += 1;
                continue;
            }
        };
        let queries = match parse_queries(&grid_path.with_extension("queries"), &gf) {
            Ok(q) => q,
            Err(e) => {
                eprintln!("parse error: {e}");
                failures += 1;
                continue;
            }
        };
        let grid = match Grid::from_fn(gf.height, gf.width, |r, c| u8::from(gf.free[r * gf.width + c])) {
            Ok(g) => g,
            Err(e) => {
                eprintln!("{}: {e}", gf.name);
                failures += 1;
                continue;
            }
        };
        let (mut t_ours, mut t_ref, mut t_pf) = (Vec::new(), Vec::new(), Vec::new());
        let (mut n_ours, mut n_ref, mut n_pf) = (0u64, 0u64, 0u64);
        let (mut s_ours, mut s_pf) = (0f64, 0f64);
        let (w, free) = (gf.width, &gf.free);
        for (qi, q) in queries.iter().enumerate() {
            // Ours, fast order.
            let mut best = f64::MAX;
            for _ in 0..REPS {
                let t0 = Instant::now();
                let p = planner.search_with(&grid, q.start, q.goal, TieBreak::Fast);
                let dt = t0.elapsed().as_secs_f64();
                best = best.min(dt);
                let cost = p.map(|p| p.cost);
                if cost != Some(q.cost) {
                    let _ = writeln!(report, "{} query {qi}: ours {cost:?}, file {}", gf.name, q.cost);
                    failures += 1;
                    break;
                }
            }
            n_ours += planner.last_expanded();
            s_ours += best;
            t_ours.push(best * 1e6);
            // Ours, the original's (f, row, col) order.
            let mut best = f64::MAX;
            for _ in 0..REPS {
                let t0 = Instant::now();
                let p = planner.search_with(&grid, q.start, q.goal, TieBreak::Reference);
                best = best.min(t0.elapsed().as_secs_f64());
                let cost = p.map(|p| p.cost);
                if cost != Some(q.cost) {
                    let _ = writeln!(report, "{} query {qi}: ours-ref {cost:?}, file {}", gf.name, q.cost);
                    failures += 1;
                    break;
                }
            }
            n_ref += planner.last_expanded();
            t_ref.push(best * 1e6);
            // pathfinding 4.16, successors as Vec<((usize, usize), u32)> (the README's baseline).
            let mut best = f64::MAX;
            let expanded = Cell::new(0u64);
            for _ in 0..REPS {
                expanded.set(0);
                let goal = q.goal;
                let t0 = Instant::now();
                let res = pathfinding::directed::astar::astar(
                    &q.start,
                    |&(r, c)| {
                        expanded.set(expanded.get() + 1);
                        let mut v = Vec::with_capacity(4);
                        for (dr, dc) in [(0isize, 1isize), (1, 0), (-1, 0), (0, -1)] {
                            let (nr, nc) = (r.wrapping_add_signed(dr), c.wrapping_add_signed(dc));
                            if nr < gf.height && nc < w && free[nr * w + nc] {
                                v.push(((nr, nc), 1u32));
                            }
                        }
                        v
                    },
                    |&(r, c)| (r.abs_diff(goal.0) + c.abs_diff(goal.1)) as u32,
                    |&n| n == goal,
                );
                best = best.min(t0.elapsed().as_secs_f64());
                let cost = res.map(|(_, c)| c);
                if cost != Some(q.cost) {
                    let _ = writeln!(report, "{} query {qi}: pathfinding {cost:?}, file {}", gf.name, q.cost);
                    failures += 1;
                    break;
                }
            }
            n_pf += expanded.get();
            s_pf += best;
            t_pf.push(best * 1e6);
        }
        let (mo, mr, mp) = (median(&mut t_ours), median(&mut t_ref), median(&mut t_pf));
        let per_query = |n: u64| n as f64 / queries.len().max(1) as f64;
        expansions.push(format!(
            "{}: mean nodes expanded per query: ours {:.0}, ours-ref {:.0}, pathfinding {:.0}",
            gf.name,
            per_query(n_ours),
            per_query(n_ref),
            per_query(n_pf)
        ));
        println!(
            "| {:<14} | {:>7} | {:>10.1} | {:>12.1} | {:>11.1} | {:>7.1}x | {:>13.1} | {:>12.1} |",
            gf.name,
            queries.len(),
            mo,
            mr,
            mp,
            if mo > 0.0 { mp / mo } else { 0.0 },
            n_ours as f64 / s_ours.max(1e-12) / 1e6,
            n_pf as f64 / s_pf.max(1e-12) / 1e6,
        );
    }
    println!();
    for line in &expansions {
        println!("{line}");
    }
    if failures > 0 {
        eprint!("{report}");
        eprintln!("{failures} failure(s)");
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}
