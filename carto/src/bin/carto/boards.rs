//! The two board ports: where each is, how it opens, and the link the loop waits on.

use std::os::fd::{AsFd, BorrowedFd};
use std::time::Duration as StdDuration;

use anyhow::{Context, Result};
use carto::backoff::Backoff;
use transport::{Link, SerialLink, TcpLink};

use crate::TransportKind;

/// One board port: where it is, and how often to try it again while it is down.
pub struct Board {
    pub which: &'static str,
    pub kind: TransportKind,
    pub port: String,
    pub baud: u32,
    pub backoff: Backoff,
    /// The current outage has been logged.
    pub down_logged: bool,
}

/// A board link the loop can wait on: a serial port (or the twin's pty) or a TCP connection.
pub enum BoardLink {
    Serial(SerialLink),
    Tcp(TcpLink),
}

impl Link for BoardLink {
    type Error = transport::Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, transport::Error> {
        match self {
            BoardLink::Serial(l) => l.read(buf),
            BoardLink::Tcp(l) => l.read(buf),
        }
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, transport::Error> {
        match self {
            BoardLink::Serial(l) => l.write(buf),
            BoardLink::Tcp(l) => l.write(buf),
        }
    }
}

impl AsFd for BoardLink {
    fn as_fd(&self) -> BorrowedFd<'_> {
        match self {
            BoardLink::Serial(l) => l.as_fd(),
            BoardLink::Tcp(l) => l.as_fd(),
        }
    }
}

impl Board {
    pub fn open(&self, connect_timeout: StdDuration) -> Result<BoardLink> {
        let (which, port, baud) = (self.which, self.port.as_str(), self.baud);
        Ok(match self.kind {
            TransportKind::Sim | TransportKind::Serial => BoardLink::Serial(
                SerialLink::builder(port, baud)
                    .open()
                    .with_context(|| format!("cannot open the {which} board port {port} ({baud} baud)"))?,
            ),
            TransportKind::Tcp => BoardLink::Tcp(
                TcpLink::connect_timeout(port, connect_timeout)
                    .with_context(|| format!("cannot connect to the {which} board at {port}"))?,
            ),
        })
    }
}
