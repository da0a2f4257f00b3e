//! Stalled FORWARDs: wheels that turn while the body stands still.
//!
//! Pushed against something the sonar did not report (the side of a slanted box, a leg beside
//! the path), the body stops but the wheels keep turning on the floor, and the encoders count a
//! move that did not happen: Carto would believe, and tell Cute, that the robot reached a cell it
//! never entered, and every later move would start from the wrong cell. The sonar keeps
//! measuring while a FORWARD runs (10 frames a second). Driving towards whatever answers, the
//! range falls about as fast as the wheels advance: by cos 7.5° ≈ 0.99 of it or more for a leg
//! or a corner anywhere in the 15° cone, by 0.94–1.05 of it for a flat surface up to the
//! twin's 22.5° incidence limit. A body that does not move hears the same range. Both assume a
//! target that stands still: one that moves with the robot (a person walking ahead) holds the
//! range too, and is taken for a stall.
//!
//! Rule ([`StallWatch`]): the echoes heard since the FORWARD started, each paired with how far
//! the wheels had driven when the sonar measured, are fitted with a line `range = a + b · driven`
//! over the latest ones that span at least the span below of driving. The FORWARD is
//! stalled when
//! - the range changed by less than [`STALL_MAX_PROGRESS`] (0.3) of what the wheels drove
//!   (`|b| < 0.3`: a range that grows slowly is a body pushed back, one that grows faster is
//!   something moving away),
//! - every echo of the span lies within a tolerance of the line: three sonar σ
//!   plus the error the moment of a reading adds while driving (the frame carries the sonar's
//!   latest result, up to one cycle old, and Carto takes half a cycle,
//!   [`Sonar::lag`](crate::config::Sonar::lag): ± the lag times the cruise speed, 1.1 cm for the
//!   default robot). One surface answered them all: a new surface coming into the cone, or one
//!   leaving it, makes a step that does not fit a line, and
//! - the span holds at least [`STALL_MIN_ECHOES`] echoes in a row (a reading without echo
//!   starts again), none more than half the span of driving after the one before: two echoes
//!   far apart from two surfaces fit any line.
//!
//! The span is 15 cm, or twelve sonar σ when that is longer (24 cm with `noisy`'s 2 cm sonar):
//! over 8 cm the ±1.1 cm of timing alone can make a flat stretch of three readings in a robot
//! that drives. A stall in the last span of a FORWARD is not
//! seen: the wheels finish first.
//!
//! What the body really drove is read off the sonar: the line is extended back over earlier
//! echoes that still fit it, and from the first of them (the wheels are trusted up to there) the
//! body went on by what the range fell from that echo to the line now. The pilot then stops,
//! sets the odometry to that, answers `SET_OBSTACLE_POSITION` for the cell ahead and, as after
//! the bumper, drives back to the centre of the
//! cell it started from. The wheels that coast after the stop, the body still held, still count
//! as motion (about 3 cm), as after the bumper.

/// The smallest span of driving the rule looks at, metres.
pub const STALL_SPAN_MIN_M: f64 = 0.15;
/// The range may fall by at most this share of what the wheels drove over the span.
pub const STALL_MAX_PROGRESS: f64 = 0.3;
/// The fewest echoes a span needs.
pub const STALL_MIN_ECHOES: usize = 4;

/// One echo heard during a FORWARD.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    /// Metres the wheels had driven since the FORWARD started.
    driven_m: f64,
    /// The range, metres.
    range_m: f64,
}

/// The stall rule of the module docs, fed one echo at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct StallWatch {
    /// The span of driving the rule fits its line over, metres.
    span_m: f64,
    /// How far an echo may lie from the line, metres.
    tolerance_m: f64,
    samples: Vec<Sample>,
}

/// A stall: how far the body really drove since the FORWARD started, by the sonar, and what the
/// wheels said.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stall {
    /// By the sonar: the wheels up to the first echo of the fitted line, then the range's fall.
    pub driven_m: f64,
    /// By the wheels.
    pub wheels_m: f64,
}

impl StallWatch {
    /// A watch for a sonar whose readings have standard deviation `sonar_sigma_m`, read while
    /// driving with a timing error of up to `timing_m` of travel (module docs).
    pub fn new(sonar_sigma_m: f64, timing_m: f64) -> StallWatch {
        let sigma = sonar_sigma_m.max(0.0);
        StallWatch {
            span_m: STALL_SPAN_MIN_M.max(12.0 * sigma),
            tolerance_m: 3.0 * sigma + timing_m.max(0.0),
            samples: Vec::new(),
        }
    }

    /// A new FORWARD, or a reading without echo (the next echo may come from another surface):
    /// forget the echoes so far.
    pub fn restart(&mut self) {
        self.samples.clear();
    }

    /// An echo `range_m` heard when the wheels had driven `driven_m` since the FORWARD started;
    /// the stall, if this echo shows one. Non-finite values are ignored.
    pub fn push(&mut self, driven_m: f64, range_m: f64) -> Option<Stall> {
        if !(driven_m.is_finite() && range_m.is_finite()) {
            return None;
        }
        // bounded: a FORWARD of one cell hears a few dozen echoes; keep the newest
        if self.samples.len() >= 256 {
            self.samples.remove(0);
        }
        self.samples.push(Sample { driven_m, range_m });
        let last = *self.samples.last()?;
        // the latest echoes that span at least `span_m` of driving
        let first = self.samples.iter().rposition(|s| last.driven_m - s.driven_m >= self.span_m)?;
        let window = &self.samples[first..];
        let dense = window.windows(2).all(|p| p[1].driven_m - p[0].driven_m <= 0.5 * self.span_m);
        if window.len() < STALL_MIN_ECHOES || !dense {
            return None;
        }
        let (a, b) = fit_line(window)?;
        let fits = |s: &Sample| (s.range_m - (a + b * s.driven_m)).abs() <= self.tolerance_m;
        // a range that grows is something moving away, not a body that stands
        if b.abs() >= STALL_MAX_PROGRESS || !window.iter().all(fits) {
            return None;
        }
        // the wheels are trusted up to the first echo that still fits the line; from there the
        // body went on by what the range fell, measured there and on the line now
        let mut start = first;
        while start > 0 && fits(&self.samples[start - 1]) {
            start -= 1;
        }
        let from = self.samples[start];
        let fell = from.range_m - (a + b * last.driven_m);
        let driven_m = (from.driven_m + fell).clamp(from.driven_m, last.driven_m.max(from.driven_m));
        Some(Stall { driven_m, wheels_m: last.driven_m })
    }
}

/// Least-squares line `range = a + b · driven` through the samples; `None` when the driving does
/// not vary.
fn fit_line(samples: &[Sample]) -> Option<(f64, f64)> {
    let n = samples.len() as f64;
    let mean_x = samples.iter().map(|s| s.driven_m).sum::<f64>() / n;
    let mean_y = samples.iter().map(|s| s.range_m).sum::<f64>() / n;
    let sxx: f64 = samples.iter().map(|s| (s.driven_m - mean_x).powi(2)).sum();
    let sxy: f64 = samples.iter().map(|s| (s.driven_m - mean_x) * (s.range_m - mean_y)).sum();
    if sxx <= f64::EPSILON {
        return None;
    }
    let b = sxy / sxx;
    Some((mean_y - b * mean_x, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default robot's: 30 ms of lag at the 0.377 m/s cruise.
    const TIMING: f64 = 0.0113;

    /// Feeds echoes every `step_m` of wheel travel up to `to_m`; `range(driven)` gives each.
    fn drive(w: &mut StallWatch, to_m: f64, step_m: f64, range: impl Fn(f64) -> f64) -> Option<Stall> {
        let mut d = 0.0;
        while d <= to_m + 1e-9 {
            if let Some(s) = w.push(d, range(d)) {
                return Some(s);
            }
            d += step_m;
        }
        None
    }

    #[test]
    fn a_robot_that_drives_towards_a_wall_is_not_stalled() {
        let mut w = StallWatch::new(0.003, TIMING);
        assert_eq!(drive(&mut w, 0.45, 0.035, |d| 1.2 - d), None);
        // seen across the cone's edge (cos 7.5°) too
        w.restart();
        assert_eq!(drive(&mut w, 0.45, 0.035, |d| 1.2 - 0.99 * d), None);
    }

    #[test]
    fn a_range_that_holds_while_the_wheels_turn_is_a_stall_from_where_it_began() {
        let mut w = StallWatch::new(0.003, TIMING);
        // the body drives 15 cm, then stops against something beside it; the wheels go on
        let s = drive(&mut w, 0.45, 0.035, |d| 1.68 - d.min(0.15)).expect("a stall");
        assert!(s.wheels_m <= 0.15 + w.span_m + 0.035, "found within a span of the stop: {s:?}");
        assert!((s.driven_m - 0.15).abs() <= 0.01, "the body drove 15 cm, not {:.3} m", s.driven_m);
    }

    #[test]
    fn a_new_surface_coming_into_the_cone_is_not_a_stall() {
        let mut w = StallWatch::new(0.003, TIMING);
        // a leg at 0.8 m leaves the cone after 20 cm and the wall behind it answers at the same
        // range the leg had at the start: the range steps up, it does not hold
        let range = |d: f64| if d < 0.2 { 0.8 - d } else { 1.25 - d };
        assert_eq!(drive(&mut w, 0.45, 0.035, range), None);
    }

    #[test]
    fn a_robot_that_crawls_is_stalled_below_a_third_of_the_wheels_speed() {
        // 20 % of the wheels' travel: stalled; 40 %: not
        let mut w = StallWatch::new(0.003, TIMING);
        let s = drive(&mut w, 0.45, 0.02, |d| 1.0 - 0.2 * d).expect("a stall");
        assert!((s.driven_m - 0.2 * s.wheels_m).abs() < 0.01, "{s:?}");
        w.restart();
        assert_eq!(drive(&mut w, 0.45, 0.02, |d| 1.0 - 0.4 * d), None);
    }

    #[test]
    fn the_timing_of_readings_while_driving_is_not_a_stall() {
        // generated warehouse seed 2: the range falls with the wheels but two readings 3.6 cm
        // apart read the same; over a 15 cm span the line still falls
        let samples = [
            (0.012, 3.2412),
            (0.004, 3.2278),
            (0.039, 3.2147),
            (0.059, 3.1747),
            (0.095, 3.1362),
            (0.130, 3.1098),
            (0.166, 3.0674),
            (0.203, 3.0266),
            (0.240, 3.0016),
            (0.276, 3.0019),
            (0.305, 2.9693),
            (0.340, 2.9350),
        ];
        let mut w = StallWatch::new(0.003, TIMING);
        for (d, r) in samples {
            assert_eq!(w.push(d, r), None, "stalled at {d} m");
        }
    }

    #[test]
    fn echoes_far_apart_are_not_a_stall() {
        let mut w = StallWatch::new(0.003, TIMING);
        // office seed 26: an echo at 9 cm of driving, then none until 41 cm, where another
        // surface answers twice; three points fit a flat line, but nothing was seen in between
        assert_eq!(w.push(0.001, 2.855), None);
        assert_eq!(w.push(0.092, 1.903), None);
        assert_eq!(w.push(0.415, 2.075), None);
        assert_eq!(w.push(0.429, 2.066), None);
        assert_eq!(w.push(0.44, 2.07), None);
    }

    #[test]
    fn a_range_that_grows_fast_is_not_a_stall_and_a_slow_one_never_drives_backwards() {
        // something walking away ahead at half the robot's speed
        let mut w = StallWatch::new(0.003, TIMING);
        assert_eq!(drive(&mut w, 0.45, 0.02, |d| 1.0 + 0.5 * d), None);
        // a body pushed back a little while its wheels drive: a stall, and the sonar's figure
        // never puts it behind where the wheels were last trusted
        w.restart();
        let s = drive(&mut w, 0.45, 0.02, |d| 1.0 + 0.2 * d).expect("a stall");
        assert_eq!(s.driven_m, 0.0, "{s:?}");
    }

    #[test]
    fn a_noisy_sonar_needs_a_longer_span() {
        let w = StallWatch::new(0.02, TIMING);
        assert!((w.span_m - 0.24).abs() < 1e-9);
        assert!((w.tolerance_m - 0.0713).abs() < 1e-9);
        assert!((StallWatch::new(0.003, TIMING).span_m - STALL_SPAN_MIN_M).abs() < 1e-9);
    }

    #[test]
    fn bad_numbers_are_ignored() {
        let mut w = StallWatch::new(0.003, TIMING);
        assert_eq!(w.push(f64::NAN, 1.0), None);
        assert_eq!(w.push(0.0, f64::INFINITY), None);
        assert!(w.samples.is_empty());
    }
}
