//! `carto --record`: Carto's links traced into a [`transport::recorder::Recorder`], in the twin's
//! recording format (`transport::recording`).
//!
//! Endpoint names, as the twin's: link `motor` and `sensor` at endpoint `carto`, and link `gui`
//! at `carto#1`, `carto#2`, … one per accepted client connection (the twin records Cute's side
//! as `cute#N`). A board link that is reopened carries on its endpoint's trace
//! ([`MaybeTraced::new`] with the same handle).
//!
//! Invariant: without recording, links are passed through untouched and nothing is kept.
//!
//! ```
//! use carto::recording::MaybeTraced;
//! use transport::{Link, MemLink, MockClock, TraceHandle};
//! let clock = MockClock::new();
//! let motor_trace = TraceHandle::default();
//! let (a, _b) = MemLink::pair(None, clock.clone());
//! let mut motor = MaybeTraced::new(a, Some((&motor_trace, clock)));
//! motor.write(&[0xAA])?;
//! assert_eq!(motor_trace.take().len(), 1);
//! # Ok::<(), transport::Error>(())
//! ```

use std::os::fd::{AsFd, BorrowedFd};

use transport::recorder::RecorderFeed;
use transport::{Clock, Link, Listener, TraceHandle, Tracer};

/// A link traced into a recording, or passed through.
#[derive(Debug)]
pub enum MaybeTraced<L> {
    /// Not recorded.
    Plain(L),
    /// Every byte recorded.
    Traced(Tracer<L>),
}

impl<L: Link> MaybeTraced<L> {
    /// `link`, traced into `trace` (stamped by its clock) if there is one.
    pub fn new<C: Clock + 'static>(link: L, trace: Option<(&TraceHandle, C)>) -> Self {
        match trace {
            Some((handle, clock)) => MaybeTraced::Traced(Tracer::with_handle(link, clock, handle)),
            None => MaybeTraced::Plain(link),
        }
    }

    /// The link itself.
    pub fn inner(&self) -> &L {
        match self {
            MaybeTraced::Plain(l) => l,
            MaybeTraced::Traced(l) => l.inner(),
        }
    }
}

impl<L: Link> Link for MaybeTraced<L> {
    type Error = L::Error;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, L::Error> {
        match self {
            MaybeTraced::Plain(l) => l.read(buf),
            MaybeTraced::Traced(l) => l.read(buf),
        }
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, L::Error> {
        match self {
            MaybeTraced::Plain(l) => l.write(buf),
            MaybeTraced::Traced(l) => l.write(buf),
        }
    }
}

impl<L: Link + AsFd> AsFd for MaybeTraced<L> {
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.inner().as_fd()
    }
}

/// A listener whose accepted connections are traced, each as endpoint `carto#N` of link `gui`,
/// when it is given a recorder.
#[derive(Debug)]
pub struct TracedListener<L, C> {
    inner: L,
    record: Option<(RecorderFeed, C)>,
    accepted: u64,
}

impl<L: Listener, C: Clock + Clone + 'static> TracedListener<L, C> {
    /// Wraps `inner`; with `record`, every connection it accepts is traced into that recorder.
    pub fn new(inner: L, record: Option<(RecorderFeed, C)>) -> Self {
        TracedListener { inner, record, accepted: 0 }
    }

    /// The listener itself.
    pub fn inner(&self) -> &L {
        &self.inner
    }
}

impl<L: Listener, C: Clock + Clone + 'static> Listener for TracedListener<L, C> {
    type Link = MaybeTraced<L::Link>;
    type Error = L::Error;

    fn accept(&mut self) -> Result<Option<(Self::Link, String)>, L::Error> {
        let Some((link, peer)) = self.inner.accept()? else {
            return Ok(None);
        };
        self.accepted += 1;
        let link = match &self.record {
            Some((feed, clock)) => {
                let traced = Tracer::new(link, clock.clone());
                feed.add("gui", &format!("carto#{}", self.accepted), traced.handle());
                MaybeTraced::Traced(traced)
            }
            None => MaybeTraced::Plain(link),
        };
        Ok(Some((link, peer)))
    }

    fn has_pending(&mut self) -> bool {
        self.inner.has_pending()
    }
}

impl<L: AsFd, C> AsFd for TracedListener<L, C> {
    fn as_fd(&self) -> BorrowedFd<'_> {
        self.inner.as_fd()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use transport::recorder::{Recorder, RecorderConfig};
    use transport::recording::{FORMAT_VERSION, Oracle, Recording};
    use transport::{Connector, MockClock, mem_listener};

    #[test]
    fn each_client_connection_is_its_own_endpoint_and_plain_links_keep_nothing() {
        let dir = std::env::temp_dir().join(format!("carto-recording-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.rec");
        let header = Recording {
            version: FORMAT_VERSION,
            scenario_label: "t".into(),
            scenario_ron: String::new(),
            profile_ron: "()".into(),
            seed: 0,
            logs: vec![],
            oracle: Oracle::None,
        };
        let recorder = Recorder::start(path.clone(), header, RecorderConfig::default()).unwrap();
        let clock = MockClock::new();
        let (listener, mut connector) = mem_listener(None, clock.clone());
        let mut listener = TracedListener::new(listener, Some((recorder.feed(), clock.clone())));
        for hello in [&b"first"[..], b"second"] {
            let mut client = connector.connect().unwrap();
            let (mut server, _) = listener.accept().unwrap().unwrap();
            client.write(hello).unwrap();
            let mut buf = [0u8; 16];
            assert_eq!(server.read(&mut buf).unwrap(), hello.len());
        }
        recorder.finish();
        let rec = Recording::load(&path).unwrap();
        let endpoints: Vec<_> = rec.logs.iter().map(|l| (l.link.as_str(), l.endpoint.as_str())).collect();
        assert_eq!(endpoints, [("gui", "carto#1"), ("gui", "carto#2")]);
        assert_eq!(rec.logs[1].chunks[0].bytes, b"second");

        let (listener, mut connector) = mem_listener(None, clock.clone());
        let mut plain = TracedListener::<_, MockClock>::new(listener, None);
        let _client = connector.connect().unwrap();
        assert!(matches!(plain.accept().unwrap(), Some((MaybeTraced::Plain(_), _))));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
