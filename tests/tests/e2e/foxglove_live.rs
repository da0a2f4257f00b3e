//! Issue 13: the live Foxglove WebSocket server, seen by a client speaking the protocol
//! (`foxglove.sdk.v1`): it reads the channel advertisement, subscribes, and decodes the
//! messages it receives.
//!
//! 1. `explobot sim --serve --foxglove ADDR` (real time): the true pose, the room.
//! 2. `explobot run --window --foxglove ADDR` (needs a display: `.ci/test` runs everything under
//!    Xvfb; without one the test says SKIPPED, except in CI, where it fails): the pose and Cute's
//!    map.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::processes::{Guard, TempDir, binary, free_port, free_port_pair, wait_for, workspace_root};
use foxglove::messages::{Grid, PoseInFrame, SceneUpdate};
use prost::Message as _;
use serde_json::{Value, json};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// A Foxglove WebSocket client: the channels the server advertised, by topic (id, schema).
struct Client {
    ws: WebSocket<MaybeTlsStream<TcpStream>>,
    channels: BTreeMap<String, (u64, String)>,
}

impl Client {
    /// Connects to `port` (retried while the server starts) and reads the advertisements until
    /// every topic of `want` is known.
    fn connect(port: u16, want: &[&str]) -> Client {
        let ws = wait_for("the foxglove server to accept", Duration::from_secs(60), || {
            let mut request = format!("ws://127.0.0.1:{port}").into_client_request().unwrap();
            request.headers_mut().insert("Sec-WebSocket-Protocol", "foxglove.sdk.v1".parse().unwrap());
            tungstenite::connect(request).ok().map(|(ws, _)| ws)
        });
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_secs(1))).unwrap();
        }
        let mut client = Client { ws, channels: BTreeMap::new() };
        let deadline = Instant::now() + Duration::from_secs(60);
        while !want.iter().all(|t| client.channels.contains_key(*t)) {
            assert!(Instant::now() < deadline, "advertised only {:?}", client.channels.keys());
            if let Some(Message::Text(text)) = client.next() {
                let v: Value = serde_json::from_str(&text).unwrap();
                if v["op"] == "advertise" {
                    for c in v["channels"].as_array().unwrap() {
                        let topic = c["topic"].as_str().unwrap().to_owned();
                        let schema = c["schemaName"].as_str().unwrap_or_default().to_owned();
                        client.channels.insert(topic, (c["id"].as_u64().unwrap(), schema));
                    }
                }
            }
        }
        client
    }

    /// The next message, `None` after a read timeout.
    fn next(&mut self) -> Option<Message> {
        match self.ws.read() {
            Ok(m) => Some(m),
            Err(tungstenite::Error::Io(e))
                if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) =>
            {
                None
            }
            Err(e) => panic!("the server closed the connection: {e}"),
        }
    }

    /// Subscribes to `topics` (subscription id = place in the list) and collects the payloads
    /// and log times received per topic until `enough` says so.
    fn receive(
        &mut self,
        topics: &[&str],
        limit: Duration,
        enough: impl Fn(&BTreeMap<String, Vec<(u64, Vec<u8>)>>) -> bool,
    ) -> BTreeMap<String, Vec<(u64, Vec<u8>)>> {
        let subscriptions: Vec<Value> = topics
            .iter()
            .enumerate()
            .map(|(i, t)| json!({"id": i, "channelId": self.channels[*t].0}))
            .collect();
        let subscribe = json!({"op": "subscribe", "subscriptions": subscriptions}).to_string();
        self.ws.send(Message::Text(subscribe.into())).unwrap();
        let mut got: BTreeMap<String, Vec<(u64, Vec<u8>)>> = BTreeMap::new();
        let deadline = Instant::now() + limit;
        while !enough(&got) {
            assert!(Instant::now() < deadline, "after {limit:?} only {:?}", counts(&got));
            // Message data: opcode 1, subscription id (u32 LE), log time (u64 LE, ns), payload.
            if let Some(Message::Binary(data)) = self.next()
                && data.len() >= 13
                && data[0] == 1
            {
                let id = u32::from_le_bytes(data[1..5].try_into().unwrap()) as usize;
                let time = u64::from_le_bytes(data[5..13].try_into().unwrap());
                got.entry(topics[id].to_owned()).or_default().push((time, data[13..].to_vec()));
            }
        }
        got
    }
}

fn counts(got: &BTreeMap<String, Vec<(u64, Vec<u8>)>>) -> Vec<(String, usize)> {
    got.iter().map(|(t, v)| (t.clone(), v.len())).collect()
}

/// Stdout lines of a child, as they come.
fn lines_of(child: &mut std::process::Child) -> Arc<Mutex<Vec<String>>> {
    let lines: Arc<Mutex<Vec<String>>> = Arc::default();
    let sink = Arc::clone(&lines);
    let stdout = child.stdout.take().unwrap();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            sink.lock().unwrap().push(line);
        }
    });
    lines
}

#[test]
fn issue_13_served_twin_streams_poses_to_a_websocket_client() {
    let dir = TempDir::new("explobot-fox-serve");
    // The twin listens on `boards` and `boards + 1`; the Foxglove server must not take either.
    let boards = free_port_pair();
    let port = loop {
        let p = free_port();
        if p != boards && p != boards + 1 {
            break p;
        }
    };
    let mut child = Command::new(binary("explobot"))
        .args(["sim", "scenarios/empty.ron", "--serve", "--tcp", &boards.to_string(), "--status-every", "0"])
        .args(["--foxglove", &format!("127.0.0.1:{port}"), "--run-dir"])
        .arg(dir.0.join("run"))
        .current_dir(workspace_root())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lines = lines_of(&mut child);
    let _guard = Guard(child);
    wait_for("the server line", Duration::from_secs(60), || {
        lines.lock().unwrap().iter().any(|l| l.contains(&format!("ws://127.0.0.1:{port}"))).then_some(())
    });
    let mut client = Client::connect(port, &["/robot/pose", "/room", "/tf", "/links/motor/bytes"]);
    assert_eq!(client.channels["/robot/pose"].1, "foxglove.PoseInFrame");
    let got = client.receive(&["/robot/pose", "/room"], Duration::from_secs(60), |g| {
        g.get("/robot/pose").is_some_and(|p| p.len() >= 5) && g.contains_key("/room")
    });
    // Poses on the sim clock, 100 ms apart (20 steps of 5 ms), at the start cell of the empty room.
    let poses = &got["/robot/pose"];
    for pair in poses.windows(2) {
        assert_eq!(
            pair[1].0 - pair[0].0,
            100_000_000,
            "log times {:?}",
            poses.iter().map(|p| p.0).collect::<Vec<_>>()
        );
    }
    let pose = PoseInFrame::decode(&poses[0].1[..]).unwrap();
    assert_eq!(pose.frame_id, "world");
    let position = pose.pose.unwrap().position.unwrap();
    assert!(position.x > 0.0 && position.y > 0.0, "{position:?}");
    // The room was sent again on subscribing: walls and obstacles.
    let room = SceneUpdate::decode(&got["/room"][0].1[..]).unwrap();
    assert!(room.entities.iter().any(|e| e.id == "room" && !e.lines.is_empty()));
}

#[test]
fn issue_13_window_run_streams_poses_and_cute_map() {
    let ci = std::env::var_os("CI").is_some();
    if std::env::var_os("DISPLAY").is_none() {
        assert!(!ci, "no display in CI (DISPLAY is unset); run the tests under xvfb-run");
        println!("SKIPPED issue_13_window_run_streams_poses_and_cute_map: no display; run under xvfb-run");
        return;
    }
    let port = free_port();
    // Xvfb refuses connections for a moment after its last client leaves: start again then.
    let mut attempt = 0;
    let (lines, _guard) = loop {
        attempt += 1;
        let mut child = Command::new(binary("explobot"))
            .args(["run", "scenarios/default.ron", "--foxglove", &format!("127.0.0.1:{port}")])
            .current_dir(workspace_root())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let lines = lines_of(&mut child);
        let stderr = child.stderr.take().unwrap();
        let errors: Arc<Mutex<String>> = Arc::default();
        let sink = Arc::clone(&errors);
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                sink.lock().unwrap().push_str(&(line + "\n"));
            }
        });
        let mut guard = Guard(child);
        std::thread::sleep(Duration::from_secs(3));
        match guard.0.try_wait().unwrap() {
            None => break (lines, guard),
            Some(code) => {
                let err = errors.lock().unwrap().clone();
                assert!(
                    err.contains("XOpenDisplayFailed") && attempt < 4,
                    "the window exited ({code})\n{err}"
                );
            }
        }
    };
    wait_for("the server line", Duration::from_secs(120), || {
        lines.lock().unwrap().iter().any(|l| l.contains(&format!("ws://127.0.0.1:{port}"))).then_some(())
    });
    let mut client = Client::connect(port, &["/robot/pose", "/cute/map", "/carto/pose"]);
    assert_eq!(client.channels["/cute/map"].1, "foxglove.Grid");
    let got = client.receive(&["/robot/pose", "/cute/map"], Duration::from_secs(120), |g| {
        g.get("/robot/pose").is_some_and(|p| p.len() >= 3) && g.contains_key("/cute/map")
    });
    let grid = Grid::decode(&got["/cute/map"][0].1[..]).unwrap();
    // The default room is 8 × 10 cells; 5 bytes a cell (RGBA and Cute's number).
    assert_eq!((grid.column_count, grid.data.len()), (10, 8 * 10 * 5));
    let pose = PoseInFrame::decode(&got["/robot/pose"][0].1[..]).unwrap();
    assert_eq!(pose.frame_id, "world");
}
