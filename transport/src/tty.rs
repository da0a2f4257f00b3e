//! Terminal-device plumbing shared by [`PtyClient`](crate::PtyClient) and
//! [`SerialLink`](crate::SerialLink): non-blocking open by path, raw mode, and the read/write
//! error mapping (`EAGAIN` → `Ok(0)`, hang-up or `EIO` → `Disconnected`).

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Write};
use std::os::fd::AsFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;

use nix::errno::Errno;
use nix::fcntl::OFlag;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};
use nix::sys::termios::{self, SetArg};

use crate::link::Error;

/// Opens a terminal device read-write, without making it our controlling terminal, and
/// non-blocking (so neither the open nor any later read or write waits).
pub(crate) fn open_nonblocking(path: &Path) -> io::Result<File> {
    OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags((OFlag::O_NOCTTY | OFlag::O_NONBLOCK).bits())
        .open(path)
}

/// Puts the terminal behind `fd` in raw mode: no echo, no line editing, no CR/LF translation,
/// 8-bit characters.
pub(crate) fn make_raw(fd: impl AsFd) -> nix::Result<()> {
    let mut attrs = termios::tcgetattr(fd.as_fd())?;
    termios::cfmakeraw(&mut attrs);
    termios::tcsetattr(fd.as_fd(), SetArg::TCSANOW, &attrs)
}

/// Whether `fd` reports a hang-up (or an error) right now. Never waits.
pub(crate) fn hung_up(fd: impl AsFd) -> bool {
    let mut fds = [PollFd::new(fd.as_fd(), PollFlags::POLLOUT)];
    match poll(&mut fds, PollTimeout::ZERO) {
        Ok(_) => fds[0].revents().is_some_and(|r| r.intersects(PollFlags::POLLHUP | PollFlags::POLLERR)),
        Err(_) => false,
    }
}

/// Whether an OS error means the other side of a terminal is gone.
pub(crate) fn is_hangup_error(err: &io::Error) -> bool {
    err.raw_os_error() == Some(Errno::EIO as i32)
        || matches!(err.kind(), io::ErrorKind::BrokenPipe | io::ErrorKind::UnexpectedEof)
}

/// A non-blocking read from a terminal device: `Ok(0)` when nothing is waiting, `Disconnected`
/// when the device hung up (pty master closed, USB adapter unplugged).
pub(crate) fn read(file: &mut File, buf: &mut [u8], what: &str) -> Result<usize, Error> {
    if buf.is_empty() {
        return Ok(0);
    }
    match file.read(buf) {
        Ok(0) if hung_up(&*file) => {
            Err(Error::disconnected(format!("{what}: hung up (device unplugged or closed)")))
        }
        Ok(n) => Ok(n),
        Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted) => Ok(0),
        Err(e) if is_hangup_error(&e) => {
            Err(Error::disconnected(format!("{what}: hung up (device unplugged or closed): {e}")))
        }
        Err(e) => Err(Error::from_io(&e, what)),
    }
}

/// A non-blocking write to a terminal device: takes what fits, `Ok(0)` when the output buffer is
/// full, `Disconnected` when the device hung up.
pub(crate) fn write(file: &mut File, buf: &[u8], what: &str) -> Result<usize, Error> {
    if buf.is_empty() {
        return Ok(0);
    }
    match file.write(buf) {
        Ok(n) => Ok(n),
        Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::Interrupted) => Ok(0),
        Err(e) if is_hangup_error(&e) => {
            Err(Error::disconnected(format!("{what}: hung up (device unplugged or closed): {e}")))
        }
        Err(e) => Err(Error::from_io(&e, what)),
    }
}
