//! TCP links: Cute ⇄ Carto over the network (port 12345), or a board twin served over TCP.
//!
//! Every socket is non-blocking with `TCP_NODELAY` (frames are small and latency matters more
//! than packet count). [`TcpLink::connect`] and [`TcpConnector`] wait at most a short connect
//! timeout (default [`DEFAULT_CONNECT_TIMEOUT`]); [`TcpListenerLink::accept`] never waits.
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
}

impl TcpListenerLink {
    /// Listens on `addr` (`"0.0.0.0:12345"`; port 0 picks a free port, see `local_addr`).
    pub fn bind(addr: impl ToSocketAddrs) -> Result<TcpListenerLink, Error> {
        let listener = TcpListener::bind(addr).map_err(|e| Error::from_io(&e, "tcp: binding"))?;
        let local = listener.local_addr().map_err(|e| Error::from_io(&e, "tcp: local address"))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| Error::from_io(&e, format!("tcp {local}: non-blocking")))?;
        Ok(TcpListenerLink { listener, local })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }
}

impl Listener for TcpListenerLink {
    type Link = TcpLink;
    type Error = Error;

    fn accept(&mut self) -> Result<Option<(TcpLink, String)>, Error> {
        match self.listener.accept() {
            Ok((stream, peer)) => Ok(Some((TcpLink::from_stream(stream)?, peer.to_string()))),
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
