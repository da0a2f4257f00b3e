//! When a frame read off a serial line was sampled ([`LineTimer`]).

use robot_model::time::{Duration, Instant};

/// Estimates when a frame's content was sampled from when it finished arriving on a serial line.
///
/// A board samples its sensors and writes all due frames at once; on a slow line (9600 baud is
/// 960 bytes/s) the last frame of such a burst arrives up to ~100 ms after the sample. Stamping a
/// reading with its arrival time would make every estimate lag by that much (a turn at 30°/s
/// overshoots by ~1.5°). So: a frame of `len` bytes that completed at `arrived` started at
/// `arrived − len × 10 / baud`; if it started right when the previous frame ended (within two
/// byte times or 2 ms), it was queued behind it and belongs to the same burst, so it gets the
/// burst's start as its time; otherwise it starts a new burst. A burst longer than 150 ms is cut
/// (a saturated line must not freeze the clock). Baud 0 disables the correction.
#[derive(Debug, Clone)]
pub struct LineTimer {
    byte_micros: f64,
    last_end: Option<Instant>,
    burst_start: Instant,
}

impl LineTimer {
    /// A timer for a line at `baud` (8N1: ten bits per byte); 0 = arrival time as is.
    pub fn new(baud: u32) -> Self {
        let byte_micros = robot_model::time::line_byte_micros(baud);
        LineTimer { byte_micros, last_end: None, burst_start: Instant::ZERO }
    }

    /// The estimated sampling time of a `len`-byte frame that completed at `arrived`.
    pub fn sampled_at(&mut self, arrived: Instant, len: usize) -> Instant {
        if self.byte_micros == 0.0 {
            return arrived;
        }
        let tx = Duration::from_micros((len as f64 * self.byte_micros).round() as u64);
        let start = arrived - tx;
        let slack = Duration::from_micros(((2.0 * self.byte_micros) as u64).max(2000));
        let queued = self.last_end.is_some_and(|end| start <= end + slack);
        if !queued || arrived.saturating_since(self.burst_start) > Duration::from_millis(150) {
            self.burst_start = start;
        }
        self.last_end = Some(self.last_end.map_or(arrived, |e| e.max(arrived)));
        self.burst_start
    }
}
