//! The one transport trait: a non-blocking byte stream.
//!
//! A [`Link`] is what Carto's serial ports and Cute's socket look like to the logic: `read` returns
//! the bytes that have arrived (possibly none), `write` takes the bytes that fit now. Neither
//! waits. Waiting, timeouts and retries belong to the caller, who holds `now`.
//!
//! *NOTE*: `Ok(0)` from `read` means "nothing yet", not end of stream. A peer that has gone away is
//! reported as an error of kind [`ErrorKind::Disconnected`].

use core::fmt;
use std::io;

/// What went wrong on a link, coarse enough for callers to act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The peer closed the link or was unplugged; reads and writes will keep failing.
    ///
    /// *NOTE*: one link outlives its peers: a [`PtyLink`](crate::PtyLink) master reports this
    /// once per departed client, then waits (`Ok(0)`) for the next program to open the slave.
    Disconnected,
    /// The device or path could not be opened.
    NotFound,
    /// Opening the device was refused (permissions, already in use).
    PermissionDenied,
    /// A setting (baud rate, address) was rejected.
    InvalidInput,
    /// Any other I/O failure, with the operating system's kind.
    Io(io::ErrorKind),
}

/// The error type of every link in this crate: a kind plus a human-readable context.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    kind: ErrorKind,
    context: String,
}

impl Error {
    /// A new error of `kind`, with `context` saying what was being done (e.g. the port path).
    pub fn new(kind: ErrorKind, context: impl Into<String>) -> Self {
        Error { kind, context: context.into() }
    }

    /// The link was closed by the peer.
    pub fn disconnected(context: impl Into<String>) -> Self {
        Error::new(ErrorKind::Disconnected, context)
    }

    /// Wraps an OS error, mapping its kind.
    pub fn from_io(err: &io::Error, context: impl Into<String>) -> Self {
        let kind = match err.kind() {
            io::ErrorKind::NotFound => ErrorKind::NotFound,
            io::ErrorKind::PermissionDenied => ErrorKind::PermissionDenied,
            io::ErrorKind::InvalidInput => ErrorKind::InvalidInput,
            io::ErrorKind::BrokenPipe
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::UnexpectedEof
            | io::ErrorKind::NotConnected => ErrorKind::Disconnected,
            other => ErrorKind::Io(other),
        };
        Error { kind, context: format!("{}: {err}", context.into()) }
    }

    /// The same error as any [`LinkError`]: a clone when it already is an [`Error`], otherwise its
    /// kind and message.
    pub fn from_link_error<E: LinkError>(err: &E) -> Self {
        let any: &(dyn std::error::Error + 'static) = err;
        match any.downcast_ref::<Error>() {
            Some(e) => e.clone(),
            None => Error::new(err.kind(), err.to_string()),
        }
    }

    /// What kind of failure this is.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// What was being done when it failed (e.g. the port path and the OS message).
    pub fn context(&self) -> &str {
        &self.context
    }

    /// Whether the peer is gone (the session is over; see [`ErrorKind::Disconnected`]).
    pub fn is_disconnected(&self) -> bool {
        self.kind == ErrorKind::Disconnected
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = match self.kind {
            ErrorKind::Disconnected => "disconnected".to_string(),
            ErrorKind::NotFound => "not found".to_string(),
            ErrorKind::PermissionDenied => "permission denied".to_string(),
            ErrorKind::InvalidInput => "invalid input".to_string(),
            ErrorKind::Io(k) => format!("i/o error ({k:?})"),
        };
        write!(f, "{kind}: {}", self.context)
    }
}

impl std::error::Error for Error {}

/// Errors that a [`Link`] can return: anything that can say its [`ErrorKind`].
pub trait LinkError: std::error::Error + Send + Sync + 'static {
    /// The coarse kind of this error.
    fn kind(&self) -> ErrorKind;
}

impl LinkError for Error {
    fn kind(&self) -> ErrorKind {
        self.kind
    }
}

/// A non-blocking byte stream: a UART, a pseudo-terminal, a TCP socket, or an in-memory pipe.
pub trait Link {
    /// The error type of this link.
    type Error: LinkError;

    /// Copies up to `buf.len()` bytes that have already arrived into `buf`; `Ok(0)` = none yet.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;

    /// Queues as many bytes of `buf` as fit now and returns how many; the caller keeps the rest.
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error>;

    /// Appends every byte that has arrived to `out` and returns how many that was. On an error,
    /// the bytes read before it are already in `out` (nothing is lost). There is no cap: it reads
    /// until the link has nothing more, so a peer that writes faster than this drains keeps it
    /// in the loop (Carto's server, which faces unknown clients, reads a bounded number of chunks
    /// per step instead).
    fn read_available(&mut self, out: &mut Vec<u8>) -> Result<usize, Self::Error> {
        let mut chunk = [0u8; 512];
        let mut total = 0;
        loop {
            match self.read(&mut chunk)? {
                0 => return Ok(total),
                n => {
                    out.extend_from_slice(&chunk[..n]);
                    total += n;
                }
            }
        }
    }
}

impl<L: Link + ?Sized> Link for &mut L {
    type Error = L::Error;
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        L::read(self, buf)
    }
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        L::write(self, buf)
    }
    fn read_available(&mut self, out: &mut Vec<u8>) -> Result<usize, Self::Error> {
        L::read_available(self, out)
    }
}

impl<L: Link + ?Sized> Link for Box<L> {
    type Error = L::Error;
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        L::read(self, buf)
    }
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        L::write(self, buf)
    }
    fn read_available(&mut self, out: &mut Vec<u8>) -> Result<usize, Self::Error> {
        L::read_available(self, out)
    }
}

/// A link chosen at run time (the transport flag): any link whose errors are [`Error`].
pub type DynLink = Box<dyn Link<Error = Error> + Send>;

/// The server side of a connection-oriented link (Carto's TCP port): hands out newly connected
/// peers. Never blocks.
pub trait Listener {
    /// The link each accepted peer gets.
    type Link: Link;
    /// The error type of accepting.
    type Error: LinkError;

    /// A newly connected peer and a printable address if one is waiting, `Ok(None)` otherwise.
    fn accept(&mut self) -> Result<Option<(Self::Link, String)>, Self::Error>;

    /// Whether a peer is waiting to be accepted, without accepting it (it stays in the backlog).
    /// Implementations that cannot tell say `false`.
    fn has_pending(&mut self) -> bool {
        false
    }
}

/// The client side of a connection-oriented link (Cute's socket): opens a new link on demand, so
/// a client can reconnect after a disconnect.
pub trait Connector {
    /// The link a successful connection gives.
    type Link: Link;
    /// The error type of connecting.
    type Error: LinkError;

    /// Tries once to connect. Failure is an error (e.g. [`ErrorKind::Disconnected`] when nobody
    /// listens); the caller decides when to try again.
    fn connect(&mut self) -> Result<Self::Link, Self::Error>;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hands out `chunks` one `read` at a time, then fails if `then_fail`, else reports nothing.
    struct Scripted {
        chunks: Vec<Vec<u8>>,
        then_fail: bool,
    }

    impl Link for Scripted {
        type Error = Error;
        fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
            if self.chunks.is_empty() {
                return if self.then_fail { Err(Error::disconnected("peer gone")) } else { Ok(0) };
            }
            let chunk = self.chunks.remove(0);
            buf[..chunk.len()].copy_from_slice(&chunk);
            Ok(chunk.len())
        }
        fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
            Ok(buf.len())
        }
    }

    #[test]
    fn read_available_appends_every_chunk_until_nothing_is_left() {
        let mut link = Scripted { chunks: vec![vec![1, 2], vec![3; 512], vec![4]], then_fail: false };
        let mut out = vec![0];
        assert_eq!(link.read_available(&mut out).unwrap(), 515);
        assert_eq!(out.len(), 516);
        assert_eq!((out[0], out[1], out[3], out[515]), (0, 1, 3, 4));
        assert_eq!(link.read_available(&mut out).unwrap(), 0);
    }

    #[test]
    fn read_available_keeps_the_bytes_read_before_an_error() {
        let mut link = Scripted { chunks: vec![vec![7, 8, 9]], then_fail: true };
        let mut out = Vec::new();
        let err = link.read_available(&mut out).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Disconnected);
        assert_eq!(out, [7, 8, 9]);
    }
}
