//! A real serial port (or a pty slave) as a [`Link`]: Carto's `/dev/ttyAMA0` at 115200 baud to
//! the motor board and `/dev/ttyUSB0` at 9600 baud to the sensor board.
//!
//! [`SerialLink::builder`] mirrors `serialport::new(path, baud)`. The port is always 8N1, no flow
//! control, raw; `serialport` applies those settings (including non-standard baud rates and the
//! exclusive lock), and the bytes go through a second, non-blocking handle on the same device:
//! `serialport`'s own read and write wait up to a timeout, and it offers no way to make its handle
//! non-blocking without `unsafe`, which this workspace denies.
//!
//! Invariants:
//! - `read` returns the bytes already received (`Ok(0)` if none) and `write` what fits in the
//!   driver's output buffer now; neither waits.
//! - A device that goes away (USB adapter unplugged, pty master closed) is `Disconnected`, with the
//!   path in the message; so is everything after. Bytes still in the driver are lost.
//! - Input already waiting when the port is opened is dropped (see
//!   [`SerialLinkBuilder::clear_on_open`]), so a restarted program does not parse stale bytes.
//!
//! *NOTE*: ports are opened exclusive (`TIOCEXCL` plus `flock`) except pty slaves (`/dev/pts/*`,
//! also through a symlink such as `run/tty-motor`). A real UART forgets `TIOCEXCL` when its last
//! handle closes, but a pty slave keeps it while the master lives: after a client that set it dies
//! without clearing it (Ctrl-C, crash), every non-root open fails with `EBUSY` (measured on Linux
//! 6.x). Carto restarting against a running twin must not be locked out, so on a pty only a shared
//! `flock` is taken. [`SerialLinkBuilder::exclusive`] overrides the choice.
//!
//! ```no_run
//! use transport::{Link, SerialLink};
//! let mut motor = SerialLink::builder("/dev/ttyAMA0", 115_200).open()?;
//! motor.write(&[0xAA, 0x01])?;
//! # Ok::<(), transport::Error>(())
//! ```

use std::fs::File;
use std::path::Path;
use std::time::Duration;

use serialport::{ClearBuffer, DataBits, FlowControl, Parity, SerialPort, StopBits, TTYPort};

use crate::link::{Error, ErrorKind, Link};
use crate::tty;

/// Settings for opening a [`SerialLink`], like `serialport::SerialPortBuilder`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SerialLinkBuilder {
    path: String,
    baud: u32,
    exclusive: Option<bool>,
    clear_on_open: bool,
}

impl SerialLinkBuilder {
    /// Whether to lock the port against other openers. Default: yes, except on a pty slave
    /// (`/dev/pts/*`), where the kernel keeps the lock after its opener dies (see the module docs).
    pub fn exclusive(mut self, exclusive: bool) -> Self {
        self.exclusive = Some(exclusive);
        self
    }

    /// Whether to drop input already waiting at open time (default `true`).
    pub fn clear_on_open(mut self, clear: bool) -> Self {
        self.clear_on_open = clear;
        self
    }

    /// The device path.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Opens the port: 8N1, no flow control, raw, non-blocking.
    pub fn open(self) -> Result<SerialLink, Error> {
        let what = format!("serial port {}", self.path);
        // The non-blocking handle first: a modem port without CLOCAL would make a blocking open
        // wait for carrier, and once `serialport` sets the exclusive lock no second open works.
        let file = tty::open_nonblocking(Path::new(&self.path)).map_err(|e| {
            if e.raw_os_error() == Some(nix::errno::Errno::EBUSY as i32) {
                return Error::new(
                    ErrorKind::PermissionDenied,
                    format!("{what}: {e} (in use by another program?)"),
                );
            }
            let err = Error::from_io(&e, &what);
            match err.kind() {
                ErrorKind::NotFound => {
                    Error::new(ErrorKind::NotFound, format!("{} (is the device plugged in?)", err.context()))
                }
                _ => err,
            }
        })?;
        let exclusive = self.exclusive.unwrap_or_else(|| !is_pty_slave(Path::new(&self.path)));
        let port = serialport::new(self.path.as_str(), self.baud)
            .data_bits(DataBits::Eight)
            .parity(Parity::None)
            .stop_bits(StopBits::One)
            .flow_control(FlowControl::None)
            .timeout(Duration::ZERO)
            .exclusive(exclusive)
            .open_native()
            .map_err(|e| map_serial_error(&e, &what))?;
        if self.clear_on_open {
            port.clear(ClearBuffer::Input).map_err(|e| map_serial_error(&e, &what))?;
        }
        Ok(SerialLink { file, _port: port, path: self.path, baud: self.baud, what })
    }
}

/// Whether `path` (after following symlinks) is a Unix 98 pty slave.
fn is_pty_slave(path: &Path) -> bool {
    std::fs::canonicalize(path).is_ok_and(|p| p.starts_with("/dev/pts"))
}

/// Maps a `serialport` error to ours, naming the port.
fn map_serial_error(err: &serialport::Error, what: &str) -> Error {
    let msg = format!("{what}: {}", err.description);
    match err.kind {
        serialport::ErrorKind::NoDevice => {
            Error::new(ErrorKind::PermissionDenied, format!("{msg} (in use by another program?)"))
        }
        serialport::ErrorKind::InvalidInput => Error::new(ErrorKind::InvalidInput, msg),
        serialport::ErrorKind::Io(kind) => Error::from_io(&std::io::Error::new(kind, msg), what),
        serialport::ErrorKind::Unknown => Error::new(ErrorKind::Io(std::io::ErrorKind::Other), msg),
    }
}

/// An open serial port (see the [module docs](self)).
#[derive(Debug)]
pub struct SerialLink {
    file: File,
    /// Holds the settings and the exclusive lock for as long as the link lives.
    _port: TTYPort,
    path: String,
    baud: u32,
    what: String,
}

impl SerialLink {
    /// Settings for the port at `path` running at `baud` (8N1, no flow control).
    pub fn builder(path: impl Into<String>, baud: u32) -> SerialLinkBuilder {
        SerialLinkBuilder { path: path.into(), baud, exclusive: None, clear_on_open: true }
    }

    /// The device path it was opened with.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The baud rate it was opened with.
    pub fn baud(&self) -> u32 {
        self.baud
    }
}

/// The device, for a caller that waits on it with `poll`.
impl std::os::fd::AsFd for SerialLink {
    fn as_fd(&self) -> std::os::fd::BorrowedFd<'_> {
        std::os::fd::AsFd::as_fd(&self.file)
    }
}

impl Link for SerialLink {
    type Error = Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        tty::read(&mut self.file, buf, &self.what)
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        tty::write(&mut self.file, buf, &self.what)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pty::PtyLink;

    #[test]
    fn missing_port_is_not_found_with_the_path() {
        let err = SerialLink::builder("/dev/ttyUSB-explobot-missing", 9600).open().unwrap_err();
        assert_eq!(err.kind(), ErrorKind::NotFound);
        let msg = err.to_string();
        assert!(msg.contains("/dev/ttyUSB-explobot-missing"), "{msg}");
        assert!(msg.contains("plugged in"), "{msg}");
    }

    #[test]
    fn opens_a_pty_at_9600_and_reports_unplug_with_the_path() {
        let mut board = PtyLink::open().unwrap();
        let path = board.slave_path().display().to_string();
        let mut port = SerialLink::builder(path.clone(), 9600).open().unwrap();
        assert_eq!((port.path(), port.baud()), (path.as_str(), 9600));
        assert_eq!(port.read(&mut [0u8; 8]).unwrap(), 0);
        assert_eq!(board.read(&mut [0u8; 8]).unwrap(), 0);
        assert!(board.client_attached());
        drop(board);
        let err = port.read(&mut [0u8; 8]).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Disconnected);
        assert!(err.to_string().contains(&path), "{err}");
        assert!(port.write(b"x").unwrap_err().is_disconnected());
    }

    #[test]
    fn pty_slaves_are_recognised_through_symlinks() {
        let link = std::env::temp_dir().join(format!("explobot-transport-{}-tty-sensor", std::process::id()));
        let pty = PtyLink::open_with_symlink(&link).unwrap();
        assert!(is_pty_slave(pty.slave_path()));
        assert!(is_pty_slave(&link));
        assert!(!is_pty_slave(Path::new("/dev/null")));
        assert!(!is_pty_slave(Path::new("/dev/ttyUSB-explobot-missing")));
    }

    #[test]
    fn a_second_opener_of_a_pty_is_not_refused() {
        // Non-exclusive on a pty: a restarted client can open the port again.
        let board = PtyLink::open().unwrap();
        let path = board.slave_path().display().to_string();
        let first = SerialLink::builder(path.clone(), 115_200).open().unwrap();
        let second = SerialLink::builder(path, 115_200).open();
        assert!(second.is_ok(), "{second:?}");
        drop(first);
    }

    #[test]
    fn exclusive_port_refuses_a_second_opener_naming_the_path() {
        let board = PtyLink::open().unwrap();
        let path = board.slave_path().display().to_string();
        let _first = SerialLink::builder(path.clone(), 115_200).exclusive(true).open().unwrap();
        let err = SerialLink::builder(path.clone(), 115_200).open().unwrap_err();
        assert_eq!(err.kind(), ErrorKind::PermissionDenied, "{err}");
        assert!(err.to_string().contains(&path), "{err}");
    }

    #[test]
    fn not_a_tty_is_an_error_not_a_panic() {
        let err = SerialLink::builder("/dev/null", 9600).open().unwrap_err();
        assert!(err.to_string().contains("/dev/null"), "{err}");
    }
}
