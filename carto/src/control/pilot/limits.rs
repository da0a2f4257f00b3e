//! The geometry and the limits the pilot's safety checks share (`pilot/safety.rs` sequences
//! the checks, `pilot/echoes.rs` asks the echo points), taken once from [`CartoConfig`].

use crate::CartoConfig;
use crate::slide::SlideGeometry;

/// A look past a turn keeps its readings within its own angle plus this, degrees (the look may
/// overshoot a little before it settles).
const LOOK_WINDOW_SLACK_DEG: f64 = 5.0;
/// The tracks a FORWARD tries beside the line through the centres are this far apart, metres.
pub(super) const ASIDE_STEP_M: f64 = 0.0025;

/// An echo heard while moving is kept this many sonar σ beyond its range.
pub(super) const FAR_SIGMAS: f64 = 3.0;

/// The geometry the checks need, from [`CartoConfig`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Safety {
    /// How far each way the scan before a FORWARD looks, degrees (0: no scan).
    pub(super) scan_deg: f64,
    pub(super) cell_m: f64,
    pub(super) mount_m: f64,
    pub(super) half_cone_deg: f64,
    pub(super) max_range_m: f64,
    pub(super) half_length_m: f64,
    pub(super) half_width_m: f64,
    pub(super) clearance_m: f64,
    /// The swept circle of a turn plus the clearance: no known echo may lie inside it.
    pub(super) turn_clear_m: f64,
    /// How far past a finished turn the robot turns on and back, listening, degrees (0: off).
    pub(super) look_past_deg: f64,
    /// How long before its frame arrives a reading was measured.
    pub(super) sonar_lag_s: f64,
    /// One reading's noise, metres.
    pub(super) sonar_sigma_m: f64,
    /// [`CartoConfig::drive_timing_m`].
    pub(super) drive_timing_m: f64,
    /// How far beside the line through the centres a FORWARD's track may lie, metres
    /// ([`Safety::stop_within_m`](crate::config::Safety::stop_within_m) less the lateral tolerance it ends within).
    pub(super) aside_max_m: f64,
    /// The geometry of local motion ([`crate::slide`]).
    pub(super) slide: SlideGeometry,
}

impl Safety {
    pub(super) fn new(cfg: &CartoConfig) -> Safety {
        // the body, the clearance, the band and the turning circle, worked out once
        let slide = SlideGeometry::from_config(cfg);
        Safety {
            scan_deg: cfg.safety.scan_deg.map_or(0.0, f64::abs),
            cell_m: slide.cell_m,
            mount_m: cfg.sonar.mount_m,
            half_cone_deg: 0.5 * cfg.sonar.cone_deg,
            max_range_m: cfg.sonar.max_m,
            half_length_m: slide.half_length_m,
            half_width_m: slide.half_width_m,
            clearance_m: slide.clearance_m,
            turn_clear_m: slide.turn_clear_m,
            look_past_deg: cfg.safety.look_past_turn_deg.map_or(0.0, f64::abs),
            sonar_lag_s: cfg.sonar.lag.as_secs_f64(),
            sonar_sigma_m: cfg.sonar.sigma_m,
            drive_timing_m: cfg.drive_timing_m(),
            aside_max_m: slide.band_m,
            slide,
        }
    }

    /// How far from the grid heading a reading taken while looking past a turn may be, degrees.
    pub(super) fn look_window_deg(&self) -> f64 {
        self.look_past_deg + LOOK_WINDOW_SLACK_DEG
    }

    /// The looks of a scan, as offsets from the grid heading (counter-clockwise degrees); a
    /// reading is taken after each but the last, which faces the grid heading again.
    pub(super) fn looks(&self) -> &'static [f64] {
        if self.scan_deg > 0.0 { &[1.0, -1.0, 0.0] } else { &[] }
    }
}
