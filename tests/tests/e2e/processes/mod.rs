//! Processes and clients for the multi-process tests (`daemon.rs`, `serial_hil.rs`,
//! `serve_e2e.rs`): the served twin, the `carto` binary, a link-protocol client, our Cute without
//! its window, pty pairs made by `socat`, scratch folders, all cleaned up on drop.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![allow(dead_code)]

use std::ffi::OsString;
use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use cute::{Cute, CuteConfig, CuteRuntime};
use protocol::link::{Decoder, GuiMessage, MsgOrder};
use robot_model::grid::Heading;
use transport::{Clock, Link, TcpConnector, TcpLink, WallClock};

/// Kills the child process when dropped, so a failing test leaves nothing running.
pub struct Guard(pub Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A scratch folder removed when the test ends, passed or failed.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(name: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The workspace's binaries sit next to this test's `deps/` folder, or in `EXPLOBOT_BIN_DIR` if
/// set (when several checkouts share one target directory, its `release/carto` is whichever
/// checkout built last).
pub fn binary(name: &str) -> PathBuf {
    if let Some(dir) = std::env::var_os("EXPLOBOT_BIN_DIR") {
        return PathBuf::from(dir).join(name);
    }
    let exe = std::env::current_exe().expect("test executable path");
    let dir = exe.parent().and_then(Path::parent).expect("target profile folder");
    let path = dir.join(name);
    assert!(
        path.exists(),
        "{} is missing: build the workspace binaries first (cargo test --workspace builds them)",
        path.display()
    );
    path
}

/// The repository root: the parent of the package root, which is `cargo test`'s working directory
/// (a path baked in at compile time would go stale when two checkouts share a target directory).
pub fn workspace_root() -> PathBuf {
    std::env::current_dir().unwrap().parent().unwrap().to_path_buf()
}

pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// A free port whose next one is free too: a base for `explobot sim --serve --tcp BASE`, which
/// listens on BASE (motor) and BASE + 1 (sensor).
pub fn free_port_pair() -> u16 {
    loop {
        let p = free_port();
        if p < u16::MAX && TcpListener::bind(("127.0.0.1", p + 1)).is_ok() {
            return p;
        }
    }
}

/// Polls `f` every 5 ms until it gives a value; panics naming `what` after `limit`.
pub fn wait_for<T>(what: &str, limit: Duration, mut f: impl FnMut() -> Option<T>) -> T {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(v) = f() {
            return v;
        }
        assert!(Instant::now() < deadline, "timed out after {limit:?} waiting for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The wheel setpoints of a twin status line (`… wheels [a, b, c, d] rpm`).
pub fn wheels(line: &str) -> Option<Vec<f64>> {
    let rest = line.split("wheels [").nth(1)?;
    let inner = rest.split(']').next()?;
    inner.split(',').map(|v| v.trim().parse().ok()).collect()
}

/// `explobot sim scenarios/empty.ron --serve --tcp BASE` in real time, its status lines kept
/// with the wall time each arrived.
pub struct Twin {
    pub base: u16,
    lines: Arc<Mutex<Vec<(Instant, String)>>>,
    _child: Guard,
}

impl Twin {
    /// On two free ports.
    pub fn start(dir: &TempDir, status_every: f64) -> Twin {
        Self::start_on(dir, free_port_pair(), status_every)
    }

    /// On ports `base` (motor) and `base + 1` (sensor); returns once it serves.
    pub fn start_on(dir: &TempDir, base: u16, status_every: f64) -> Twin {
        let mut args: Vec<OsString> =
            ["scenarios/empty.ron", "--tcp", &base.to_string()].map(Into::into).into();
        args.extend(["--status-every".into(), status_every.to_string().into(), "--run-dir".into()]);
        args.push(dir.0.join("run").into());
        Self::serve(base, &args)
    }

    /// `explobot sim --serve ARGS` (scenario and ports in `args`); `base` is its TCP base port, if
    /// any. Returns once it serves.
    pub fn serve(base: u16, args: &[OsString]) -> Twin {
        let mut child = Command::new(binary("explobot"))
            .args(["sim", "--serve"])
            .args(args)
            .current_dir(workspace_root())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start explobot sim --serve");
        let stdout = child.stdout.take().unwrap();
        let child = Guard(child);
        let lines: Arc<Mutex<Vec<(Instant, String)>>> = Arc::default();
        let sink = Arc::clone(&lines);
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                sink.lock().unwrap().push((Instant::now(), line));
            }
        });
        let twin = Twin { base, lines, _child: child };
        twin.wait_line("the twin to serve", Duration::from_secs(60), |l| l.contains("start Carto with"));
        twin
    }

    /// Waits for a status line matching `pred` that arrived within `limit` from now (or was
    /// already there after `since`, see [`Twin::wait_line_since`]).
    pub fn wait_line(&self, what: &str, limit: Duration, pred: impl Fn(&str) -> bool) -> Instant {
        self.wait_line_since(Instant::now(), what, limit, pred)
    }

    /// The arrival time of the first line after `since` that matches `pred`; panics if none
    /// arrives by `since + limit`.
    pub fn wait_line_since(
        &self,
        since: Instant,
        what: &str,
        limit: Duration,
        pred: impl Fn(&str) -> bool,
    ) -> Instant {
        let deadline = since.max(Instant::now()) + limit;
        loop {
            let found =
                self.lines.lock().unwrap().iter().find(|(t, l)| *t >= since && pred(l)).map(|(t, _)| *t);
            if let Some(t) = found {
                assert!(t <= since + limit, "{what}: only {:?} after", t.duration_since(since));
                return t;
            }
            if Instant::now() >= deadline {
                panic!("timed out waiting for {what}; last twin line: {}", self.last_line());
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    pub fn last_line(&self) -> String {
        self.lines.lock().unwrap().last().map(|(_, l)| l.clone()).unwrap_or_default()
    }
}

/// The `carto` binary on the given board ports (TCP), listening on a free port, its log in a file.
pub struct Carto {
    pub port: u16,
    log: PathBuf,
    child: Guard,
    exit: Option<Option<i32>>,
}

impl Carto {
    pub fn start(dir: &TempDir, motor: u16, sensor: u16, extra: &[&str]) -> Carto {
        let motor = format!("127.0.0.1:{motor}");
        let sensor = format!("127.0.0.1:{sensor}");
        Self::start_on(dir, "tcp", (Path::new(&motor), Path::new(&sensor)), extra)
    }

    /// On the boards at `motor` and `sensor` (device paths, or HOST:PORT with `tcp`) reached with
    /// `--transport transport`.
    pub fn start_on(
        dir: &TempDir,
        transport: &str,
        (motor, sensor): (&Path, &Path),
        extra: &[&str],
    ) -> Carto {
        let port = free_port();
        let log = dir.0.join(format!("carto-{port}.log"));
        let child = Command::new(binary("carto"))
            .args(["--transport", transport, "--motor-port"])
            .arg(motor)
            .arg("--sensor-port")
            .arg(sensor)
            .args(["--listen", &format!("127.0.0.1:{port}"), "--profile", "scenarios/robots/mecanum-4wd.ron"])
            .args(["--cell", "0.30"]) // scenarios/empty.ron is drawn for 0.30 m cells
            .args(extra)
            .env("RUST_LOG", "info")
            .env("NO_COLOR", "1")
            .current_dir(workspace_root())
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .spawn()
            .expect("start carto");
        let carto = Carto { port, log, child: Guard(child), exit: None };
        wait_for("carto to listen", Duration::from_secs(30), || {
            carto.log().contains("carto ready").then_some(())
        });
        carto
    }

    /// A new client connection (retried while Carto starts).
    pub fn client(&self) -> Client {
        let link = wait_for("a connection to carto", Duration::from_secs(20), || {
            TcpLink::connect(("127.0.0.1", self.port)).ok()
        });
        Client { link, decoder: Decoder::default() }
    }

    pub fn log(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// Sends signal `name` (`TERM`, `INT`, `HUP`) with `kill`.
    pub fn signal(&self, name: &str) {
        let ok = Command::new("kill").arg(format!("-{name}")).arg(self.child.0.id().to_string()).status();
        assert!(ok.is_ok_and(|s| s.success()), "kill -{name} failed");
    }

    /// The exit code if Carto has exited (`Some(None)`: killed by a signal).
    pub fn try_exit(&mut self) -> Option<Option<i32>> {
        if self.exit.is_none() {
            self.exit = self.child.0.try_wait().unwrap().map(|s| s.code());
        }
        self.exit
    }

    /// Waits up to `limit` for Carto to exit; its exit code.
    pub fn wait_exit(&mut self, limit: Duration) -> Option<i32> {
        wait_for("carto to exit", limit, || self.try_exit())
    }
}

/// Our Cute, the library's session without its window, connected to a `carto` over TCP on the
/// wall clock, as the `cute` binary runs it.
pub struct CuteClient {
    runtime: CuteRuntime<TcpConnector>,
    clock: WallClock,
}

impl CuteClient {
    /// A session on a `rows` × `cols` map, the robot in cell (0, 0) facing east, dialling `port`.
    pub fn connect(port: u16, rows: usize, cols: usize) -> CuteClient {
        let config =
            CuteConfig { rows, cols, start: (0, 0), heading: Heading::East, ..CuteConfig::default() };
        let connector = TcpConnector::new(format!("127.0.0.1:{port}")).timeout(Duration::from_millis(200));
        CuteClient {
            runtime: CuteRuntime::new(Cute::new(config).unwrap(), connector),
            clock: WallClock::start(),
        }
    }

    /// Starts cartography as soon as Carto acknowledges the position and runs it until `moves`
    /// moves are done (or the room is mapped); panics after `limit`.
    pub fn map_for(&mut self, moves: u64, limit: Duration) -> &Cute {
        let deadline = Instant::now() + limit;
        let mut started = false;
        loop {
            let now = self.clock.now();
            self.runtime.step_with(now, |cute| {
                if !started && cute.is_ready() {
                    cute.start_cartography().unwrap();
                    started = true;
                }
            });
            let cute = self.runtime.cute();
            if started && (cute.counters().moves_done >= moves || cute.cartographer().is_none()) {
                return self.runtime.cute();
            }
            assert!(
                Instant::now() < deadline,
                "cartography did not make {moves} moves within {limit:?}: {:?}\n{}",
                cute.counters(),
                cute.map().to_text()
            );
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

/// A pair of connected pseudo-terminals made by `socat`, at `DIR/a` and `DIR/b`: two serial
/// device paths wired to each other, as two USB-serial adapters with crossed TX and RX.
pub struct SerialPair {
    pub a: PathBuf,
    pub b: PathBuf,
    _socat: Guard,
}

impl SerialPair {
    pub fn new(dir: &TempDir, a: &str, b: &str) -> SerialPair {
        let (a, b) = (dir.0.join(a), dir.0.join(b));
        let end = |p: &Path| format!("pty,raw,echo=0,link={}", p.display());
        let socat = Command::new("socat")
            .args(["-d", "-d", &end(&a), &end(&b)])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("socat is missing: apt-get install socat (.ci/run installs it)");
        let socat = Guard(socat);
        wait_for("socat's ptys", Duration::from_secs(10), || (a.exists() && b.exists()).then_some(()));
        SerialPair { a, b, _socat: socat }
    }
}

/// A client speaking the link protocol (big-endian, as our Cute).
pub struct Client {
    link: TcpLink,
    decoder: Decoder,
}

impl Client {
    pub fn send(&mut self, m: GuiMessage) {
        self.send_raw(&m.to_bytes(MsgOrder::BigEndian));
    }

    pub fn send_raw(&mut self, bytes: &[u8]) {
        self.try_send_raw(bytes).unwrap_or_else(|e| panic!("{e}"));
    }

    /// Sends `m`, or says why the connection would not take it.
    pub fn try_send(&mut self, m: GuiMessage) -> Result<(), String> {
        self.try_send_raw(&m.to_bytes(MsgOrder::BigEndian))
    }

    /// Sends raw bytes, or says why the connection would not take them.
    pub fn try_send_raw(&mut self, mut bytes: &[u8]) -> Result<(), String> {
        let deadline = Instant::now() + Duration::from_secs(60);
        while !bytes.is_empty() {
            let n = self.link.write(bytes).map_err(|e| format!("carto closed the connection: {e}"))?;
            bytes = &bytes[n..];
            if n == 0 {
                if Instant::now() >= deadline {
                    return Err("carto stopped reading".to_owned());
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        Ok(())
    }

    /// Messages up to the first matching `want`, or why there was none within `limit`.
    pub fn try_read_until(
        &mut self,
        want: impl Fn(&GuiMessage) -> bool,
        limit: Duration,
    ) -> Result<Vec<GuiMessage>, String> {
        let deadline = Instant::now() + limit;
        let mut seen = Vec::new();
        let mut buf = [0u8; 256];
        while Instant::now() < deadline {
            let n = self.link.read(&mut buf).map_err(|e| format!("{e} (after {seen:?})"))?;
            for m in self.decoder.feed(&buf[..n]) {
                let m = m.map_err(|e| format!("bad frame from carto: {e}"))?;
                let done = want(&m);
                seen.push(m);
                if done {
                    return Ok(seen);
                }
            }
            if n == 0 {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        Err(format!("timed out after {limit:?}; received so far: {seen:?}"))
    }

    pub fn read_until(&mut self, want: impl Fn(&GuiMessage) -> bool, limit: Duration) -> Vec<GuiMessage> {
        self.try_read_until(want, limit).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Every message received during `span` (panics if the connection closes).
    pub fn collect_for(&mut self, span: Duration) -> Vec<GuiMessage> {
        let deadline = Instant::now() + span;
        let mut seen = Vec::new();
        let mut buf = [0u8; 256];
        while Instant::now() < deadline {
            let n = self.link.read(&mut buf).unwrap_or_else(|e| panic!("{e} (after {seen:?})"));
            seen.extend(self.decoder.feed(&buf[..n]).into_iter().map(|m| m.expect("well-formed frame")));
            if n == 0 {
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        seen
    }

    /// Whether Carto closes this connection within `limit`.
    pub fn is_closed_within(&mut self, limit: Duration) -> bool {
        let deadline = Instant::now() + limit;
        let mut buf = [0u8; 256];
        while Instant::now() < deadline {
            match self.link.read(&mut buf) {
                Err(e) if e.is_disconnected() => return true,
                Err(_) => return true,
                Ok(_) => std::thread::sleep(Duration::from_millis(5)),
            }
        }
        false
    }
}

/// `Command::output` with a time limit (the child is killed past it).
pub trait OutputWithin {
    fn output_within(&mut self, limit: Duration) -> Output;
}

impl OutputWithin for Command {
    fn output_within(&mut self, limit: Duration) -> Output {
        let child = self.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn");
        let pid = child.id();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(child.wait_with_output());
        });
        match rx.recv_timeout(limit) {
            Ok(out) => out.expect("wait for the child"),
            Err(_) => {
                let _ = Command::new("kill").arg("-KILL").arg(pid.to_string()).status();
                panic!("the command did not finish within {limit:?}");
            }
        }
    }
}
