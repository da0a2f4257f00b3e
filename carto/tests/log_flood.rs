//! Issue 45: every line Carto logs about client input goes through one rate limiter, per kind and
//! per client host. A megabyte of each malformed kind the issue names, fed to [`Carto`] at the
//! speed the binary reads it (64 KiB a millisecond), writes a few kilobytes of log, and every
//! frame is either logged or counted in a "N more like this" summary.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::io::Write;
use std::sync::{Arc, Mutex};

use carto::{Carto, CartoConfig};
use robot_model::time::{Duration, Instant};

/// A tracing writer that keeps everything in memory.
#[derive(Clone, Default)]
struct Captured(Arc<Mutex<Vec<u8>>>);

impl Write for Captured {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl<'a> tracing_subscriber::fmt::MakeWriter<'a> for Captured {
    type Writer = Captured;
    fn make_writer(&'a self) -> Captured {
        self.clone()
    }
}

/// Runs `f` with INFO logging captured; returns the log text.
fn capture(f: impl FnOnce()) -> String {
    let out = Captured::default();
    let subscriber = tracing_subscriber::fmt()
        .with_max_level(tracing::Level::INFO)
        .with_ansi(false)
        .with_writer(out.clone())
        .finish();
    tracing::subscriber::with_default(subscriber, f);
    String::from_utf8(out.0.lock().unwrap().clone()).unwrap()
}

/// A megabyte of `frame`, repeated.
fn megabyte_of(frame: &[u8]) -> (Vec<u8>, usize) {
    let n = (1 << 20) / frame.len();
    (frame.repeat(n), n)
}

/// The malformed kinds of the issue, big-endian `Msg` as our Cute sends it.
const KINDS: [(&str, &[u8], &str); 5] = [
    ("cartography moves with command 9", &[0x00, 0x03, 0x02, 0x00, 9], "is not a move"),
    ("trajectories with n_total 0", &[0x00, 0x04, 0x01, 0x00, 0, 0], "n_total 0"),
    ("positions with direction 9", &[0x00, 0x05, 0x07, 0x00, 1, 1, 9], "invalid direction"),
    ("STOP frames", &[0x00, 0x02, 0x06, 0x00], "stop: motors stopped"),
    ("MOVE_DONE sent by the client", &[0x00, 0x02, 0x03, 0x00], "message for Cute received by Carto"),
];

/// Feeds `bytes` as the binary would (64 KiB per 1 ms step), then 3 s of polls; the log.
fn flood(bytes: &[u8]) -> String {
    capture(|| {
        let mut carto = Carto::new(CartoConfig::default());
        let mut now = Instant::ZERO;
        carto.on_client_connected(now, "10.0.0.7:40000");
        for chunk in bytes.chunks(64 * 1024) {
            carto.on_client_bytes(now, chunk);
            carto.poll(now);
            carto.take_client_bytes();
            now += Duration::from_millis(1);
        }
        for _ in 0..3000 {
            carto.poll(now);
            carto.take_client_bytes();
            now += Duration::from_millis(1);
        }
    })
}

/// The count of a `more=N` field, summed over the lines that contain `what` or are its summary.
fn suppressed(log: &str) -> u64 {
    log.lines()
        .filter_map(|l| l.split("more=").nth(1))
        .filter_map(|rest| rest.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

#[test]
fn issue_45_a_megabyte_of_each_malformed_kind_writes_a_few_kilobytes_of_log() {
    for (name, frame, line) in KINDS {
        let (bytes, frames) = megabyte_of(frame);
        let log = flood(&bytes);
        let logged = log.lines().filter(|l| l.contains(line) && !l.contains("more like this")).count() as u64;
        eprintln!("{name}: {frames} frames, {} bytes of log in {} lines", log.len(), log.lines().count());
        assert!(logged >= 1, "{name}: the input was not logged at all:\n{log}");
        assert!(log.len() < 4096, "{name}: {} bytes of log for 1 MB of input:\n{log}", log.len());
        // Nothing is lost: each frame is logged or counted in exactly one summary.
        assert_eq!(logged + suppressed(&log), frames as u64, "{name}:\n{log}");
    }
}

#[test]
fn issue_45_two_thousand_connections_from_one_host_write_a_few_lines() {
    let log = capture(|| {
        let mut carto = Carto::new(CartoConfig::default());
        let mut now = Instant::ZERO;
        for i in 0..2000u32 {
            carto.on_client_connected(now, &format!("10.0.0.7:{}", 20_000 + i));
            carto.poll(now);
            carto.on_client_disconnected(now);
            now += Duration::from_micros(500);
        }
        for _ in 0..1500 {
            now += Duration::from_millis(1);
            carto.poll(now);
        }
    });
    let logged =
        |what: &str| log.lines().filter(|l| l.contains(what) && !l.contains("more like this")).count() as u64;
    let (connected, gone) = (logged("client connected"), logged("client disconnected"));
    eprintln!("2000 connections: {} bytes of log in {} lines", log.len(), log.lines().count());
    assert!(connected >= 1 && gone >= 1, "{log}");
    assert!(log.lines().count() <= 12, "{log}");
    assert_eq!(connected + gone + suppressed(&log), 4000, "{log}");
}

#[test]
fn issue_45_each_client_host_has_its_own_budget() {
    let log = capture(|| {
        let mut carto = Carto::new(CartoConfig::default());
        let now = Instant::ZERO;
        for host in ["10.0.0.7", "10.0.0.8"] {
            carto.on_client_connected(now, &format!("{host}:5000"));
            carto.on_client_bytes(now, &[0x00, 0x02, 0x06, 0x00, 0x00, 0x02, 0x06, 0x00]);
            carto.on_client_disconnected(now);
        }
    });
    // One STOP line per host, the second STOP of each counted.
    assert_eq!(log.lines().filter(|l| l.contains("stop: motors stopped")).count(), 2, "{log}");
    assert!(!log.contains("more like this"), "each host's second STOP is counted, not summarised yet: {log}");
    assert!(log.contains("10.0.0.7:5000") && log.contains("10.0.0.8:5000"), "{log}");
}
