//! Measures how fast bytes move through each link (wall time; numbers for the README).
//!
//! `cargo run --release -p transport --example throughput`

use std::time::{Duration, Instant};

use transport::{
    ByteFaults, Error, FaultInjector, Link, Listener, MemLink, MockClock, PtyLink, SerialLink, TcpLink,
    TcpListenerLink, Tracer,
};

/// Pushes `total` bytes from `a` to `b` in chunks; returns MB/s.
fn pump(
    a: &mut impl Link<Error = Error>,
    b: &mut impl Link<Error = Error>,
    total: usize,
) -> Result<f64, Error> {
    let chunk = vec![0x5au8; 4096];
    let mut buf = vec![0u8; 4096];
    let (mut sent, mut got) = (0, 0);
    let start = Instant::now();
    while got < total {
        if sent < total {
            sent += a.write(&chunk[..chunk.len().min(total - sent)])?;
        }
        let n = b.read(&mut buf)?;
        got += n;
        if n == 0 && start.elapsed() > Duration::from_secs(30) {
            return Err(Error::disconnected("stalled"));
        }
    }
    Ok(total as f64 / start.elapsed().as_secs_f64() / 1e6)
}

fn main() -> Result<(), Error> {
    const MIB: usize = 1 << 20;

    let (mut a, mut b) = MemLink::pair(None, MockClock::new());
    println!("MemLink instant:                     {:8.1} MB/s", pump(&mut a, &mut b, 256 * MIB)?);

    let clock = MockClock::new();
    let (a, b) = MemLink::pair(None, clock.clone());
    let noisy = ByteFaults { drop_rate: 0.01, flip_rate: 0.01, duplicate_rate: 0.01 };
    let mut a = Tracer::new(FaultInjector::new(a, 1, clock.clone()).tx_faults(noisy), clock.clone());
    let mut b = FaultInjector::new(b, 2, clock.clone()).rx_faults(ByteFaults::NONE);
    // Count what arrives, not what was sent: faults change the length.
    let start = Instant::now();
    let chunk = vec![0x5au8; 4096];
    let mut buf = vec![0u8; 4096];
    let mut moved = 0usize;
    while moved < 32 * MIB {
        clock.advance(robot_model::time::Duration::from_micros(100));
        moved += a.write(&chunk)?;
        while b.read(&mut buf)? > 0 {}
    }
    let records = a.take_records().len();
    println!(
        "FaultInjector(1% each) + Tracer:     {:8.1} MB/s ({records} trace records)",
        moved as f64 / start.elapsed().as_secs_f64() / 1e6
    );

    // Lockstep: one minute of a 115200-baud motor link, 5 ms steps, a 10-byte frame every 20 ms
    // each way, as the runner would drive it.
    let clock = MockClock::new();
    let (mut carto, mut board) = MemLink::pair(Some(115_200), clock.clone());
    let frame = [0xAAu8, 1, 2, 3, 4, 5, 6, 7, 8, 9];
    let steps = 12_000u64;
    let start = Instant::now();
    let mut received = 0usize;
    for step in 0..steps {
        if step % 4 == 0 {
            carto.write(&frame)?;
            board.write(&frame)?;
        }
        received += board.read(&mut buf)? + carto.read(&mut buf)?;
        clock.advance(robot_model::time::Duration::from_micros(5_000));
    }
    let wall = start.elapsed().as_secs_f64();
    println!(
        "MemLink 115200 lockstep, 60 s sim:   {:8.2} ms wall ({:.0}× real time, {received} bytes)",
        wall * 1e3,
        60.0 / wall
    );

    let mut master = PtyLink::open()?;
    let mut port = SerialLink::builder(master.slave_path().display().to_string(), 115_200).open()?;
    println!("PtyLink → SerialLink (pty):          {:8.1} MB/s", pump(&mut master, &mut port, 32 * MIB)?);
    println!("SerialLink → PtyLink (pty):          {:8.1} MB/s", pump(&mut port, &mut master, 32 * MIB)?);

    let mut server = TcpListenerLink::bind("127.0.0.1:0")?;
    let mut client = TcpLink::connect(server.local_addr())?;
    let mut accepted = None;
    while accepted.is_none() {
        accepted = server.accept()?;
    }
    if let Some((mut peer, _)) = accepted {
        println!(
            "TcpLink loopback:                    {:8.1} MB/s",
            pump(&mut client, &mut peer, 256 * MIB)?
        );
    }
    Ok(())
}
