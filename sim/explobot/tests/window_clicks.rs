//! Issue 16: the window driven the way a person drives it — real X input events (xdotool) on a
//! real window under Xvfb, read back from the window's `--status-file` (what its status bar and
//! map show, and where its buttons are drawn).
//!
//! 1. A room without a script: the twin keeps running; Cartography and Max make the map grow and
//!    the robot move until the map is complete; a click on a far mapped free cell brings the
//!    robot there; at 1x (measured about 1x) another click sends it off and Stop halts it.
//! 2. The default room: Max plays the script to its end (the same end as a headless run), the
//!    verdict is shown and the twin keeps running; the "Carto's map" button hides and shows
//!    Carto's layer; Reset map, then Cartography and click-to-go as
//!    in 1; Restart starts the scenario again and its script ends at the same time.
//!
//! Run: `xvfb-run -a -s "-screen 0 1280x800x24" env WGPU_BACKEND=vulkan \
//!       cargo test --release -p explobot --features window --test window_clicks`
//! (needs `xdotool`; `.ci/run` installs it). Without a display the tests say SKIPPED, except in
//! CI (`CI` set), where they fail: there they must run.
#![cfg(feature = "window")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::Value;
use twin::runner::Lockstep;
use twin::setup::RunSetup;

/// One window at a time: real clicks go to whatever window is under the pointer.
static ONE_WINDOW: Mutex<()> = Mutex::new(());

/// Generous: a loaded 2-core machine renders through a software Vulkan driver.
const START_TIMEOUT: Duration = Duration::from_secs(120);
const STEP_TIMEOUT: Duration = Duration::from_secs(90);

/// Whether the tests can run here; panics in CI when they cannot.
fn display_ready(test: &str) -> bool {
    let ci = std::env::var_os("CI").is_some();
    if std::env::var_os("DISPLAY").is_none() {
        assert!(!ci, "{test}: no display in CI (DISPLAY is unset); run the tests under xvfb-run");
        println!("SKIPPED {test}: no display (DISPLAY is unset); run under xvfb-run");
        return false;
    }
    // Installed, and able to reach the display: a busy X server (the other test's window
    // starting) may refuse a connection for a moment, so a failed run is tried again.
    let mut failed = String::new();
    for _ in 0..5 {
        match Command::new("xdotool").arg("version").output() {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                panic!("{test}: xdotool is missing: apt-get install -y xdotool (.ci/run does)")
            }
            Err(e) => failed = e.to_string(),
            Ok(o) if o.status.success() => return true,
            Ok(o) => failed = format!("{}: {}", o.status, String::from_utf8_lossy(&o.stderr).trim()),
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    panic!("{test}: xdotool cannot reach the display {:?}: {failed}", std::env::var_os("DISPLAY"))
}

/// The window process, killed when dropped (a failing test leaves no window behind).
struct Window {
    child: Child,
    dir: PathBuf,
    status: PathBuf,
    id: Option<String>,
}

impl Drop for Window {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Window {
    /// `explobot window ARGS --status-file …` with its output in `dir`, up and writing its
    /// status. Xvfb resets itself when its last client leaves (the previous window, an xdotool
    /// call), and refuses connections meanwhile: a window that could not open the display is
    /// started again, a few times.
    fn open(name: &str, args: &[&str]) -> Window {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("window-clicks-{name}"));
        for attempt in 1..=4 {
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            let status = dir.join("status.json");
            let child = Command::new(env!("CARGO_BIN_EXE_explobot"))
                .arg("window")
                .args(args)
                .arg("--status-file")
                .arg(&status)
                .stdin(Stdio::null())
                .stdout(std::fs::File::create(dir.join("stdout.txt")).unwrap())
                .stderr(std::fs::File::create(dir.join("stderr.txt")).unwrap())
                .spawn()
                .unwrap();
            let mut w = Window { child, dir: dir.clone(), status, id: None };
            let start = Instant::now();
            loop {
                if w.status.exists() {
                    return w;
                }
                if let Ok(Some(code)) = w.child.try_wait() {
                    let out = w.output();
                    assert!(
                        out.contains("XOpenDisplayFailed") && attempt < 4,
                        "the window exited ({code})\n{out}"
                    );
                    println!("attempt {attempt}: the window could not open the display; again in 1 s");
                    break;
                }
                assert!(start.elapsed() < START_TIMEOUT, "no status after {START_TIMEOUT:?}\n{}", w.output());
                std::thread::sleep(Duration::from_millis(100));
            }
            std::thread::sleep(Duration::from_secs(1));
        }
        unreachable!("the last attempt either starts or fails an assertion")
    }

    /// The window's own output, for failure messages.
    fn output(&self) -> String {
        let read = |f: &str| std::fs::read_to_string(self.dir.join(f)).unwrap_or_default();
        let tail = |s: String| {
            s.lines().rev().take(30).collect::<Vec<_>>().into_iter().rev().collect::<Vec<_>>().join("\n")
        };
        format!("--- stdout\n{}\n--- stderr\n{}", tail(read("stdout.txt")), tail(read("stderr.txt")))
    }

    /// The status file as last written (`None` before the first write).
    fn status(&mut self) -> Option<Value> {
        if let Ok(Some(code)) = self.child.try_wait() {
            panic!("the window exited ({code})\n{}", self.output());
        }
        let text = std::fs::read_to_string(&self.status).ok()?;
        serde_json::from_str(&text).ok()
    }

    /// Waits until `want` holds for the status; the last status otherwise, in the panic message.
    fn wait(&mut self, what: &str, timeout: Duration, want: impl Fn(&Value) -> bool) -> Value {
        let start = Instant::now();
        let mut last = None;
        while start.elapsed() < timeout {
            if let Some(s) = self.status() {
                if want(&s) {
                    println!(
                        "{what}: after {:.1} s wall, t = {:.1} s",
                        start.elapsed().as_secs_f64(),
                        t_s(&s)
                    );
                    return s;
                }
                last = Some(s);
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        panic!("timed out after {timeout:?} waiting for: {what}\nlast status: {last:#?}\n{}", self.output());
    }

    /// The X window id (through the process id, so no other window is clicked).
    fn x_id(&mut self) -> String {
        if let Some(id) = &self.id {
            return id.clone();
        }
        let pid = self.child.id().to_string();
        let start = Instant::now();
        while start.elapsed() < START_TIMEOUT {
            let out = Command::new("xdotool")
                .args(["search", "--all", "--onlyvisible", "--pid", &pid, "--name", "ExploBot Twin"])
                .output()
                .unwrap();
            if let Some(id) = String::from_utf8_lossy(&out.stdout).lines().next() {
                self.id = Some(id.to_string());
                return id.to_string();
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        panic!("no X window for process {pid}\n{}", self.output());
    }

    /// A left click at logical point (x, y) of the window: pointer there, press, release, as a
    /// hand would (egui and Bevy see a hover first, then the button).
    fn click_at(&mut self, x: f64, y: f64, scale: f64) {
        let id = self.x_id();
        let (px, py) = ((x * scale).round().to_string(), (y * scale).round().to_string());
        xdotool(&["mousemove", "--window", &id, &px, &py]);
        std::thread::sleep(Duration::from_millis(150));
        xdotool(&["mousedown", "1"]);
        std::thread::sleep(Duration::from_millis(80));
        xdotool(&["mouseup", "1"]);
        std::thread::sleep(Duration::from_millis(150));
    }

    /// Clicks the button drawn with `label`, as the status file places it.
    fn press(&mut self, label: &str) {
        let s =
            self.wait(&format!("button {label} drawn"), START_TIMEOUT, |s| s["buttons"][label].is_array());
        let r: Vec<f64> =
            s["buttons"][label].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        println!("press {label} at ({:.0}, {:.0})", (r[0] + r[2]) / 2.0, (r[1] + r[3]) / 2.0);
        self.click_at((r[0] + r[2]) / 2.0, (r[1] + r[3]) / 2.0, scale(&s));
    }

    /// Clicks Cute's map on cell (row, col).
    fn click_cell(&mut self, (row, col): (usize, usize)) {
        let s = self.status().unwrap();
        let m = &s["map_layout"];
        let cell = m["cell"].as_f64().unwrap();
        let x = m["origin"][0].as_f64().unwrap() + (col as f64 + 0.5) * cell;
        let y = m["origin"][1].as_f64().unwrap() + (row as f64 + 0.5) * cell;
        println!("click cell ({row}, {col}) at ({x:.0}, {y:.0})");
        self.click_at(x, y, scale(&s));
    }

    /// Acknowledges every pop-up (they would catch a click on the map).
    fn close_popups(&mut self) {
        for _ in 0..5 {
            let s = self.status().unwrap();
            if s["popups"].as_u64() == Some(0) {
                return;
            }
            println!("pop-up waiting: OK");
            self.press("OK");
            std::thread::sleep(Duration::from_millis(300));
        }
    }
}

fn xdotool(args: &[&str]) {
    let out = Command::new("xdotool").args(args).output().unwrap();
    assert!(out.status.success(), "xdotool {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn scale(s: &Value) -> f64 {
    s["window"]["scale_factor"].as_f64().unwrap_or(1.0)
}

fn t_s(s: &Value) -> f64 {
    s["t_s"].as_f64().unwrap_or(0.0)
}

fn known_free(s: &Value) -> u64 {
    s["cute"]["known_free"].as_u64().unwrap_or(0)
}

fn cute_status(s: &Value) -> &str {
    s["cute"]["status"].as_str().unwrap_or("")
}

fn robot_xy(s: &Value) -> (f64, f64) {
    (s["robot"]["x"].as_f64().unwrap(), s["robot"]["y"].as_f64().unwrap())
}

fn cell_of(v: &Value) -> Option<(usize, usize)> {
    Some((v[0].as_u64()? as usize, v[1].as_u64()? as usize))
}

/// The known free cell farthest (by moves over known free cells) from Cute's robot cell.
fn far_free_cell(s: &Value) -> (usize, usize) {
    let map: Vec<Vec<char>> =
        s["cute"]["map"].as_array().unwrap().iter().map(|r| r.as_str().unwrap().chars().collect()).collect();
    let start = cell_of(&s["cute"]["cell"]).unwrap();
    let mut dist = vec![vec![usize::MAX; map[0].len()]; map.len()];
    dist[start.0][start.1] = 0;
    let mut queue = std::collections::VecDeque::from([start]);
    let mut far = start;
    while let Some((r, c)) = queue.pop_front() {
        if dist[r][c] > dist[far.0][far.1] {
            far = (r, c);
        }
        let next = [(r.wrapping_sub(1), c), (r + 1, c), (r, c.wrapping_sub(1)), (r, c + 1)];
        for (nr, nc) in next {
            if map.get(nr).and_then(|row| row.get(nc)) == Some(&'.') && dist[nr][nc] == usize::MAX {
                dist[nr][nc] = dist[r][c] + 1;
                queue.push_back((nr, nc));
            }
        }
    }
    assert!(dist[far.0][far.1] >= 3, "no known free cell 3 moves away: {:?}", s["cute"]);
    far
}

/// Cartography at Max: the map grows and the robot moves, until the map is complete; then a
/// click on a far mapped free cell brings the robot (true pose and Cute's belief) there.
fn map_then_click_to_go(w: &mut Window) {
    let before = w.wait("a status", START_TIMEOUT, |_| true);
    let (free0, xy0) = (known_free(&before), robot_xy(&before));
    w.close_popups();
    w.press("Cartography");
    w.press("Max");
    let grown = w.wait("the map grows and the robot moves", STEP_TIMEOUT, |s| {
        let (x, y) = robot_xy(s);
        known_free(s) >= free0 + 8 && (x - xy0.0).hypot(y - xy0.1) > 0.5
    });
    assert_eq!(grown["speed"], "Max");
    let done = w.wait("the map complete", STEP_TIMEOUT, |s| cute_status(s) == "Done");
    let target = far_free_cell(&done);
    w.close_popups();
    w.click_cell(target);
    let there = w.wait(&format!("the robot at {target:?}"), STEP_TIMEOUT, |s| {
        cute_status(s) == "Idle"
            && cell_of(&s["cute"]["cell"]) == Some(target)
            && cell_of(&s["robot"]["cell"]) == Some(target)
    });
    let speed = there["achieved"].as_f64().unwrap_or(0.0);
    assert!(speed > 1.0, "Max runs faster than real time: {speed}");
}

/// At 1x, a click sends the robot off and Stop halts it before it gets there; the speed shown is
/// the one measured.
fn click_then_stop(w: &mut Window) {
    w.press("1x");
    let s = w.wait("1x measured", STEP_TIMEOUT, |s| s["speed"] == "1x" && s["achieved"].is_number());
    let achieved = s["achieved"].as_f64().unwrap();
    assert!((0.2..2.0).contains(&achieved), "1x achieved {achieved}x");
    let target = far_free_cell(&s);
    w.click_cell(target);
    w.wait("the robot on its way", STEP_TIMEOUT, |s| cute_status(s) == "Moving");
    std::thread::sleep(Duration::from_millis(1000));
    w.press("Stop");
    let stopped = w.wait("Cute idle after Stop", STEP_TIMEOUT, |s| cute_status(s) == "Idle");
    assert_ne!(cell_of(&stopped["cute"]["cell"]), Some(target), "stopped before the far cell");
    // The robot stands still (a moment for the wheels to spin down first).
    std::thread::sleep(Duration::from_millis(800));
    let a = w.status().unwrap();
    std::thread::sleep(Duration::from_millis(1000));
    let b = w.status().unwrap();
    let ((xa, ya), (xb, yb)) = (robot_xy(&a), robot_xy(&b));
    assert!(t_s(&b) > t_s(&a) + 0.5, "the twin runs on: {} then {}", t_s(&a), t_s(&b));
    assert!((xa - xb).hypot(ya - yb) < 0.01, "the robot still moves after Stop: {a} then {b}");
}

#[test]
fn issue_16_window_user_drives_a_room_without_script() {
    let test = "issue_16_window_user_drives_a_room_without_script";
    if !display_ready(test) {
        return;
    }
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    // scenarios/empty.ron without its mission and expectations: what someone writes to drive.
    // Relative to the package root, cargo test's working directory (not a compile-time path).
    let scenarios = std::fs::canonicalize("../../scenarios").unwrap();
    let text = std::fs::read_to_string(scenarios.join("empty.ron")).unwrap();
    let robot = scenarios.join("robots/mecanum-4wd.ron").canonicalize().unwrap();
    let text: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("mission:") && !l.trim_start().starts_with("expect:"))
        .map(|l| {
            l.replace("\"robots/mecanum-4wd.ron\"", &format!("{:?}", robot.display().to_string())) + "\n"
        })
        .collect();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let file = dir.join("issue-16-no-script.ron");
    std::fs::write(&file, text).unwrap();

    let mut w = Window::open("no-script", &[file.to_str().unwrap()]);
    // The twin keeps running at 1x with nobody driving: no "run finished" after half a second.
    let first = w.wait("the window at 1 s", START_TIMEOUT, |s| t_s(s) >= 1.0);
    assert_eq!(first["script"]["text"], "no script, you drive");
    assert_eq!(first["script"]["user_drives"], true);
    w.wait("time goes on", STEP_TIMEOUT, |s| t_s(s) >= t_s(&first) + 1.0);
    map_then_click_to_go(&mut w);
    click_then_stop(&mut w);
}

#[test]
fn issue_16_window_user_drives_after_the_default_script() {
    let test = "issue_16_window_user_drives_after_the_default_script";
    if !display_ready(test) {
        return;
    }
    let _one = ONE_WINDOW.lock().unwrap_or_else(|e| e.into_inner());
    let mut w = Window::open("default", &[]);
    w.press("Max");
    let done =
        w.wait("the script ends and the verdict shows", STEP_TIMEOUT * 2, |s| s["verdict"].is_object());
    let ended = done["script"]["headless_end_s"].as_f64().unwrap();
    assert!(done["script"]["text"].as_str().unwrap().starts_with("script done at"), "{:?}", done["script"]);
    assert_eq!(done["verdict"]["line"], "expectations PASS (5/5)");
    assert_eq!(cell_of(&done["cute"]["cell"]), Some((7, 9)), "the script's GoTo(7, 9)");
    // Nobody clicked during the script: the window's run is the headless run up to its end.
    let mut headless = Lockstep::new(RunSetup::builtin_default().unwrap(), None).unwrap();
    headless.run_to_end(|_| {});
    assert_eq!(headless.headless_end().map(|t| t.as_secs_f64()), Some(ended));
    // The twin goes on after the script.
    let after = w.wait("time goes on after the script", STEP_TIMEOUT, |s| t_s(s) > ended + 20.0);
    // Carto's layer: shown from the start, with the walls the sonar heard; its button hides it and
    // shows it again.
    assert_eq!(after["carto_layer"]["shown"], true, "{:?}", after["carto_layer"]);
    assert!(after["carto_layer"]["occupied"].as_u64().unwrap() > 50, "{:?}", after["carto_layer"]);
    assert!(after["carto_layer"]["free"].as_u64().unwrap() > 1000, "{:?}", after["carto_layer"]);
    w.press("Carto's map");
    w.wait("Carto's layer hidden", STEP_TIMEOUT, |s| s["carto_layer"]["shown"] == false);
    w.press("Carto's map");
    w.wait("Carto's layer shown again", STEP_TIMEOUT, |s| s["carto_layer"]["shown"] == true);
    // The user drives: a fresh map, the same buttons, a click.
    w.press("Reset map");
    w.wait("the map reset", STEP_TIMEOUT, |s| known_free(s) <= 2);
    map_then_click_to_go(&mut w);
    // Restart: the scenario from its start, script and all.
    w.press("Restart");
    let again = w.wait("restarted", STEP_TIMEOUT, |s| s["verdict"].is_null() && t_s(s) < ended);
    assert!(again["script"]["text"].as_str().unwrap().starts_with("script step"), "{:?}", again["script"]);
    w.wait("the script ends again at the same time", STEP_TIMEOUT * 2, |s| s["verdict"].is_object());
    let s = w.status().unwrap();
    assert_eq!(s["script"]["headless_end_s"].as_f64(), Some(ended), "same seed, same run");
}
