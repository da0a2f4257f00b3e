//! Carto's and Cute's `tracing` events as Foxglove `Log` messages, stamped with the sim time of
//! the step that emitted them.
//!
//! Concept: [`layer`] is a `tracing_subscriber` layer that does nothing until a thread is
//! *capturing*: between [`Capture::start`] and [`Capture::stop`] (the publisher calls them around
//! every step), each event of level INFO or above on that thread is kept in that capture's
//! buffer. Captures are per thread, so the runs of a sweep, each on its own worker thread, never
//! see each other's events.
//!
//! `explobot` installs the layer beside its stderr output; a program that wants the events
//! installs it too:
//!
//! ```
//! use tracing_subscriber::prelude::*;
//! let subscriber = tracing_subscriber::registry().with(twin_viz::logs::layer());
//! tracing::subscriber::with_default(subscriber, || {
//!     let capture = twin_viz::logs::Capture::default();
//!     capture.start();
//!     tracing::info!(cell = 3, "reached");
//!     capture.stop();
//!     let events = capture.drain();
//!     assert_eq!(events[0].message, "reached cell=3");
//! });
//! ```

use std::cell::RefCell;
use std::fmt::{self, Write as _};
use std::sync::{Arc, Mutex, PoisonError};

use foxglove::messages::{Log, log};
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Metadata, Subscriber};
use tracing_subscriber::layer::{Context, Filter, Layer};

/// One captured event.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Captured {
    /// Its level.
    pub level: Level,
    /// Its target (module path), e.g. `carto::pilot`.
    pub target: String,
    /// The message, then every other field as `name=value`.
    pub message: String,
    /// Source file, if known.
    pub file: String,
    /// Source line, 0 if unknown.
    pub line: u32,
}

impl Captured {
    /// As a Foxglove `Log` at `ns` nanoseconds of sim time; `name` is the crate (`carto`, `cute`).
    pub fn to_log(&self, ns: u64) -> Log {
        let level = match self.level {
            Level::ERROR => log::Level::Error,
            Level::WARN => log::Level::Warning,
            Level::INFO => log::Level::Info,
            Level::DEBUG | Level::TRACE => log::Level::Debug,
        };
        Log {
            timestamp: Some(super::scene::timestamp(ns)),
            level: level as i32,
            message: self.message.clone(),
            name: self.target.split("::").next().unwrap_or_default().to_string(),
            file: self.file.clone(),
            line: self.line,
        }
    }
}

type Buffer = Arc<Mutex<Vec<Captured>>>;

thread_local! {
    static CAPTURING: RefCell<Option<Buffer>> = const { RefCell::new(None) };
}

/// A buffer of events captured on the threads that [`start`](Capture::start)ed it.
#[derive(Debug, Clone, Default)]
pub struct Capture {
    buffer: Buffer,
}

impl Capture {
    /// From now on, events on this thread go to this capture.
    pub fn start(&self) {
        CAPTURING.with(|c| *c.borrow_mut() = Some(Arc::clone(&self.buffer)));
    }

    /// Events on this thread are no longer captured (by any capture).
    pub fn stop(&self) {
        stop_capturing();
    }

    /// The events captured so far, oldest first, leaving none.
    pub fn drain(&self) -> Vec<Captured> {
        std::mem::take(&mut *self.buffer.lock().unwrap_or_else(PoisonError::into_inner))
    }
}

/// Ends any capture on this thread (e.g. after a run that panicked inside a step).
pub fn stop_capturing() {
    CAPTURING.with(|c| *c.borrow_mut() = None);
}

fn capturing() -> bool {
    CAPTURING.with(|c| c.borrow().is_some())
}

/// The layer that feeds captures (see the [module docs](self)).
pub fn layer<S: Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>>() -> impl Layer<S> {
    CaptureLayer.with_filter(WhileCapturing)
}

struct CaptureLayer;

impl<S: Subscriber> Layer<S> for CaptureLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let Some(buffer) = CAPTURING.with(|c| c.borrow().clone()) else { return };
        let meta = event.metadata();
        let mut fields = Fields::default();
        event.record(&mut fields);
        let captured = Captured {
            level: *meta.level(),
            target: meta.target().to_string(),
            message: fields.text,
            file: meta.file().unwrap_or_default().to_string(),
            line: meta.line().unwrap_or_default(),
        };
        buffer.lock().unwrap_or_else(PoisonError::into_inner).push(captured);
    }
}

/// INFO and above, on a thread that is capturing.
struct WhileCapturing;

impl<S> Filter<S> for WhileCapturing {
    fn enabled(&self, meta: &Metadata<'_>, _cx: &Context<'_, S>) -> bool {
        *meta.level() <= Level::INFO && capturing()
    }

    fn callsite_enabled(&self, meta: &'static Metadata<'static>) -> tracing::subscriber::Interest {
        if *meta.level() <= Level::INFO {
            tracing::subscriber::Interest::sometimes()
        } else {
            tracing::subscriber::Interest::never()
        }
    }

    fn max_level_hint(&self) -> Option<tracing::level_filters::LevelFilter> {
        Some(tracing::level_filters::LevelFilter::INFO)
    }
}

/// The message first, then `name=value` for every other field.
#[derive(Default)]
struct Fields {
    text: String,
}

impl Visit for Fields {
    fn record_debug(&mut self, field: &Field, value: &dyn fmt::Debug) {
        if field.name() == "message" {
            let rest = std::mem::take(&mut self.text);
            let _ = write!(self.text, "{value:?}");
            if !rest.is_empty() {
                self.text.push(' ');
                self.text.push_str(&rest);
            }
        } else {
            if !self.text.is_empty() {
                self.text.push(' ');
            }
            let _ = write!(self.text, "{}={value:?}", field.name());
        }
    }

    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name() == "message" {
            self.record_debug(field, &format_args!("{value}"));
        } else {
            self.record_debug(field, &value);
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use tracing_subscriber::prelude::*;

    use super::*;

    #[test]
    fn only_a_capturing_thread_keeps_events_at_info_and_above() {
        let subscriber = tracing_subscriber::registry().with(layer());
        tracing::subscriber::with_default(subscriber, || {
            let capture = Capture::default();
            tracing::warn!("before");
            capture.start();
            tracing::debug!("too low");
            tracing::warn!(peer = "a", "bad frame");
            std::thread::scope(|s| {
                s.spawn(|| tracing::error!("another thread"));
            });
            capture.stop();
            tracing::error!("after");
            let events = capture.drain();
            assert_eq!(events.len(), 1, "{events:?}");
            assert_eq!(events[0].message, "bad frame peer=\"a\"");
            let log = events[0].to_log(1_500_000_000);
            assert_eq!((log.level, log.name.as_str()), (log::Level::Warning as i32, "twin_viz"));
            assert!(capture.drain().is_empty());
        });
    }
}
