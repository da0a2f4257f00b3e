//! The robot programs' log of one `explobot run`: Carto's and Cute's `tracing` events, kept for
//! the run folder (`runs/NAME/log.txt`) instead of the terminal.
//!
//! Concept: [`layer`] is a `tracing_subscriber` layer that keeps nothing until [`start`] is
//! called; from then on each event of level INFO or above whose target is in `carto` or `cute`
//! is formatted as one line and kept, at most [`MAX_LINES`] of them (the rest are counted), until
//! [`take`] hands them over. `explobot run` starts it, writes the lines to `log.txt` and prints
//! their count in its report; its terminal shows them only when `RUST_LOG` or `-v` asks. A sweep
//! never starts it.
//!
//! ```
//! use tracing_subscriber::prelude::*;
//! let subscriber = tracing_subscriber::registry().with(explobot::runlog::layer());
//! tracing::subscriber::with_default(subscriber, || {
//!     explobot::runlog::start();
//!     tracing::warn!(target: "carto::pilot", "bumper pressed");
//!     tracing::warn!(target: "twin::world", "not a robot program's line");
//!     let log = explobot::runlog::take();
//!     assert_eq!((log.lines.len(), log.warnings), (1, 1));
//!     assert!(log.lines[0].ends_with("WARN carto::pilot: bumper pressed"));
//! });
//! ```

use std::fmt::{self, Write as _};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::layer::{Context, Layer};

/// The most lines kept for one run; the rest are counted in [`RunLog::dropped`].
pub const MAX_LINES: usize = 200_000;

static ENABLED: AtomicBool = AtomicBool::new(false);
static LOG: Mutex<RunLog> = Mutex::new(RunLog { lines: Vec::new(), warnings: 0, errors: 0, dropped: 0 });

/// What the robot programs logged.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RunLog {
    /// One line per event: `LEVEL target: message field=value …`.
    pub lines: Vec<String>,
    /// Events at WARN.
    pub warnings: u64,
    /// Events at ERROR.
    pub errors: u64,
    /// Events past [`MAX_LINES`], not kept.
    pub dropped: u64,
}

impl RunLog {
    /// The lines as the text of `log.txt`.
    pub fn text(&self) -> String {
        let mut s = String::new();
        for l in &self.lines {
            s.push_str(l);
            s.push('\n');
        }
        if self.dropped > 0 {
            let _ = writeln!(s, "… {} more lines not kept", self.dropped);
        }
        s
    }
}

/// Starts keeping events (and forgets any kept before).
pub fn start() {
    if let Ok(mut log) = LOG.lock() {
        *log = RunLog::default();
    }
    ENABLED.store(true, Ordering::SeqCst);
}

/// Stops keeping events and hands over what was kept.
pub fn take() -> RunLog {
    ENABLED.store(false, Ordering::SeqCst);
    LOG.lock().map(|mut log| std::mem::take(&mut *log)).unwrap_or_default()
}

/// The layer (see the module docs).
pub fn layer<S: Subscriber>() -> impl Layer<S> {
    RunLogLayer
}

struct RunLogLayer;

impl<S: Subscriber> Layer<S> for RunLogLayer {
    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        if !ENABLED.load(Ordering::Relaxed) {
            return;
        }
        let meta = event.metadata();
        let robot = ["carto", "cute"]
            .iter()
            .any(|p| meta.target() == *p || meta.target().starts_with(&format!("{p}::")));
        if !robot || *meta.level() > Level::INFO {
            return;
        }
        let mut line = format!("{:>5} {}: ", meta.level(), meta.target());
        event.record(&mut LineVisitor(&mut line));
        let Ok(mut log) = LOG.lock() else { return };
        match *meta.level() {
            Level::WARN => log.warnings += 1,
            Level::ERROR => log.errors += 1,
            _ => {}
        }
        if log.lines.len() < MAX_LINES {
            log.lines.push(line);
        } else {
            log.dropped += 1;
        }
    }
}

/// Writes the message, then each field as `name=value`.
struct LineVisitor<'a>(&'a mut String);

impl Visit for LineVisitor<'_> {
    fn record_debug(&mut self, field: &Field, value: &dyn fmt::Debug) {
        if field.name() == "message" {
            let _ = write!(self.0, "{value:?}");
        } else {
            let _ = write!(self.0, " {}={value:?}", field.name());
        }
    }

    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name() == "message" {
            self.0.push_str(value);
        } else {
            let _ = write!(self.0, " {}={value}", field.name());
        }
    }
}
