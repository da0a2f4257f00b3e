//! TCP links: Cute ⇄ Carto over the network (port 12345), or a board twin served over TCP.
//!
//! Every socket is non-blocking with `TCP_NODELAY` (frames are small and latency matters more
//! than packet count). [`TcpLink::connect`] and [`TcpConnector`] wait at most a short connect
//! timeout (default [`DEFAULT_CONNECT_TIMEOUT`]); [`TcpListenerLink::accept`] never waits.
//! [`TcpListenerLink::set_keepalive`] makes every accepted socket probe a silent peer
//! ([`KeepAlive`]: TCP keepalive plus `TCP_USER_TIMEOUT` on Linux), so a peer that vanished
//! without closing (unplugged, powered off) ends up `Disconnected` within a bounded time.
//!
//! Invariants:
//! - `read` returns `Ok(0)` when nothing has arrived; the peer closing (end of stream) or
//!   resetting the connection is `Disconnected`, after every byte it sent has been read, and the
//!   link stays disconnected.
//! - A connect that finds nobody listening (refused, or timed out) is `Disconnected`.
//!
//! ```
//! use transport::{Link, Listener, TcpLink, TcpListenerLink};
//! let mut server = TcpListenerLink::bind("127.0.0.1:0")?;
//! let mut cute = TcpLink::connect(server.local_addr())?;
//! let mut carto = loop {
//!     if let Some((link, _peer)) = server.accept()? { break link; }
//!     std::thread::sleep(std::time::Duration::from_millis(1));
//! };
//! cute.write(b"hi")?;
//! let mut buf = [0u8; 2];
//! while carto.read(&mut buf)? == 0 { std::thread::sleep(std::time::Duration::from_millis(1)); }
//! assert_eq!(&buf, b"hi");
//! # Ok::<(), transport::Error>(())
//! ```

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::time::Duration;

use crate::link::{Connector, Error, ErrorKind, Link, Listener};

/// How long a connect waits for the peer before giving up.
pub const DEFAULT_CONNECT_TIMEOUT: Duration = Duration::from_millis(500);

/// How a socket notices a peer that vanished without closing: after `idle` without traffic the
/// kernel sends up to `retries` keepalive probes `interval` apart; unanswered, the connection
/// fails (`Disconnected` on the next read). Unacknowledged outgoing data fails it after
/// [`KeepAlive::dead_after`] too (`TCP_USER_TIMEOUT`, Linux only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeepAlive {
    /// Silence before the first probe.
    pub idle: Duration,
    /// Time between probes.
    pub interval: Duration,
    /// Unanswered probes before the connection fails.
    pub retries: u32,
}

impl KeepAlive {
    /// Settings that declare a silent, unresponsive peer dead after about `limit`: a third of it
    /// idle, then 5 probes over the remaining two thirds (at least 1 s each).
    pub fn within(limit: Duration) -> KeepAlive {
        let secs = limit.as_secs().max(3);
        let idle = Duration::from_secs((secs / 3).max(1));
        let interval = Duration::from_secs(((secs - secs / 3) / 5).max(1));
        KeepAlive { idle, interval, retries: 5 }
    }

    /// Silence after which the peer is declared dead: `idle + retries × interval`.
    pub fn dead_after(&self) -> Duration {
        self.idle + self.interval * self.retries
    }
}

/// A connected, non-blocking TCP byte stream.
#[derive(Debug)]
pub struct TcpLink {
    stream: TcpStream,
    peer: String,
    closed: bool,
}

impl TcpLink {
    /// Connects to `addr` (e.g. `"127.0.0.1:12345"`), waiting at most the default timeout.
    pub fn connect(addr: impl ToSocketAddrs) -> Result<TcpLink, Error> {
        Self::connect_timeout(addr, DEFAULT_CONNECT_TIMEOUT)
    }

    /// Connects to `addr`, trying each address it resolves to for at most `timeout`.
    pub fn connect_timeout(addr: impl ToSocketAddrs, timeout: Duration) -> Result<TcpLink, Error> {
        let addrs: Vec<SocketAddr> =
            addr.to_socket_addrs().map_err(|e| Error::from_io(&e, "tcp: resolving the address"))?.collect();
        let mut last = Error::new(ErrorKind::InvalidInput, "tcp: the address resolved to nothing");
        for a in addrs {
            match TcpStream::connect_timeout(&a, timeout) {
                Ok(stream) => return Self::from_stream(stream),
                Err(e) => last = connect_error(&e, a),
            }
        }
        Err(last)
    }

    /// Wraps a connected stream: makes it non-blocking and sets `TCP_NODELAY`.
    pub fn from_stream(stream: TcpStream) -> Result<TcpLink, Error> {
        let peer = stream.peer_addr().map_or_else(|_| "?".to_string(), |a| a.to_string());
        let ctx = || format!("tcp {peer}: configuring the socket");
        stream.set_nonblocking(true).map_err(|e| Error::from_io(&e, ctx()))?;
        stream.set_nodelay(true).map_err(|e| Error::from_io(&e, ctx()))?;
        Ok(TcpLink { stream, peer, closed: false })
    }

    /// Turns on TCP keepalive (and, on Linux, `TCP_USER_TIMEOUT`) with `settings`.
    pub fn set_keepalive(&self, settings: &KeepAlive) -> Result<(), Error> {
        let sock = socket2::SockRef::from(&self.stream);
        let ctx = || format!("tcp {}: setting keepalive", self.peer);
        let params = socket2::TcpKeepalive::new().with_time(settings.idle);
        #[cfg(any(
            target_os = "linux",
            target_os = "android",
            target_vendor = "apple",
            target_os = "freebsd"
        ))]
        let params = params.with_interval(settings.interval).with_retries(settings.retries);
        sock.set_tcp_keepalive(&params).map_err(|e| Error::from_io(&e, ctx()))?;
        #[cfg(any(target_os = "linux", target_os = "android"))]
        sock.set_tcp_user_timeout(Some(settings.dead_after())).map_err(|e| Error::from_io(&e, ctx()))?;
        Ok(())
    }

    /// The peer's address, as text.
    pub fn peer_addr(&self) -> &str {
        &self.peer
    }

    fn fail(&mut self, err: &io::Error, what: &str) -> Error {
        let err = Error::from_io(err, format!("tcp {}: {what}", self.peer));
        if err.is_disconnected() {
            self.closed = true;
        }
        err
    }
}

fn connect_error(err: &io::Error, addr: SocketAddr) -> Error {
    let ctx = format!("tcp: connecting to {addr} (nobody listening?)");
    match err.kind() {
        io::ErrorKind::ConnectionRefused | io::ErrorKind::TimedOut => {
            Error::disconnected(format!("{ctx}: {err}"))
        }
        _ => Error::from_io(err, ctx),
    }
}

impl Link for TcpLink {
    type Error = Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        if self.closed {
            return Err(Error::disconnected(format!("tcp {}: connection closed", self.peer)));
        }
        if buf.is_empty() {
            return Ok(0);
        }
        match self.stream.read(buf) {
            Ok(0) => {
                self.closed = true;
                Err(Error::disconnected(format!("tcp {}: the peer closed the connection", self.peer)))
            }
            Ok(n) => Ok(n),
            Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted) => Ok(0),
            Err(e) => Err(self.fail(&e, "read")),
        }
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        if self.closed {
            return Err(Error::disconnected(format!("tcp {}: connection closed", self.peer)));
        }
        if buf.is_empty() {
            return Ok(0);
        }
        match self.stream.write(buf) {
            Ok(n) => Ok(n),
            Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted) => Ok(0),
            Err(e) => Err(self.fail(&e, "write")),
        }
    }
}

/// Opens a new [`TcpLink`] to a fixed address on each `connect` (Cute reconnecting to Carto).
#[derive(Debug, Clone)]
pub struct TcpConnector {
    addr: String,
    timeout: Duration,
}

impl TcpConnector {
    /// A connector for `addr` (`"host:port"`), with the default connect timeout.
    pub fn new(addr: impl Into<String>) -> Self {
        TcpConnector { addr: addr.into(), timeout: DEFAULT_CONNECT_TIMEOUT }
    }

    /// The same connector with another connect timeout.
    pub fn timeout(mut self, timeout: Duration) -> Self {
        self.timeout = timeout;
        self
    }

    /// The address it connects to.
    pub fn addr(&self) -> &str {
        &self.addr
    }
}

impl Connector for TcpConnector {
    type Link = TcpLink;
    type Error = Error;

    fn connect(&mut self) -> Result<TcpLink, Error> {
        TcpLink::connect_timeout(self.addr.as_str(), self.timeout)
    }
}

/// A non-blocking TCP server socket handing out [`TcpLink`]s (Carto's port 12345).
#[derive(Debug)]
pub struct TcpListenerLink {
    listener: TcpListener,
    local: SocketAddr,
    keepalive: Option<KeepAlive>,
}

impl TcpListenerLink {
    /// Listens on `addr` (`"0.0.0.0:12345"`; port 0 picks a free port, see `local_addr`).
    pub fn bind(addr: impl ToSocketAddrs) -> Result<TcpListenerLink, Error> {
        let listener = TcpListener::bind(addr).map_err(|e| Error::from_io(&e, "tcp: binding"))?;
        let local = listener.local_addr().map_err(|e| Error::from_io(&e, "tcp: local address"))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| Error::from_io(&e, format!("tcp {local}: non-blocking")))?;
        Ok(TcpListenerLink { listener, local, keepalive: None })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// Keepalive settings for every socket accepted from now on (`None`: the system's, i.e. off).
    pub fn set_keepalive(&mut self, keepalive: Option<KeepAlive>) {
        self.keepalive = keepalive;
    }
}

/// The socket, for a caller that waits on it with `poll` (readable: a client to accept).
#[cfg(unix)]
impl std::os::fd::AsFd for TcpListenerLink {
    fn as_fd(&self) -> std::os::fd::BorrowedFd<'_> {
        std::os::fd::AsFd::as_fd(&self.listener)
    }
}

/// The socket, for a caller that waits on it with `poll`.
#[cfg(unix)]
impl std::os::fd::AsFd for TcpLink {
    fn as_fd(&self) -> std::os::fd::BorrowedFd<'_> {
        std::os::fd::AsFd::as_fd(&self.stream)
    }
}

impl Listener for TcpListenerLink {
    type Link = TcpLink;
    type Error = Error;

    fn accept(&mut self) -> Result<Option<(TcpLink, String)>, Error> {
        match self.listener.accept() {
            Ok((stream, peer)) => {
                let link = TcpLink::from_stream(stream)?;
                if let Some(k) = &self.keepalive {
                    link.set_keepalive(k)?;
                }
                Ok(Some((link, peer.to_string())))
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted | io::ErrorKind::ConnectionAborted
                ) =>
            {
                Ok(None)
            }
            Err(e) => Err(Error::from_io(&e, format!("tcp {}: accept", self.local))),
        }
    }

    #[cfg(unix)]
    fn has_pending(&mut self) -> bool {
        use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
        use std::os::fd::AsFd;
        let mut fds = [PollFd::new(self.listener.as_fd(), PollFlags::POLLIN)];
        matches!(poll(&mut fds, PollTimeout::ZERO), Ok(n) if n > 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn connect_with_nobody_listening_is_disconnected() {
        let port = TcpListenerLink::bind("127.0.0.1:0").unwrap().local_addr().port();
        let mut connector = TcpConnector::new(format!("127.0.0.1:{port}"));
        let err = connector.connect().unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Disconnected);
        assert!(err.to_string().contains(&port.to_string()), "{err}");
    }

    #[test]
    fn keepalive_within_15_s() {
        let k = KeepAlive::within(Duration::from_secs(15));
        assert_eq!((k.idle, k.interval, k.retries), (Duration::from_secs(5), Duration::from_secs(2), 5));
        assert_eq!(k.dead_after(), Duration::from_secs(15));
    }

    #[test]
    fn issue_14_accepted_sockets_get_keepalive_and_pending_peers_wait() {
        let mut server = TcpListenerLink::bind("127.0.0.1:0").unwrap();
        server.set_keepalive(Some(KeepAlive::within(Duration::from_secs(15))));
        assert!(!server.has_pending());
        let _client = TcpLink::connect(server.local_addr()).unwrap();
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        while !server.has_pending() {
            assert!(std::time::Instant::now() < deadline, "the connection never showed as pending");
            std::thread::sleep(Duration::from_millis(1));
        }
        let (link, _) = server.accept().unwrap().unwrap();
        let sock = socket2::SockRef::from(&link.stream);
        assert!(sock.keepalive().unwrap());
        assert_eq!(sock.tcp_keepalive_time().unwrap(), Duration::from_secs(5));
        #[cfg(target_os = "linux")]
        assert_eq!(sock.tcp_user_timeout().unwrap(), Some(Duration::from_secs(15)));
        assert!(!server.has_pending());
    }

    #[test]
    fn accept_with_nobody_connecting_is_none() {
        let mut server = TcpListenerLink::bind("127.0.0.1:0").unwrap();
        assert!(server.accept().unwrap().is_none());
    }

    #[test]
    fn connector_reconnects_after_disconnect() {
        let mut server = TcpListenerLink::bind("127.0.0.1:0").unwrap();
        let mut connector = TcpConnector::new(server.local_addr().to_string());
        for _ in 0..2 {
            let client = connector.connect().unwrap();
            let deadline = std::time::Instant::now() + Duration::from_secs(2);
            let mut accepted = None;
            while accepted.is_none() && std::time::Instant::now() < deadline {
                accepted = server.accept().unwrap();
                std::thread::sleep(Duration::from_millis(1));
            }
            let (_, peer) = accepted.unwrap();
            assert_eq!(peer, client.stream.local_addr().unwrap().to_string());
        }
    }
}
