//! [`CuteRuntime`]: the pump between [`Cute`] and a real (or in-memory) connection to Carto — the
//! twin of `carto::CartoRuntime`.
//!
//! Concept: generic over transport's [`Connector`] and [`Link`], so the lockstep simulator
//! (in-memory links, virtual clock, each connection wrapped in a fault injector and a tracer by a
//! [`Wrap`]) and the `cute` binary (TCP, wall clock) run the very same loop. One
//! [`CuteRuntime::step_with`] at `now`:
//! 1. dials when Cute says a (re)connection is due (the back-off is Cute's), wrapping the new link;
//! 2. reads everything waiting and feeds it to Cute;
//! 3. drops the link if reading failed or Cute asked to close it;
//! 4. runs the caller's hook on Cute (a user action, a mission script);
//! 5. polls Cute (timeouts, the next move);
//! 6. writes Cute's output, keeping what the link did not take for the next step.
//!
//! Errors: a failed attempt is reported to Cute (which backs off) and logged once per distinct
//! message; a read or write error drops the link, and Cute reconnects by itself.
//!
//! Invariants: nothing here reads a clock; the `n`-th connection (from 0) is wrapped with `n`;
//! bytes not yet written never reach a later connection (Cute re-sends what matters).
//!
//! ```
//! use cute::{Cute, CuteConfig, CuteRuntime};
//! use robot_model::time::Instant;
//! use transport::{Link, Listener, MockClock, mem_listener};
//! let (mut listener, connector) = mem_listener(None, MockClock::new());
//! let mut rt = CuteRuntime::new(Cute::new(CuteConfig::default()).unwrap(), connector);
//! rt.step(Instant::ZERO); // dials and sends SEND_ROBOT_POSITION
//! let (mut carto, _peer) = listener.accept().unwrap().unwrap();
//! let mut got = Vec::new();
//! carto.read_available(&mut got).unwrap();
//! assert_eq!(got, [0x00, 0x05, 0x07, 0x00, 0, 0, 3]);
//! carto.write(&[0x00, 0x02, 0x08, 0x00]).unwrap(); // ROBOT_POSITION_RECEIVED
//! rt.step_with(Instant::from_millis(5), |cute| cute.start_cartography().unwrap());
//! got.clear();
//! carto.read_available(&mut got).unwrap();
//! assert_eq!(got, [0x00, 0x03, 0x02, 0x00, 0]); // SEND_MOVE_CARTOGRAPHY FORWARD, same step
//! assert_eq!(rt.connects(), 1);
//! ```

use robot_model::time::Instant;
use tracing::warn;
use transport::{Connector, Link};

use crate::session::Cute;

/// What the runtime does with each new connection's link, and with a link it lets go.
pub trait Wrap<R> {
    /// The link the runtime reads and writes.
    type Link: Link;

    /// Wraps the raw link of connection number `n` (0 for the first).
    fn wrap(&mut self, raw: R, n: u64) -> Self::Link;

    /// Called with a link just before the runtime drops it (e.g. to keep its counters).
    fn retire(&mut self, link: Self::Link) {
        drop(link);
    }
}

/// Uses each connection's link as it is.
#[derive(Debug, Clone, Copy, Default)]
pub struct Plain;

impl<R: Link> Wrap<R> for Plain {
    type Link = R;
    fn wrap(&mut self, raw: R, _n: u64) -> R {
        raw
    }
}

/// [`Cute`] plus its connection to Carto (see the module docs).
pub struct CuteRuntime<C: Connector, W: Wrap<C::Link> = Plain> {
    cute: Cute,
    connector: C,
    wrap: W,
    link: Option<W::Link>,
    unsent: Vec<u8>,
    connects: u64,
    last_connect_error: Option<String>,
    incoming: Vec<u8>,
}

impl<C: Connector> CuteRuntime<C> {
    /// A runtime dialling Carto with `connector` and using each link as it is.
    pub fn new(cute: Cute, connector: C) -> Self {
        CuteRuntime::with_wrap(cute, connector, Plain)
    }
}

impl<C: Connector, W: Wrap<C::Link>> CuteRuntime<C, W> {
    /// A runtime dialling Carto with `connector`, passing each new link through `wrap`.
    pub fn with_wrap(cute: Cute, connector: C, wrap: W) -> Self {
        CuteRuntime {
            cute,
            connector,
            wrap,
            link: None,
            unsent: Vec::new(),
            connects: 0,
            last_connect_error: None,
            incoming: Vec::new(),
        }
    }

    /// The session.
    pub fn cute(&self) -> &Cute {
        &self.cute
    }

    /// The session, for user actions and events.
    pub fn cute_mut(&mut self) -> &mut Cute {
        &mut self.cute
    }

    /// The wrapper (e.g. to read what it keeps about each connection).
    pub fn wrapper(&self) -> &W {
        &self.wrap
    }

    /// The current link, while connected.
    pub fn link(&self) -> Option<&W::Link> {
        self.link.as_ref()
    }

    /// Successful connections so far.
    pub fn connects(&self) -> u64 {
        self.connects
    }

    /// One pump cycle at `now` with no hook.
    pub fn step(&mut self, now: Instant) {
        self.step_with(now, |_| {});
    }

    /// One pump cycle at `now`; `act` runs on Cute after the incoming bytes and before
    /// [`Cute::poll`], so what it sends goes out in this same step.
    pub fn step_with(&mut self, now: Instant, act: impl FnOnce(&mut Cute)) {
        self.connect_if_due(now);
        let alive = self.read(now);
        if !alive || self.cute.close_requested() {
            self.disconnect(now);
        }
        act(&mut self.cute);
        self.cute.poll(now);
        self.write(now);
    }

    /// Drops the link now, if any (a fault, a shutdown); Cute hears of it and reconnects later.
    pub fn disconnect(&mut self, now: Instant) {
        if let Some(link) = self.link.take() {
            self.unsent.clear();
            self.wrap.retire(link);
            self.cute.on_disconnected(now);
        }
    }

    fn connect_if_due(&mut self, now: Instant) {
        if self.link.is_some() || self.cute.next_connect_at(now).is_none_or(|at| now < at) {
            return;
        }
        match self.connector.connect() {
            Ok(raw) => {
                self.link = Some(self.wrap.wrap(raw, self.connects));
                self.connects += 1;
                self.last_connect_error = None;
                self.cute.on_connected(now);
            }
            Err(e) => {
                let text = e.to_string();
                if self.last_connect_error.as_deref() != Some(text.as_str()) {
                    warn!("cannot connect to Carto: {text}");
                    self.last_connect_error = Some(text);
                }
                self.cute.on_connect_failed(now);
            }
        }
    }

    /// Feeds what has arrived to Cute; false if the link failed.
    fn read(&mut self, now: Instant) -> bool {
        let Some(link) = self.link.as_mut() else {
            return true;
        };
        self.incoming.clear();
        // On an error, the bytes read before it are in `incoming` and still count.
        let alive = match link.read_available(&mut self.incoming) {
            Ok(_) => true,
            Err(e) => {
                warn!("link to Carto failed: {e}");
                false
            }
        };
        if !self.incoming.is_empty() {
            self.cute.on_bytes(now, &self.incoming);
        }
        alive
    }

    fn write(&mut self, now: Instant) {
        let out = self.cute.take_outgoing();
        let Some(link) = self.link.as_mut() else {
            return;
        };
        self.unsent.extend_from_slice(&out);
        while !self.unsent.is_empty() {
            match link.write(&self.unsent) {
                Ok(0) => break,
                Ok(n) => {
                    self.unsent.drain(..n.min(self.unsent.len()));
                }
                Err(e) => {
                    warn!("link to Carto failed: {e}");
                    self.disconnect(now);
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use std::cell::Cell;
    use std::rc::Rc;

    use protocol::link::{Decoder, GuiMessage, MsgOrder};
    use robot_model::time::Duration;
    use transport::{Error, Listener, MemConnector, MemLink, MemListener, MockClock, mem_listener};

    use super::*;
    use crate::session::{CuteConfig, CuteEvent, RECONNECT_MIN, Status};

    const ACK: [u8; 4] = [0x00, 0x02, 0x08, 0x00];

    /// A link that takes at most `budget` bytes in all, until the test adds more.
    struct Trickle {
        inner: MemLink,
        budget: Rc<Cell<usize>>,
    }

    impl Link for Trickle {
        type Error = Error;
        fn read(&mut self, buf: &mut [u8]) -> Result<usize, Error> {
            self.inner.read(buf)
        }
        fn write(&mut self, buf: &[u8]) -> Result<usize, Error> {
            let n = buf.len().min(self.budget.get());
            let n = self.inner.write(&buf[..n])?;
            self.budget.set(self.budget.get() - n);
            Ok(n)
        }
    }

    /// Records the connection numbers it wrapped and retired.
    #[derive(Default)]
    struct Recorder {
        budget: Rc<Cell<usize>>,
        wrapped: Vec<u64>,
        retired: usize,
    }

    impl Wrap<MemLink> for Recorder {
        type Link = Trickle;
        fn wrap(&mut self, raw: MemLink, n: u64) -> Trickle {
            self.wrapped.push(n);
            Trickle { inner: raw, budget: Rc::clone(&self.budget) }
        }
        fn retire(&mut self, link: Trickle) {
            self.retired += 1;
            drop(link);
        }
    }

    fn setup(budget: usize) -> (CuteRuntime<MemConnector, Recorder>, MemListener) {
        let (listener, connector) = mem_listener(None, MockClock::new());
        let rec = Recorder { budget: Rc::new(Cell::new(budget)), ..Recorder::default() };
        (CuteRuntime::with_wrap(Cute::new(CuteConfig::default()).unwrap(), connector, rec), listener)
    }

    fn frames(link: &mut MemLink) -> Vec<GuiMessage> {
        let mut bytes = Vec::new();
        link.read_available(&mut bytes).unwrap();
        Decoder::default().feed(&bytes).into_iter().map(Result::unwrap).collect()
    }

    fn ms(n: u64) -> Instant {
        Instant::from_millis(n)
    }

    #[test]
    fn the_hook_acts_between_reading_and_polling() {
        let (mut rt, mut listener) = setup(usize::MAX);
        rt.step(ms(0));
        let (mut carto, _) = listener.accept().unwrap().unwrap();
        assert!(matches!(frames(&mut carto)[..], [GuiMessage::SendRobotPosition { .. }]));
        carto.write(&ACK).unwrap();
        let mut ready_in_hook = false;
        rt.step_with(ms(5), |cute| {
            ready_in_hook = cute.is_ready();
            cute.start_cartography().unwrap();
        });
        assert!(ready_in_hook, "the acknowledgement was read before the hook ran");
        assert!(matches!(frames(&mut carto)[..], [GuiMessage::SendMoveCartography { .. }]));
        assert_eq!(rt.cute().status(), Status::Mapping);
    }

    #[test]
    fn the_hook_acts_before_timeouts_are_checked() {
        let (mut rt, mut listener) = setup(usize::MAX);
        rt.step(ms(0));
        let (mut carto, _) = listener.accept().unwrap().unwrap();
        carto.write(&ACK).unwrap();
        rt.step_with(ms(1), |cute| cute.start_cartography().unwrap());
        frames(&mut carto);
        rt.cute_mut().take_events();
        // The move's deadline has passed, but the hook stops the mission first: no timeout.
        rt.step_with(ms(1) + Duration::from_secs(6), Cute::stop);
        assert_eq!(rt.cute_mut().take_events(), [CuteEvent::Stopped]);
        assert_eq!(frames(&mut carto), [GuiMessage::StopRobot]);
    }

    #[test]
    fn a_closed_peer_drops_the_link_and_cute_reconnects_after_the_back_off() {
        let (mut rt, mut listener) = setup(usize::MAX);
        rt.step(ms(0));
        let (carto, _) = listener.accept().unwrap().unwrap();
        drop(carto);
        rt.step(ms(10));
        assert!(rt.link().is_none() && !rt.cute().is_connected());
        assert_eq!(rt.wrapper().retired, 1);
        rt.step(ms(10) + RECONNECT_MIN - Duration::from_millis(1));
        assert!(listener.accept().unwrap().is_none(), "not before the back-off");
        rt.step(ms(10) + RECONNECT_MIN);
        assert!(listener.accept().unwrap().is_some());
        assert_eq!((rt.connects(), &rt.wrapper().wrapped[..]), (2, &[0, 1][..]));
        let events = rt.cute_mut().take_events();
        assert_eq!(events, [CuteEvent::Connected, CuteEvent::ConnectionLost, CuteEvent::Connected]);
    }

    #[test]
    fn a_failed_connect_backs_off() {
        let (mut rt, mut listener) = setup(usize::MAX);
        listener.close();
        rt.step(ms(0));
        assert_eq!(rt.connects(), 0);
        assert_eq!(rt.cute().next_connect_at(ms(0)), Some(ms(0) + RECONNECT_MIN));
    }

    #[test]
    fn bytes_the_link_did_not_take_go_out_in_order_later_but_not_on_a_new_connection() {
        let (mut rt, mut listener) = setup(3);
        rt.step(ms(0)); // SEND_ROBOT_POSITION is 7 bytes; 3 go out
        let (mut carto, _) = listener.accept().unwrap().unwrap();
        let mut got = Vec::new();
        carto.read_available(&mut got).unwrap();
        assert_eq!(got.len(), 3);
        rt.wrapper().budget.set(usize::MAX);
        rt.step(ms(1));
        carto.read_available(&mut got).unwrap();
        let position =
            GuiMessage::SendRobotPosition { x: 0, y: 0, direction: protocol::link::Direction::East };
        assert_eq!(got, position.to_bytes(MsgOrder::BigEndian));

        rt.wrapper().budget.set(2);
        rt.cute_mut().stop(); // STOP_ROBOT: 4 bytes, 2 go out
        rt.step(ms(2));
        rt.disconnect(ms(3));
        rt.wrapper().budget.set(usize::MAX);
        rt.step(ms(3) + RECONNECT_MIN);
        let (mut second, _) = listener.accept().unwrap().unwrap();
        assert!(
            matches!(frames(&mut second)[..], [GuiMessage::SendRobotPosition { .. }]),
            "no stale half frame"
        );
    }
}
