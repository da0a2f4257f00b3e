//! One conformance suite for every `Link` in the crate.
//!
//! [`conformance`] runs the same checks over a factory of connected pairs `(a, b)`:
//! bytes arrive in order both ways; a read with nothing pending returns `Ok(0)` without blocking;
//! 64 KiB each way at once arrive intact with partial writes handled; closing one end gives the
//! other `Disconnected`. Real links are polled in bounded loops with a wall-clock deadline, and
//! every check runs on a watchdog thread, so a link that blocks fails the test instead of hanging
//! it. None of this asserts timing.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use transport::{
    Connector, ErrorKind, Link, LinkError, Listener, MemLink, MockClock, PtyLink, SerialLink, TcpLink,
    TcpListenerLink, mem_listener,
};

/// How long a check may poll before it fails.
const DEADLINE: Duration = Duration::from_secs(5);
/// How long a check may run at all (it fails if it blocks longer).
const WATCHDOG: Duration = Duration::from_secs(10);

/// A connected pair and what the suite needs to know about it.
struct Pair<A, B> {
    a: A,
    b: B,
    /// Lets time pass: advances the mock clock, or sleeps a little for real links.
    tick: Box<dyn FnMut() + Send>,
    /// Whether bytes `a` wrote just before closing still reach `b` (a pty slave hangs up when its
    /// master closes, and the kernel drops what it had not read).
    a_close_delivers: bool,
    /// Whether bytes `b` wrote just before closing still reach `a`.
    b_close_delivers: bool,
    /// Whether `a` keeps failing after reporting `Disconnected` (a pty master instead waits for
    /// the next client).
    a_stays_disconnected: bool,
}

/// Runs `f` on its own thread; fails if it panics or does not finish within [`WATCHDOG`].
fn guarded(name: &str, f: impl FnOnce() + Send + 'static) {
    let (tx, rx) = mpsc::channel();
    let handle = std::thread::spawn(move || {
        f();
        let _ = tx.send(());
    });
    match rx.recv_timeout(WATCHDOG) {
        Ok(()) => handle.join().unwrap(),
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            if let Err(panic) = handle.join() {
                eprintln!("check `{name}` failed");
                std::panic::resume_unwind(panic);
            }
        }
        Err(mpsc::RecvTimeoutError::Timeout) => {
            panic!("check `{name}` did not finish within {WATCHDOG:?}: a link call blocked?")
        }
    }
}

/// A deterministic byte pattern that is not periodic over 64 KiB.
fn pattern(n: usize, seed: u32) -> Vec<u8> {
    let mut x = seed.wrapping_mul(2_654_435_761).max(1);
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 24) as u8
        })
        .collect()
}

/// Moves `to_b` from a to b and `to_a` from b to a at the same time, handling partial writes.
/// Returns what each side received.
fn exchange<A: Link, B: Link>(p: &mut Pair<A, B>, to_b: &[u8], to_a: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let deadline = Instant::now() + DEADLINE;
    let (mut sent_a, mut sent_b) = (0, 0);
    let (mut got_a, mut got_b) = (Vec::new(), Vec::new());
    let mut buf = [0u8; 1500];
    while got_b.len() < to_b.len() || got_a.len() < to_a.len() {
        assert!(
            Instant::now() < deadline,
            "exchange stalled: a sent {sent_a}/{}, b got {}; b sent {sent_b}/{}, a got {}",
            to_b.len(),
            got_b.len(),
            to_a.len(),
            got_a.len()
        );
        if sent_a < to_b.len() {
            let end = to_b.len().min(sent_a + 4096);
            sent_a += p.a.write(&to_b[sent_a..end]).expect("a write");
        }
        if sent_b < to_a.len() {
            let end = to_a.len().min(sent_b + 4096);
            sent_b += p.b.write(&to_a[sent_b..end]).expect("b write");
        }
        let nb = p.b.read(&mut buf).expect("b read");
        got_b.extend_from_slice(&buf[..nb]);
        let na = p.a.read(&mut buf).expect("a read");
        got_a.extend_from_slice(&buf[..na]);
        if na == 0 && nb == 0 {
            (p.tick)();
        }
    }
    (got_a, got_b)
}

fn nothing_pending_reads_zero<A: Link, B: Link>(mut p: Pair<A, B>) {
    let mut buf = [0u8; 64];
    assert_eq!(p.a.read(&mut buf).expect("a read"), 0);
    assert_eq!(p.b.read(&mut buf).expect("b read"), 0);
    // Still true after traffic has been drained.
    exchange(&mut p, b"x", b"y");
    assert_eq!(p.a.read(&mut buf).expect("a read"), 0);
    assert_eq!(p.b.read(&mut buf).expect("b read"), 0);
    // A zero-length read or write is not an error either.
    assert_eq!(p.a.read(&mut []).expect("a empty read"), 0);
    assert_eq!(p.b.write(&[]).expect("b empty write"), 0);
}

fn bytes_arrive_in_order_both_ways<A: Link, B: Link>(mut p: Pair<A, B>) {
    let (got_a, got_b) = exchange(&mut p, b"one", b"uno");
    assert_eq!((got_a.as_slice(), got_b.as_slice()), (&b"uno"[..], &b"one"[..]));
    let (got_a, got_b) = exchange(&mut p, b"two, three, \x00\xff\xaa\x0d\x0a", b"dos");
    assert_eq!(got_b, b"two, three, \x00\xff\xaa\x0d\x0a");
    assert_eq!(got_a, b"dos");
}

fn large_transfer_both_ways<A: Link, B: Link>(mut p: Pair<A, B>) {
    let to_b = pattern(64 * 1024, 1);
    let to_a = pattern(64 * 1024, 2);
    let (got_a, got_b) = exchange(&mut p, &to_b, &to_a);
    assert!(got_b == to_b, "a → b corrupted ({} bytes)", got_b.len());
    assert!(got_a == to_a, "b → a corrupted ({} bytes)", got_a.len());
}

/// Writes `msg` fully from `w`, then closes `w`; `r` must read (all or a prefix of) `msg`, then
/// `Disconnected`.
fn close_disconnects_peer<W: Link, R: Link>(
    mut w: W,
    mut r: R,
    tick: &mut dyn FnMut(),
    delivers: bool,
    stays_disconnected: bool,
) {
    let msg = b"last words before hanging up";
    let deadline = Instant::now() + DEADLINE;
    let mut sent = 0;
    while sent < msg.len() {
        assert!(Instant::now() < deadline, "could not write before closing");
        sent += w.write(&msg[sent..]).expect("write before close");
        tick();
    }
    drop(w);
    let mut got = Vec::new();
    let mut buf = [0u8; 64];
    let err = loop {
        assert!(Instant::now() < deadline, "no Disconnected after the peer closed (got {got:?})");
        match r.read(&mut buf) {
            Ok(0) => tick(),
            Ok(n) => got.extend_from_slice(&buf[..n]),
            Err(e) => break e,
        }
    };
    assert_eq!(err.kind(), ErrorKind::Disconnected, "{err}");
    if delivers {
        assert_eq!(got, msg, "bytes written before close must arrive first");
    } else {
        assert!(msg.starts_with(&got), "what arrived must be a prefix: {got:?}");
    }
    if stays_disconnected {
        assert!(r.read(&mut buf).is_err_and(|e| e.kind() == ErrorKind::Disconnected));
    }
}

fn a_close_disconnects_b<A: Link, B: Link>(p: Pair<A, B>) {
    let Pair { a, b, mut tick, a_close_delivers, .. } = p;
    close_disconnects_peer(a, b, &mut *tick, a_close_delivers, true);
}

fn b_close_disconnects_a<A: Link, B: Link>(p: Pair<A, B>) {
    let Pair { a, b, mut tick, b_close_delivers, a_stays_disconnected, .. } = p;
    close_disconnects_peer(b, a, &mut *tick, b_close_delivers, a_stays_disconnected);
}

/// The suite: every check on a fresh pair from `factory`.
fn conformance<A, B>(name: &str, factory: fn() -> Pair<A, B>)
where
    A: Link + Send + 'static,
    B: Link + Send + 'static,
    A::Error: LinkError,
    B::Error: LinkError,
{
    guarded(&format!("{name}: nothing pending"), move || nothing_pending_reads_zero(factory()));
    guarded(&format!("{name}: in order"), move || bytes_arrive_in_order_both_ways(factory()));
    guarded(&format!("{name}: 64 KiB"), move || large_transfer_both_ways(factory()));
    guarded(&format!("{name}: close a"), move || a_close_disconnects_b(factory()));
    guarded(&format!("{name}: close b"), move || b_close_disconnects_a(factory()));
}

fn sleep_tick() -> Box<dyn FnMut() + Send> {
    Box::new(|| std::thread::sleep(Duration::from_micros(200)))
}

fn clock_tick(clock: MockClock, micros: u64) -> Box<dyn FnMut() + Send> {
    Box::new(move || clock.advance(robot_model::time::Duration::from_micros(micros)))
}

/// A fresh path in the temp folder (the `PtyLink` removes its symlink when dropped).
fn unique_path(name: &str) -> std::path::PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    std::env::temp_dir().join(format!(
        "explobot-conformance-{}-{}-{name}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ))
}

fn mem_instant() -> Pair<MemLink, MemLink> {
    let clock = MockClock::new();
    let (a, b) = MemLink::pair(None, clock.clone());
    Pair {
        a,
        b,
        tick: clock_tick(clock, 1_000),
        a_close_delivers: true,
        b_close_delivers: true,
        a_stays_disconnected: true,
    }
}

fn mem_115200() -> Pair<MemLink, MemLink> {
    let clock = MockClock::new();
    let (a, b) = MemLink::pair(Some(115_200), clock.clone());
    Pair {
        a,
        b,
        tick: clock_tick(clock, 1_000),
        a_close_delivers: true,
        b_close_delivers: true,
        a_stays_disconnected: true,
    }
}

fn mem_connection() -> Pair<MemLink, MemLink> {
    let clock = MockClock::new();
    let (mut listener, mut connector) = mem_listener(Some(9_600 * 12), clock.clone());
    let a = connector.connect().unwrap();
    let (b, _) = listener.accept().unwrap().unwrap();
    Pair {
        a,
        b,
        tick: clock_tick(clock, 1_000),
        a_close_delivers: true,
        b_close_delivers: true,
        a_stays_disconnected: true,
    }
}

fn tcp() -> Pair<TcpLink, TcpLink> {
    let mut server = TcpListenerLink::bind("127.0.0.1:0").unwrap();
    let a = TcpLink::connect(server.local_addr()).unwrap();
    let deadline = Instant::now() + DEADLINE;
    let b = loop {
        if let Some((link, _)) = server.accept().unwrap() {
            break link;
        }
        assert!(Instant::now() < deadline, "accept timed out");
        std::thread::sleep(Duration::from_micros(200));
    };
    Pair {
        a,
        b,
        tick: sleep_tick(),
        a_close_delivers: true,
        b_close_delivers: true,
        a_stays_disconnected: true,
    }
}

fn pty() -> Pair<PtyLink, transport::PtyClient> {
    let (a, b) = PtyLink::pair().unwrap();
    Pair {
        a,
        b,
        tick: sleep_tick(),
        a_close_delivers: false,
        b_close_delivers: true,
        a_stays_disconnected: false,
    }
}

fn serial_on_pty() -> Pair<PtyLink, SerialLink> {
    // Through a symlink, as Carto opens run/tty-motor.
    let link = unique_path("tty-motor");
    let a = PtyLink::open_with_symlink(&link).unwrap();
    let b = SerialLink::builder(link.display().to_string(), 115_200).open().unwrap();
    Pair {
        a,
        b,
        tick: sleep_tick(),
        a_close_delivers: false,
        b_close_delivers: true,
        a_stays_disconnected: false,
    }
}

#[test]
fn mem_link_instant_conforms() {
    conformance("mem instant", mem_instant);
}

#[test]
fn mem_link_115200_baud_conforms() {
    conformance("mem 115200", mem_115200);
}

#[test]
fn mem_listener_connection_conforms() {
    conformance("mem connection", mem_connection);
}

#[test]
fn tcp_link_conforms() {
    conformance("tcp", tcp);
}

#[test]
fn pty_link_conforms() {
    conformance("pty", pty);
}

#[test]
fn serial_link_on_pty_conforms() {
    conformance("serial on pty", serial_on_pty);
}
