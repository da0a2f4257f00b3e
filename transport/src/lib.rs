#![doc = include_str!("../README.md")]

pub mod clock;
pub mod fault;
pub mod link;
pub mod mem;
#[cfg(unix)]
pub mod pty;
pub mod recorder;
pub mod recording;
#[cfg(unix)]
pub mod serial;
pub mod tcp;
pub mod tracer;
#[cfg(unix)]
mod tty;

pub use clock::{Clock, MockClock, WallClock};
pub use fault::{ByteFaults, DirectionCounters, FaultConfig, FaultCounters, FaultInjector};
pub use link::{Connector, DynLink, Error, ErrorKind, Link, LinkError, Listener};
pub use mem::{
    MemConnector, MemLink, MemLinkConfig, MemLinkStats, MemListener, mem_listener, mem_listener_with,
};
#[cfg(unix)]
pub use pty::{PtyClient, PtyLink};
#[cfg(unix)]
pub use serial::{SerialLink, SerialLinkBuilder};
pub use tcp::{KeepAlive, TcpConnector, TcpLink, TcpListenerLink};
pub use tracer::{Direction, TraceHandle, TraceRecord, TraceTotals, Tracer};
