//! Pseudo-terminals: the twin's side of a serial port that another program opens by path.
//!
//! [`PtyLink`] owns a pty *master*. Its *slave* (`/dev/pts/N`, optionally behind a stable symlink
//! such as `run/tty-motor`) is what a program like Carto opens exactly as it would open
//! `/dev/ttyUSB0` — with [`SerialLink`](crate::SerialLink), `serialport`, `screen`, Python's
//! `serial.Serial`, … Baud settings on a pty are accepted and ignored; the twin models byte time
//! itself. The slave is put in raw mode (no echo, no line editing) when the pty is made, and the
//! setting survives clients coming and going.
//!
//! Built on nix's `posix_openpt` rather than `serialport::TTYPort::pair`: `pair` keeps a slave
//! handle open in our own process, and while any slave handle is open the master never learns
//! that the client left.
//!
//! # Clients come and go
//!
//! The master cannot tell "no client yet" from "client left" by itself, so the link keeps a
//! small state machine, driven by what the kernel reports (measured on Linux 6.x):
//!
//! | kernel says                              | meaning                  | `read` returns            |
//! |------------------------------------------|--------------------------|---------------------------|
//! | `EAGAIN`                                 | a client has the slave open, nothing sent | `Ok(0)`  |
//! | data                                     | bytes from the client (also the last ones after it closed) | `Ok(n)` |
//! | `EIO` (every slave handle closed), first time after a client | the client left | `Err(Disconnected)` once |
//! | `EIO` again, or before any client        | nobody attached          | `Ok(0)`                   |
//!
//! So a [`PtyLink`] outlives its clients: `Disconnected` is reported *once per departed client*
//! (after its last bytes have been read), then the link waits for the next program to open the
//! slave path. This is the one exception to "a disconnected link stays dead"; callers that reset
//! session state on `Disconnected` simply keep polling.
//!
//! While nobody is attached, `write` succeeds and discards the bytes (counted in
//! [`PtyLink::discarded_bytes`]), like a UART transmitting into an unplugged cable. A bare pty
//! would instead keep them and hand them to the *next* client as stale data; to close the
//! remaining race (a client leaving between our check and our write) the slave's input queue is
//! also flushed when a departure is noticed. A new client therefore only sees bytes written
//! after it attached.
//!
//! The pty is made with one open-and-close of the slave (to set raw mode), which also puts the
//! master in the same "nobody attached" state a departed client leaves.
//!
//! ```
//! use transport::{Link, PtyClient, PtyLink};
//! let mut board = PtyLink::open()?;
//! // Another program would open this path; here we do it ourselves.
//! let mut carto = PtyClient::open(board.slave_path())?;
//! carto.write(b"ping")?;
//! let mut buf = [0u8; 8];
//! let mut n = 0;
//! for _ in 0..1000 {
//!     n = board.read(&mut buf)?;
//!     if n > 0 { break; }
//!     std::thread::sleep(std::time::Duration::from_millis(1));
//! }
//! assert_eq!(&buf[..n], b"ping");
//! drop(carto);
//! let gone = (0..1000).find_map(|_| {
//!     std::thread::sleep(std::time::Duration::from_millis(1));
//!     board.read(&mut buf).err()
//! });
//! assert!(gone.is_some_and(|e| e.is_disconnected()));
//! # Ok::<(), transport::Error>(())
//! ```

use std::fs::File;
use std::io;
use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};

use nix::errno::Errno;
use nix::fcntl::{FcntlArg, FdFlag, OFlag, fcntl};
use nix::pty::{PtyMaster, grantpt, posix_openpt, ptsname_r, unlockpt};
use nix::sys::termios::{FlushArg, tcflush};

use crate::link::{Error, ErrorKind, Link};
use crate::tty;

/// Whether a client has the slave open, as last observed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Client {
    Waiting,
    Attached,
}

/// The twin's side of a pseudo-terminal (see the [module docs](self)).
#[derive(Debug)]
pub struct PtyLink {
    master: PtyMaster,
    slave_path: PathBuf,
    symlink: Option<PathBuf>,
    client: Client,
    departure_unreported: bool,
    sessions: u64,
    discarded: u64,
}

fn errno_error(err: Errno, context: &str) -> Error {
    Error::from_io(&io::Error::from(err), context)
}

impl PtyLink {
    /// A new pty with nobody attached; the slave path is [`PtyLink::slave_path`].
    pub fn open() -> Result<PtyLink, Error> {
        Self::open_inner(None)
    }

    /// A new pty whose slave is also reachable through a symlink at `link` (e.g.
    /// `run/tty-motor`), made with its parent folders; an existing symlink there is replaced, any
    /// other existing file is an error. The symlink is removed when the link is dropped.
    pub fn open_with_symlink(link: impl AsRef<Path>) -> Result<PtyLink, Error> {
        Self::open_inner(Some(link.as_ref()))
    }

    /// A new pty and a client already attached to its slave (opened by path, raw, non-blocking).
    pub fn pair() -> Result<(PtyLink, PtyClient), Error> {
        let mut master = Self::open()?;
        let client = PtyClient::open(&master.slave_path)?;
        master.attach();
        Ok((master, client))
    }

    fn open_inner(link: Option<&Path>) -> Result<PtyLink, Error> {
        let ctx = "pty: creating a pseudo-terminal";
        let master = posix_openpt(OFlag::O_RDWR | OFlag::O_NOCTTY).map_err(|e| errno_error(e, ctx))?;
        grantpt(&master).map_err(|e| errno_error(e, ctx))?;
        unlockpt(&master).map_err(|e| errno_error(e, ctx))?;
        fcntl(&master, FcntlArg::F_SETFL(OFlag::O_NONBLOCK)).map_err(|e| errno_error(e, ctx))?;
        fcntl(&master, FcntlArg::F_SETFD(FdFlag::FD_CLOEXEC)).map_err(|e| errno_error(e, ctx))?;
        let slave_path = PathBuf::from(ptsname_r(&master).map_err(|e| errno_error(e, ctx))?);

        // Open the slave once to put it in raw mode; closing it leaves the master in the same
        // "nobody attached" (hang-up) state a departed client leaves.
        {
            let slave = tty::open_nonblocking(&slave_path)
                .map_err(|e| Error::from_io(&e, format!("pty: opening {}", slave_path.display())))?;
            tty::make_raw(&slave)
                .map_err(|e| errno_error(e, &format!("pty: raw mode on {}", slave_path.display())))?;
        }

        let mut pty = PtyLink {
            master,
            slave_path,
            symlink: None,
            client: Client::Waiting,
            departure_unreported: false,
            sessions: 0,
            discarded: 0,
        };
        if let Some(link) = link {
            pty.make_symlink(link)?;
        }
        Ok(pty)
    }

    fn make_symlink(&mut self, link: &Path) -> Result<(), Error> {
        let ctx = || format!("pty: symlink {} -> {}", link.display(), self.slave_path.display());
        if let Some(parent) = link.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|e| Error::from_io(&e, ctx()))?;
        }
        match std::fs::symlink_metadata(link) {
            Ok(meta) if meta.file_type().is_symlink() => {
                std::fs::remove_file(link).map_err(|e| Error::from_io(&e, ctx()))?;
            }
            Ok(_) => {
                return Err(Error::new(
                    ErrorKind::InvalidInput,
                    format!("{}: exists and is not a symlink, refusing to replace it", ctx()),
                ));
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(Error::from_io(&e, ctx())),
        }
        symlink(&self.slave_path, link).map_err(|e| Error::from_io(&e, ctx()))?;
        self.symlink = Some(link.to_path_buf());
        Ok(())
    }

    /// The slave device another program opens, e.g. `/dev/pts/3`.
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// The stable symlink to the slave, if one was made.
    pub fn symlink_path(&self) -> Option<&Path> {
        self.symlink.as_deref()
    }

    /// Whether a client was attached when the link last looked (at the last read or write).
    pub fn client_attached(&self) -> bool {
        self.client == Client::Attached
    }

    /// How many clients have attached so far.
    pub fn sessions(&self) -> u64 {
        self.sessions
    }

    /// Bytes written while nobody was attached, and therefore thrown away.
    pub fn discarded_bytes(&self) -> u64 {
        self.discarded
    }

    fn attach(&mut self) {
        if self.client == Client::Waiting {
            self.client = Client::Attached;
            self.sessions += 1;
            tracing::debug!(slave = %self.slave_path.display(), "pty client attached");
        }
    }

    fn detach(&mut self) {
        if self.client == Client::Attached {
            self.client = Client::Waiting;
            self.departure_unreported = true;
            tracing::debug!(slave = %self.slave_path.display(), "pty client left");
            self.flush_stale();
        }
    }

    /// Drops bytes that reached the slave's input queue but no client read, so the next client
    /// starts fresh. Best effort: a failure only means stale bytes may be delivered.
    fn flush_stale(&self) {
        match tty::open_nonblocking(&self.slave_path) {
            Ok(slave) => {
                if let Err(e) = tcflush(&slave, FlushArg::TCIFLUSH) {
                    tracing::debug!(error = %e, "pty: could not flush stale bytes");
                }
            }
            Err(e) => tracing::debug!(error = %e, "pty: could not open slave to flush"),
        }
    }

    fn take_departure(&mut self) -> Result<usize, Error> {
        if self.departure_unreported {
            self.departure_unreported = false;
            Err(Error::disconnected(format!("pty {}: the client closed the port", self.slave_path.display())))
        } else {
            Ok(0)
        }
    }
}

impl Drop for PtyLink {
    fn drop(&mut self) {
        let Some(link) = self.symlink.take() else {
            return;
        };
        // Only remove the symlink if it still points at our slave (a newer twin may own it).
        if std::fs::read_link(&link).is_ok_and(|target| target == self.slave_path)
            && let Err(e) = std::fs::remove_file(&link)
        {
            tracing::warn!(link = %link.display(), error = %e, "pty: could not remove symlink");
        }
    }
}

impl Link for PtyLink {
    type Error = Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
        if buf.is_empty() {
            return Ok(0);
        }
        match nix::unistd::read(&self.master, buf) {
            Ok(0) => {
                // Not seen on Linux (a closed slave gives EIO), but mean the same.
                self.detach();
                self.take_departure()
            }
            Ok(n) => {
                if self.client == Client::Waiting && !self.departure_unreported {
                    self.attach();
                }
                Ok(n)
            }
            Err(Errno::EAGAIN) => {
                // Someone holds the slave open. Report an earlier departure before the new client.
                if self.departure_unreported {
                    return self.take_departure();
                }
                self.attach();
                Ok(0)
            }
            Err(Errno::EINTR) => Ok(0),
            Err(Errno::EIO) => {
                self.detach();
                self.take_departure()
            }
            Err(e) => Err(errno_error(e, &format!("pty {}: read", self.slave_path.display()))),
        }
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
        if buf.is_empty() {
            return Ok(0);
        }
        if tty::hung_up(&self.master) {
            self.detach();
            self.discarded += buf.len() as u64;
            return Ok(buf.len());
        }
        match nix::unistd::write(&self.master, buf) {
            Ok(n) => {
                if self.client == Client::Waiting && !self.departure_unreported {
                    self.attach();
                }
                Ok(n)
            }
            Err(Errno::EAGAIN | Errno::EINTR) => Ok(0),
            Err(Errno::EIO) => {
                self.detach();
                self.discarded += buf.len() as u64;
                Ok(buf.len())
            }
            Err(e) => Err(errno_error(e, &format!("pty {}: write", self.slave_path.display()))),
        }
    }
}

/// The program's side of a pty: its slave opened by path in raw, non-blocking mode — what a
/// program does with `/dev/ttyUSB0` when it does not go through `serialport`.
///
/// When the master goes away the slave hangs up: reads and writes fail with `Disconnected`, and
/// bytes the master wrote but this side had not read yet are lost (the kernel drops them).
#[derive(Debug)]
pub struct PtyClient {
    file: File,
    what: String,
}

impl PtyClient {
    /// Opens the slave at `path` (or a symlink to it), sets raw mode and drops stale input.
    pub fn open(path: impl AsRef<Path>) -> Result<PtyClient, Error> {
        let path = path.as_ref();
        let what = format!("pty client {}", path.display());
        let file = tty::open_nonblocking(path).map_err(|e| Error::from_io(&e, &what))?;
        tty::make_raw(&file).map_err(|e| errno_error(e, &what))?;
        tcflush(&file, FlushArg::TCIFLUSH).map_err(|e| errno_error(e, &what))?;
        Ok(PtyClient { file, what })
    }
}

impl Link for PtyClient {
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
    use std::time::{Duration, Instant};

    /// Reads until `want` bytes or an error arrive, for at most two seconds.
    fn read_some(link: &mut impl Link<Error = Error>, want: usize) -> Result<Vec<u8>, Error> {
        let deadline = Instant::now() + Duration::from_secs(2);
        let mut got = Vec::new();
        let mut buf = [0u8; 256];
        while got.len() < want && Instant::now() < deadline {
            let n = link.read(&mut buf)?;
            got.extend_from_slice(&buf[..n]);
            if n == 0 {
                std::thread::sleep(Duration::from_millis(1));
            }
        }
        Ok(got)
    }

    /// Reads until an error, for at most two seconds; `None` if none came.
    fn wait_error(link: &mut impl Link<Error = Error>) -> Option<Error> {
        let deadline = Instant::now() + Duration::from_secs(2);
        let mut buf = [0u8; 256];
        while Instant::now() < deadline {
            if let Err(e) = link.read(&mut buf) {
                return Some(e);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        None
    }

    /// A folder of its own for one test (removed by the test).
    fn temp_dir(test: &str) -> PathBuf {
        std::env::temp_dir().join(format!("explobot-transport-{}-{test}", std::process::id()))
    }

    #[test]
    fn no_client_yet_reads_nothing_and_discards_writes() {
        let mut pty = PtyLink::open().unwrap();
        assert_eq!(pty.read(&mut [0u8; 16]).unwrap(), 0);
        assert_eq!(pty.write(b"nobody hears this").unwrap(), 17);
        assert_eq!(pty.discarded_bytes(), 17);
        assert!(!pty.client_attached());
        assert_eq!(pty.sessions(), 0);
    }

    #[test]
    fn client_sees_only_bytes_written_after_it_attached() {
        let mut pty = PtyLink::open().unwrap();
        pty.write(b"stale").unwrap();
        let mut client = PtyClient::open(pty.slave_path()).unwrap();
        assert_eq!(pty.write(b"fresh").unwrap(), 5);
        assert_eq!(read_some(&mut client, 5).unwrap(), b"fresh");
        assert!(pty.client_attached());
    }

    #[test]
    fn client_leaving_is_reported_once_after_its_last_bytes() {
        let (mut pty, mut client) = PtyLink::pair().unwrap();
        assert_eq!(client.write(b"last").unwrap(), 4);
        drop(client);
        assert_eq!(read_some(&mut pty, 4).unwrap(), b"last");
        let err = wait_error(&mut pty).unwrap();
        assert_eq!(err.kind(), ErrorKind::Disconnected);
        assert!(err.to_string().contains(&pty.slave_path().display().to_string()));
        // Then it waits for the next client instead of failing again.
        assert_eq!(pty.read(&mut [0u8; 4]).unwrap(), 0);
        assert_eq!(pty.read(&mut [0u8; 4]).unwrap(), 0);
    }

    #[test]
    fn reconnecting_client_gets_no_stale_bytes() {
        let (mut pty, client) = PtyLink::pair().unwrap();
        drop(client);
        assert!(wait_error(&mut pty).unwrap().is_disconnected());
        assert_eq!(pty.write(b"while away").unwrap(), 10);
        assert_eq!(pty.discarded_bytes(), 10);
        let mut again = PtyClient::open(pty.slave_path()).unwrap();
        assert_eq!(pty.read(&mut [0u8; 4]).unwrap(), 0);
        assert_eq!(pty.sessions(), 2);
        pty.write(b"hello again").unwrap();
        assert_eq!(read_some(&mut again, 11).unwrap(), b"hello again");
        again.write(b"ack").unwrap();
        assert_eq!(read_some(&mut pty, 3).unwrap(), b"ack");
    }

    #[test]
    fn unread_bytes_of_a_departed_client_are_not_handed_to_the_next() {
        let (mut pty, client) = PtyLink::pair().unwrap();
        assert_eq!(pty.write(b"never read").unwrap(), 10);
        std::thread::sleep(Duration::from_millis(10));
        drop(client);
        assert!(wait_error(&mut pty).unwrap().is_disconnected());
        // A bare open, which (unlike PtyClient::open) does not flush its input itself.
        let mut next = tty::open_nonblocking(pty.slave_path()).unwrap();
        std::thread::sleep(Duration::from_millis(10));
        let mut buf = [0u8; 16];
        let got = io::Read::read(&mut next, &mut buf);
        assert!(
            got.as_ref().is_err_and(|e| e.kind() == io::ErrorKind::WouldBlock),
            "stale bytes reached the next client: {got:?}"
        );
    }

    #[test]
    fn slave_is_raw_no_echo() {
        let (mut pty, mut client) = PtyLink::pair().unwrap();
        pty.write(b"a\rb\n").unwrap();
        assert_eq!(read_some(&mut client, 4).unwrap(), b"a\rb\n", "no CR/LF translation");
        // With echo on, the client would get its own bytes back and the master would see them
        // twice; in raw mode the master sees them once and the client nothing.
        client.write(b"xyz").unwrap();
        assert_eq!(read_some(&mut pty, 3).unwrap(), b"xyz");
        std::thread::sleep(Duration::from_millis(20));
        assert_eq!(client.read(&mut [0u8; 8]).unwrap(), 0);
        assert_eq!(pty.read(&mut [0u8; 8]).unwrap(), 0);
    }

    #[test]
    fn symlink_points_at_slave_and_is_removed_on_drop() {
        let dir = temp_dir("symlink");
        let link = dir.join("run/tty-motor");
        let pty = PtyLink::open_with_symlink(&link).unwrap();
        assert_eq!(std::fs::read_link(&link).unwrap(), pty.slave_path());
        assert_eq!(pty.symlink_path(), Some(link.as_path()));
        let mut client = PtyClient::open(&link).unwrap();
        let mut pty = pty;
        client.write(b"via symlink").unwrap();
        assert_eq!(read_some(&mut pty, 11).unwrap(), b"via symlink");
        drop(client);
        drop(pty);
        assert!(std::fs::symlink_metadata(&link).is_err());
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn symlink_replaces_stale_symlink_but_not_a_file() {
        let dir = temp_dir("stale");
        let link = dir.join("tty-stale");
        std::fs::create_dir_all(&dir).unwrap();
        symlink("/dev/null", &link).unwrap();
        let pty = PtyLink::open_with_symlink(&link).unwrap();
        assert_eq!(std::fs::read_link(&link).unwrap(), pty.slave_path());
        drop(pty);

        let file = dir.join("tty-regular-file");
        std::fs::write(&file, b"keep me").unwrap();
        let err = PtyLink::open_with_symlink(&file).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::InvalidInput);
        assert_eq!(std::fs::read(&file).unwrap(), b"keep me");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn client_sees_disconnected_when_master_drops() {
        let (pty, mut client) = PtyLink::pair().unwrap();
        drop(pty);
        let err = wait_error(&mut client).unwrap();
        assert_eq!(err.kind(), ErrorKind::Disconnected);
        assert!(client.write(b"x").unwrap_err().is_disconnected());
    }
}
