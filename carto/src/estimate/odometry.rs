//! Dead reckoning of where the robot is inside its grid cell.
//!
//! Concept: Cute thinks in cells, the robot lives in metres. [`Odometry`] keeps a [`CellOffset`]:
//! the robot's offset from the centre of the cell Carto believes it is in, expressed in the
//! *nominal frame* — `along` the grid heading the robot should face, `left` of it. It integrates
//! the four wheel encoders (mecanum forward kinematics: forward = mean of the four wheel
//! distances, left = (−FL + FR + RL − RR) / (4 · tan γ)), rotated by the IMU's heading error
//! against the nominal heading, every time all four wheels have reported again. The controller
//! uses it to aim each FORWARD at the *next cell's centre* (drive `cell − along`) and to strafe
//! `left` back to zero, so residuals never accumulate.
//!
//! Bookkeeping, done by [`crate::motor::Motor`]:
//! - a successful FORWARD moves the origin one cell ahead ([`Odometry::advance`]): `along −= cell`;
//! - a successful turn moves the nominal frame by ±90° ([`Odometry::set_frame`]) and the offset is
//!   rotated into it; any re-learnt reference heading does the same;
//! - `SEND_ROBOT_POSITION` resets the offset to zero ([`Odometry::reset`]): Cute's pose is the
//!   only outside statement of where the robot is, and it names a cell, i.e. its centre.
//!
//! Invariants:
//! - counts are integrated once: the baseline is the last fully refreshed set of four counts;
//! - a jump of more than a metre between two samples (a board reset its counters) or a loss of
//!   readings re-baselines without moving the offset;
//! - wheel slip is invisible to encoders: this is dead reckoning, it drifts with slip only.
//!
//! ```
//! use carto::odometry::Odometry;
//! use carto::sensors::{SensorEvent, SensorState};
//! use carto::CartoConfig;
//! use robot_model::time::Instant;
//! let cfg = CartoConfig::default();
//! let (mut s, mut odo) = (SensorState::default(), Odometry::default());
//! let feed = |s: &mut SensorState, ms: u64, c: [i32; 4]| {
//!     s.ingest(Instant::from_millis(ms), SensorEvent::Heading { cw_deg: 0.0 });
//!     for (wheel, count) in c.into_iter().enumerate() {
//!         s.ingest(Instant::from_millis(ms), SensorEvent::Encoder { wheel, count });
//!     }
//! };
//! feed(&mut s, 0, [0; 4]);
//! odo.update(&s, &cfg);
//! // every wheel rolled 422 counts (half a metre) forward, then strafe left: FR/RL +, FL/RR −
//! feed(&mut s, 200, [422, 422, 422, 422]);
//! odo.update(&s, &cfg);
//! feed(&mut s, 400, [422 - 84, 422 + 84, 422 + 84, 422 - 84]);
//! odo.update(&s, &cfg);
//! let o = odo.offset();
//! assert!((o.along_m - 0.5).abs() < 0.002 && (o.left_m - 0.0995).abs() < 0.002, "{o:?}");
//! ```

use robot_model::time::Instant;

use crate::CartoConfig;
use crate::sensors::SensorState;

/// The robot's offset from the centre of its cell, in the nominal frame, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CellOffset {
    /// Along the nominal heading (positive = ahead of the centre).
    pub along_m: f64,
    /// Left of the nominal heading.
    pub left_m: f64,
}

impl CellOffset {
    /// This offset seen from a frame rotated `deg` counter-clockwise.
    pub fn rotated_into(self, deg: f64) -> CellOffset {
        let (sin, cos) = deg.to_radians().sin_cos();
        CellOffset {
            along_m: self.along_m * cos + self.left_m * sin,
            left_m: -self.along_m * sin + self.left_m * cos,
        }
    }

    /// Euclidean length, metres.
    pub fn norm(self) -> f64 {
        self.along_m.hypot(self.left_m)
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    counts: [i32; 4],
    yaw_deg: f64,
    at: Instant,
}

/// Encoder + IMU dead reckoning of the offset from the cell centre (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Odometry {
    offset: CellOffset,
    frame_deg: Option<f64>,
    last: Option<Sample>,
}

impl Odometry {
    /// The offset at the last integrated sample.
    pub fn offset(&self) -> CellOffset {
        self.offset
    }

    /// The four counts the offset was last integrated at (a consistent baseline for a move that
    /// targets the offset).
    pub fn baseline_counts(&self) -> Option<[i32; 4]> {
        self.last.map(|l| l.counts)
    }

    /// The nominal heading the offset is expressed in (unwrapped CCW yaw, degrees), once known.
    pub fn frame_deg(&self) -> Option<f64> {
        self.frame_deg
    }

    /// The robot is at the centre of its cell (a fresh pose from Cute). The integration baseline
    /// and the frame are kept.
    pub fn reset(&mut self) {
        self.offset = CellOffset::default();
    }

    /// An outside measurement says the robot is `metres` further along the nominal heading than
    /// the wheels say (negative: less far), e.g. the sonar range to a wall ahead.
    pub fn correct_along(&mut self, metres: f64) {
        self.offset.along_m += metres;
    }

    /// An outside estimate says the robot is `fix` away from where the wheels say, in the
    /// nominal frame (the localiser's correction).
    pub fn correct(&mut self, fix: CellOffset) {
        self.offset.along_m += fix.along_m;
        self.offset.left_m += fix.left_m;
    }

    /// The robot now believes it is in the cell `metres` ahead: the origin moves there.
    pub fn advance(&mut self, metres: f64) {
        self.offset.along_m -= metres;
    }

    /// Expresses the offset in a new nominal heading (after a turn or a re-learnt reference).
    pub fn set_frame(&mut self, frame_deg: f64) {
        if let Some(old) = self.frame_deg {
            self.offset = self.offset.rotated_into(frame_deg - old);
        }
        self.frame_deg = Some(frame_deg);
    }

    /// Body-frame displacement `(forward, left)`, metres, of four wheel count deltas.
    pub fn body_delta(delta_counts: [f64; 4], cfg: &CartoConfig) -> (f64, f64) {
        let [fl, fr, rl, rr] = delta_counts.map(|d| d / cfg.encoder_counts_per_metre());
        let forward = (fl + fr + rl + rr) / 4.0;
        let left = (-fl + fr + rl - rr) / (4.0 * cfg.chassis.roller_tan);
        (forward, left)
    }

    /// Integrates the motion since the last sample once all four wheels have reported again.
    pub fn update(&mut self, s: &SensorState, cfg: &CartoConfig) {
        self.update_with(s, cfg, true);
    }

    /// Like [`Odometry::update`]; with `translate` false (a turn on the spot) the new sample only
    /// becomes the baseline: the offset does not move.
    ///
    /// Why: the four encoders are sampled one after the other, and while turning the wheels roll
    /// fast in opposite directions, so a set of four counts mixes instants and reads as a few
    /// millimetres of spurious translation per sample that the rotation keeps from cancelling.
    /// A turn on the spot does not translate the robot (slip, which would, is invisible anyway).
    pub fn update_with(&mut self, s: &SensorState, cfg: &CartoConfig, translate: bool) {
        let (Some(c), Some(y)) = (s.counts(), s.yaw_deg()) else {
            // Readings lost (board gone): start again from the next complete set.
            if s.counts().is_none() {
                self.last = None;
            }
            return;
        };
        let now = Sample { counts: c.value, yaw_deg: y.value, at: c.at };
        let Some(last) = self.last else {
            self.last = Some(now);
            return;
        };
        if now.at <= last.at {
            return;
        }
        let delta = delta_counts(&now.counts.map(f64::from), &last.counts);
        let limit = cfg.encoder_counts_per_metre();
        if delta.iter().any(|d| d.abs() > limit) {
            tracing::warn!(?delta, "encoder counts jumped: odometry re-baselined, offset kept");
            self.last = Some(now);
            return;
        }
        if self.frame_deg.is_none() {
            self.frame_deg = Some(last.yaw_deg);
        }
        if !translate {
            self.last = Some(now);
            return;
        }
        self.offset = self.moved(delta, 0.5 * (last.yaw_deg + now.yaw_deg), cfg);
        self.last = Some(now);
    }

    /// The offset now: the integrated one plus the motion since the last sample, extrapolated
    /// from the latest readings (see [`SensorState::predicted_counts`]).
    pub fn predicted(&self, now: Instant, s: &SensorState, cfg: &CartoConfig) -> CellOffset {
        let (Some(last), Some(counts), Some(yaw)) =
            (self.last, s.predicted_counts(now, cfg), s.predicted_yaw(now, cfg))
        else {
            return self.offset;
        };
        let delta = delta_counts(&counts, &last.counts);
        self.moved(delta, 0.5 * (last.yaw_deg + yaw), cfg)
    }

    /// The offset after a body displacement of `delta` wheel counts made at heading `yaw_deg`.
    fn moved(&self, delta: [f64; 4], yaw_deg: f64, cfg: &CartoConfig) -> CellOffset {
        let (fwd, left) = Odometry::body_delta(delta, cfg);
        let err = self.frame_deg.map_or(0.0, |f| yaw_deg - f);
        let (sin, cos) = err.to_radians().sin_cos();
        CellOffset {
            along_m: self.offset.along_m + fwd * cos - left * sin,
            left_m: self.offset.left_m + fwd * sin + left * cos,
        }
    }
}

fn delta_counts(counts: &[f64; 4], baseline: &[i32; 4]) -> [f64; 4] {
    core::array::from_fn(|i| counts[i] - f64::from(baseline[i]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::SensorEvent;

    fn feed(s: &mut SensorState, ms: u64, counts: [i32; 4], cw_deg: f64) {
        let at = Instant::from_millis(ms);
        s.ingest(at, SensorEvent::Heading { cw_deg });
        for (wheel, count) in counts.into_iter().enumerate() {
            s.ingest(at, SensorEvent::Encoder { wheel, count });
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-3
    }

    #[test]
    fn body_delta_separates_forward_strafe_and_rotation() {
        let cfg = CartoConfig::default();
        let m = cfg.encoder_counts_per_metre();
        let (f, l) = Odometry::body_delta([m; 4], &cfg);
        assert!(close(f, 1.0) && close(l, 0.0));
        let (f, l) = Odometry::body_delta([-m, m, m, -m], &cfg);
        assert!(close(f, 0.0) && close(l, 1.0), "strafe left: {f} {l}");
        let (f, l) = Odometry::body_delta([-m, m, -m, m], &cfg);
        assert!(close(f, 0.0) && close(l, 0.0), "rotation on the spot moves nothing: {f} {l}");
    }

    #[test]
    fn left_turn_rotates_the_offset_into_the_new_heading() {
        let mut o = Odometry { offset: CellOffset { along_m: 0.02, left_m: 0.01 }, ..Default::default() };
        o.set_frame(0.0);
        o.set_frame(90.0); // turned left: old left is now ahead, old ahead is now right
        assert!(close(o.offset().along_m, 0.01) && close(o.offset().left_m, -0.02), "{:?}", o.offset());
        o.set_frame(0.0); // and back
        assert!(close(o.offset().along_m, 0.02) && close(o.offset().left_m, 0.01), "{:?}", o.offset());
    }

    #[test]
    fn heading_error_turns_forward_travel_into_lateral_offset() {
        let cfg = CartoConfig::default();
        let mut s = SensorState::default();
        let mut o = Odometry::default();
        feed(&mut s, 0, [0; 4], 0.0);
        o.update(&s, &cfg);
        o.set_frame(0.0);
        // 10° counter-clockwise (NavX 350° clockwise) while rolling 0.5 m
        let c = (0.5 * cfg.encoder_counts_per_metre()).round() as i32;
        feed(&mut s, 100, [0; 4], 350.0);
        o.update(&s, &cfg);
        feed(&mut s, 300, [c; 4], 350.0);
        o.update(&s, &cfg);
        let off = o.offset();
        let want = 0.5 * 10f64.to_radians().sin();
        assert!((off.left_m - want).abs() < 0.002, "{off:?} want left {want}");
        assert!((off.along_m - 0.5 * 10f64.to_radians().cos()).abs() < 0.002, "{off:?}");
    }

    #[test]
    fn integrates_once_all_four_wheels_reported_and_advance_moves_the_origin() {
        let cfg = CartoConfig::default();
        let mut s = SensorState::default();
        let mut o = Odometry::default();
        feed(&mut s, 0, [0; 4], 0.0);
        o.update(&s, &cfg);
        // only two wheels report: nothing is integrated yet
        s.ingest(Instant::from_millis(200), SensorEvent::Encoder { wheel: 0, count: 253 });
        s.ingest(Instant::from_millis(200), SensorEvent::Encoder { wheel: 1, count: 253 });
        o.update(&s, &cfg);
        assert_eq!(o.offset(), CellOffset::default());
        s.ingest(Instant::from_millis(200), SensorEvent::Encoder { wheel: 2, count: 253 });
        s.ingest(Instant::from_millis(200), SensorEvent::Encoder { wheel: 3, count: 253 });
        o.update(&s, &cfg);
        o.update(&s, &cfg); // the same sample twice counts once
        let along = o.offset().along_m;
        assert!((along - 253.0 / cfg.encoder_counts_per_metre()).abs() < 1e-9, "{along}");
        o.advance(0.30);
        assert!((o.offset().along_m - (along - 0.30)).abs() < 1e-12);
        o.reset();
        assert_eq!(o.offset(), CellOffset::default());
    }

    #[test]
    fn a_counter_reset_rebaselines_without_moving_the_offset() {
        let cfg = CartoConfig::default();
        let mut s = SensorState::default();
        let mut o = Odometry::default();
        feed(&mut s, 0, [100_000; 4], 0.0);
        o.update(&s, &cfg);
        feed(&mut s, 200, [100_010; 4], 0.0);
        o.update(&s, &cfg);
        let before = o.offset();
        feed(&mut s, 400, [0; 4], 0.0); // the board restarted its counters
        o.update(&s, &cfg);
        assert_eq!(o.offset(), before);
        feed(&mut s, 600, [84; 4], 0.0); // and counting resumes from there
        o.update(&s, &cfg);
        assert!((o.offset().along_m - before.along_m - 84.0 / cfg.encoder_counts_per_metre()).abs() < 1e-9);
    }
}
