//! The run report: what happened, how well the room was mapped, and whether the scenario's
//! expectations hold.
//!
//! * **coverage** — of the scored set (the cells this robot can reach keeping its clearance,
//!   [`crate::scored`]), the fraction Cute's map shows as free;
//! * **map accuracy** — of the cells Cute's map has classified (free or obstacle), tight cells
//!   left out, the fraction that agree with the ground truth; cells Cute never learnt about do
//!   not count here (they count against coverage);
//! * **touches** — every contact between the robot and anything (`collisions`), each with its
//!   severity; **hard collisions** among them ([`crate::touches`]);
//! * **belief error** — Carto's own belief against the true body ([`crate::belief`]); Cute's
//!   cell against the truth stays as information ([`crate::localisation`]).

use std::fmt::Write as _;

use serde::Serialize;

use crate::belief::BeliefReport;
use crate::localisation::Localisation;
use crate::scenario::Expectations;
use crate::touches::TouchReport;
use crate::world::Unphysical;

/// Traffic on one direction of one link.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct DirectionStats {
    /// Bytes the sender wrote.
    pub bytes: u64,
    /// Frames the receiver decoded (after any injected faults).
    pub frames: u64,
    /// Frames the receiver rejected (bad checksum, bad length, framing).
    pub errors: u64,
}

/// Traffic on one link, both directions.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct LinkStats {
    /// `motor`, `sensor` or `gui`.
    pub name: String,
    /// From Carto to the board (or from Cute to Carto for `gui`).
    pub outbound: DirectionStats,
    /// From the board to Carto (or from Carto to Cute for `gui`).
    pub inbound: DirectionStats,
}

/// One checked expectation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// The expectation's name in the scenario file.
    pub name: String,
    /// What the scenario asked for.
    pub expected: String,
    /// What the run achieved.
    pub actual: String,
    /// Whether it holds.
    pub pass: bool,
}

pub use crate::scored::MapScore;

mod contact;

pub use contact::{ContactCause, FirstContact, HEARD_NEAR_M, Heard};

/// Everything a run reports; also written as `report.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// Scenario name.
    pub scenario: String,
    /// Seed of the run.
    pub seed: u64,
    /// Carto was given every surface of the room beforehand (`--known-room`): a ceiling for
    /// perfect perception, not what the robot's sensors achieve. Written only when set.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub known_room: bool,
    /// Carto was given every point the sonar heard, where it really lies, never forgotten
    /// (`--known-echoes`): a ceiling for a perfect memory of the echoes. Written only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub known_echoes: bool,
    /// Simulated time at the end, seconds.
    pub sim_time_s: f64,
    /// Wall-clock time the run took, seconds (not part of the determinism hash).
    pub wall_time_s: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// Physics steps taken.
    pub steps: u64,
    /// Whether every mission step was carried out.
    pub mission_complete: bool,
    /// Sim time when the mission's last step completed, seconds.
    pub mission_time_s: Option<f64>,
    /// Steps of the mission that failed (e.g. "GoTo(3, 4): no path").
    pub mission_errors: Vec<String>,
    /// Grid size (rows, columns).
    pub grid: (usize, usize),
    /// Map score against the truth.
    pub map: MapScore,
    /// `map.coverage()`.
    pub coverage: f64,
    /// `map.accuracy()`.
    pub map_accuracy: f64,
    /// Moves Cute sent (cartography commands and trajectory commands).
    pub moves: u64,
    /// Collisions counted by the physics: every touch ([`Report::touches`]).
    pub collisions: u32,
    /// Every touch with its severity.
    pub touches: TouchReport,
    /// Carto's belief against the truth: the localisation error a run is judged by.
    pub belief: BeliefReport,
    /// The first contact, if there was one.
    pub first_contact: Option<FirstContact>,
    /// Steps after which the body moved faster than its wheels can drive it
    /// ([`SimWorld::unphysical`](crate::world::SimWorld::unphysical)): when there are any, what
    /// the run did after `first_at_s` is not physical.
    pub unphysical: Unphysical,
    /// The robot's final pose: x, y (m), heading (deg, CCW from +x).
    pub final_pose: (f64, f64, f64),
    /// The grid cell the robot ends in.
    pub final_cell: Option<(usize, usize)>,
    /// What Cute believes is the robot's cell at the end.
    pub cute_cell: (u8, u8),
    /// How far Cute's belief (the centre of its cell) strayed from the truth at the end of each
    /// move: information, since Carto may stop off a centre on purpose.
    pub localisation: Localisation,
    /// Traffic per link.
    pub links: Vec<LinkStats>,
    /// Faults injected by the fault injectors (bit flips, drops).
    pub faults_injected: u64,
    /// Times Cute reconnected to Carto.
    pub reconnects: u64,
    /// SHA-256 of every byte on every link with its time: equal hashes = identical runs. Empty in
    /// a report taken before the run is over.
    pub link_log_sha256: String,
    /// The expectations, checked.
    pub checks: Vec<Check>,
    /// Whether every check passed.
    pub passed: bool,
}

impl Report {
    /// Checks `expect` against this report and fills `checks` and `passed`. A run that left
    /// physics (see [`Report::unphysical`]) also gets a failing `physical` check: whatever it
    /// did after that is not what the robot would do, so it cannot pass.
    pub fn check(&mut self, expect: &Expectations) {
        let mut checks = Vec::new();
        if let Some(min) = expect.coverage_min {
            checks.push(Check {
                name: "coverage_min".into(),
                expected: format!(">= {:.1}%", min * 100.0),
                actual: format!(
                    "{:.1}% ({}/{})",
                    self.coverage * 100.0,
                    self.map.scored_known_free,
                    self.map.scored
                ),
                pass: self.coverage + 1e-9 >= min,
            });
        }
        if let Some(min) = expect.map_accuracy_min {
            checks.push(Check {
                name: "map_accuracy_min".into(),
                expected: format!(">= {:.1}%", min * 100.0),
                actual: format!(
                    "{:.1}% ({}/{})",
                    self.map_accuracy * 100.0,
                    self.map.correct,
                    self.map.classified
                ),
                pass: self.map_accuracy + 1e-9 >= min,
            });
        }
        if let Some(max) = expect.collisions_max {
            checks.push(Check {
                name: "collisions_max".into(),
                expected: format!("<= {max}"),
                actual: self.collisions.to_string(),
                pass: self.collisions <= max,
            });
        }
        let t = &self.touches;
        if let Some(max) = expect.touches_max {
            checks.push(Check {
                name: "touches_max".into(),
                expected: format!("<= {max}"),
                actual: t.count.to_string(),
                pass: t.count <= max,
            });
        }
        if let Some(max) = expect.hard_collisions_max {
            checks.push(Check {
                name: "hard_collisions_max".into(),
                expected: format!("<= {max}"),
                actual: format!(
                    "{} (fastest approach {:.2} m/s, largest push {:.3} m)",
                    t.hard, t.fastest_approach_m_s, t.largest_push_m
                ),
                pass: t.hard <= max,
            });
        }
        if let Some(max) = expect.touches_per_100_moves_max {
            checks.push(Check {
                name: "touches_per_100_moves_max".into(),
                expected: format!("<= {max:.2}"),
                actual: format!("{:.2} ({} in {} moves)", t.per_100_moves, t.count, self.moves),
                pass: t.per_100_moves <= max + 1e-9,
            });
        }
        if let Some(limit) = expect.finish_within_s {
            let actual = match self.mission_time_s {
                Some(t) => format!("{t:.1} s"),
                None => "mission not finished".into(),
            };
            checks.push(Check {
                name: "finish_within_s".into(),
                expected: format!("<= {limit:.1} s"),
                actual,
                pass: self.mission_complete && self.mission_time_s.is_some_and(|t| t <= limit),
            });
        }
        if let Some((row, col)) = expect.reached {
            let actual = match self.final_cell {
                Some((r, c)) => format!("({r}, {c})"),
                None => "off the grid".into(),
            };
            checks.push(Check {
                name: "reached".into(),
                expected: format!("({row}, {col})"),
                actual,
                pass: self.final_cell == Some((row as usize, col as usize)),
            });
        }
        let loc = &self.localisation;
        if let Some(max) = expect.position_error_max_m {
            checks.push(Check {
                name: "position_error_max_m".into(),
                expected: format!("<= {max:.3} m"),
                actual: format!("{:.3} m at {:.1} s", loc.position_error_max_m, loc.position_error_at_s),
                pass: loc.position_error_max_m <= max,
            });
        }
        if let Some(max) = expect.heading_error_max_deg {
            checks.push(Check {
                name: "heading_error_max_deg".into(),
                expected: format!("<= {max:.1} deg"),
                actual: format!("{:.1} deg at {:.1} s", loc.heading_error_max_deg, loc.heading_error_at_s),
                pass: loc.heading_error_max_deg <= max,
            });
        }
        let b = &self.belief;
        if let Some(max) = expect.belief_error_max_m {
            checks.push(Check {
                name: "belief_error_max_m".into(),
                expected: format!("<= {max:.3} m"),
                actual: format!("{:.3} m at {:.1} s", b.error_max_m, b.error_max_at_s),
                pass: b.error_max_m <= max,
            });
        }
        if let Some(max) = expect.belief_error_p95_max_m {
            checks.push(Check {
                name: "belief_error_p95_max_m".into(),
                expected: format!("<= {max:.3} m"),
                actual: format!("{:.3} m over {} samples", b.error_p95_m, b.samples),
                pass: b.error_p95_m <= max,
            });
        }
        if let Some(max) = expect.belief_heading_error_max_deg {
            checks.push(Check {
                name: "belief_heading_error_max_deg".into(),
                expected: format!("<= {max:.1} deg"),
                actual: format!("{:.1} deg at {:.1} s", b.heading_error_max_deg, b.heading_error_max_at_s),
                pass: b.heading_error_max_deg <= max,
            });
        }
        if let Some(want) = expect.believed_cell_true {
            let truth = self.final_cell.map(|(r, c)| (r as u8, c as u8));
            let same =
                truth == Some(self.cute_cell) && self.final_cell.is_some_and(|(r, c)| r < 256 && c < 256);
            checks.push(Check {
                name: "believed_cell_true".into(),
                expected: format!("{want}"),
                actual: format!("{same} (Cute {:?}, true {:?})", self.cute_cell, self.final_cell),
                pass: same == want,
            });
        }
        if let Some(t) = self.unphysical.first_at_s {
            checks.push(Check {
                name: "physical".into(),
                expected: "sound".into(),
                actual: format!("not from {t:.3} s (the body moved faster than its wheels drive it)"),
                pass: false,
            });
        }
        self.passed = checks.iter().all(|c| c.pass) && self.mission_errors.is_empty();
        self.checks = checks;
    }

    /// The human-readable report printed by `explobot run`.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "scenario        {} (seed {})", self.scenario, self.seed);
        if self.known_room {
            let _ = writeln!(
                s,
                "known room      Carto was given every surface of the room (--known-room): a ceiling \
                 for perfect perception, not what the sonar achieves"
            );
        }
        if self.known_echoes {
            let _ = writeln!(
                s,
                "known echoes    Carto was given every point the sonar heard, where it lies (--known-echoes): \
                 a ceiling for a perfect memory of the echoes, not what the robot achieves"
            );
        }
        let _ = writeln!(
            s,
            "time            {:.1} s simulated in {:.2} s wall ({:.0}x real time, {} steps)",
            self.sim_time_s, self.wall_time_s, self.real_time_factor, self.steps
        );
        let mission = match (self.mission_complete, self.mission_time_s) {
            (true, Some(t)) => format!("complete at {t:.1} s"),
            _ => "NOT complete".to_string(),
        };
        let _ =
            writeln!(s, "mission         {mission}, {} moves, {} reconnects", self.moves, self.reconnects);
        for e in &self.mission_errors {
            let _ = writeln!(s, "  error         {e}");
        }
        let m = &self.map;
        let marked = match m.scored_marked_obstacle {
            0 => String::new(),
            n => format!(" ({n} marked obstacle)"),
        };
        let tight = match m.tight {
            0 => String::new(),
            n => format!(
                "; {n} tight (reachable only closer than {:.0} cm: not scored; Cute has {} free, {} obstacle)",
                m.clearance_m * 100.0,
                m.tight_known_free,
                m.tight_marked_obstacle
            ),
        };
        let _ = writeln!(
            s,
            "map             {}x{} grid, coverage {:.1}% of {} scored cells{marked}, accuracy {:.1}% of {} classified{tight}{}",
            self.grid.0,
            self.grid.1,
            self.coverage * 100.0,
            m.scored,
            self.map_accuracy * 100.0,
            m.classified,
            if m.exact {
                ""
            } else {
                " (room too large for the clearance lattice: scored on every reachable cell)"
            }
        );
        let cell = self.final_cell.map_or("off grid".to_string(), |(r, c)| format!("cell ({r}, {c})"));
        let _ = writeln!(
            s,
            "robot           x {:.3} m, y {:.3} m, heading {:.1} deg, {cell}; Cute believes ({}, {})",
            self.final_pose.0, self.final_pose.1, self.final_pose.2, self.cute_cell.0, self.cute_cell.1
        );
        let b = &self.belief;
        let _ = writeln!(
            s,
            "belief          Carto's belief against the truth over {} samples: error max {:.3} m (at {:.1} s), p95 {:.3} m; heading error max {:.1} deg (at {:.1} s); stops up to {:.3} m off Carto's cell centre",
            b.samples,
            b.error_max_m,
            b.error_max_at_s,
            b.error_p95_m,
            b.heading_error_max_deg,
            b.heading_error_max_at_s,
            b.stop_offset_max_m
        );
        if b.after_contact > 0 {
            let _ = writeln!(
                s,
                "after contacts  belief at the third MOVE_DONE after each of {} contacts: {} over {:.0} cm, largest {:.3} m",
                b.after_contact,
                b.after_contact_unrecovered,
                100.0 * crate::belief::RECOVERED_WITHIN_M,
                b.after_contact_max_m
            );
        }
        let _ = writeln!(
            s,
            "Cute's cell     at the end of {} moves: its centre up to {:.3} m from the robot (at {:.1} s), heading up to {:.1} deg off (at {:.1} s)",
            self.localisation.samples,
            self.localisation.position_error_max_m,
            self.localisation.position_error_at_s,
            self.localisation.heading_error_max_deg,
            self.localisation.heading_error_at_s
        );
        let t = &self.touches;
        let _ = writeln!(
            s,
            "touches         {} ({:.2} per 100 moves), {} hard (began at 0.10 m/s or more, or pushed 2 cm or more), {} unseen by Carto; fastest approach {:.2} m/s, largest push {:.3} m",
            t.count, t.per_100_moves, t.hard, t.unseen, t.fastest_approach_m_s, t.largest_push_m
        );
        let _ = writeln!(s, "physics         {}", self.unphysical.describe());
        if let Some(c) = &self.first_contact {
            let cell = c.cell.map_or("off grid".to_string(), |(r, col)| format!("cell ({r}, {col})"));
            let belief = c.belief_error_m.map_or(String::new(), |e| format!(", Carto's belief {e:.3} m off"));
            let _ = writeln!(
                s,
                "first contact   {:.1} s, {cell}, {}: {} ({:.3} m off the cell's centre{belief}){}{}{}",
                c.t_s,
                c.carto_activity,
                c.cause.describe(),
                c.off_centre_m,
                c.touched.map_or(String::new(), |t| format!("; touched: {}", t.describe())),
                c.touched_heard.map_or(String::new(), |h| format!(", {}", h.describe())),
                c.touched_held_m
                    .map_or(String::new(), |d| format!("; Carto's nearest echo point {d:.2} m from there"))
            );
        }
        let _ = writeln!(s, "links           out: bytes/frames/errors   in: bytes/frames/errors");
        for l in &self.links {
            let _ = writeln!(
                s,
                "  {:<13} {:>9}/{:>7}/{:<5}   {:>9}/{:>7}/{}",
                l.name,
                l.outbound.bytes,
                l.outbound.frames,
                l.outbound.errors,
                l.inbound.bytes,
                l.inbound.frames,
                l.inbound.errors
            );
        }
        let _ = writeln!(s, "faults injected {}", self.faults_injected);
        let _ = writeln!(s, "link log        sha256 {}", self.link_log_sha256);
        for c in &self.checks {
            let verdict = if c.pass { "pass" } else { "FAIL" };
            let _ = writeln!(s, "  [{verdict}] {:<17} expected {:<12} got {}", c.name, c.expected, c.actual);
        }
        let _ = writeln!(s, "result          {}", if self.passed { "PASS" } else { "FAIL" });
        s
    }

    /// A summary with no wall-clock figures: equal for equal runs on any machine (the scenario
    /// suite snapshots it).
    pub fn summary_text(&self) -> String {
        let r = self;
        let mut s = String::new();
        let _ = writeln!(s, "scenario {} seed {}", r.scenario, r.seed);
        let _ = writeln!(
            s,
            "sim time {:.2} s, mission complete {} at {:?} s",
            r.sim_time_s,
            r.mission_complete,
            r.mission_time_s.map(|t| (t * 100.0).round() / 100.0)
        );
        let _ = writeln!(s, "mission errors {:?}", r.mission_errors);
        let _ = writeln!(s, "moves {}, reconnects {}, collisions {}", r.moves, r.reconnects, r.collisions);
        if r.unphysical.steps > 0 {
            let _ = writeln!(s, "physics {}", r.unphysical.describe());
        }
        let _ = writeln!(
            s,
            "coverage {}/{} scored ({} tight), accuracy {}/{}",
            r.map.scored_known_free, r.map.scored, r.map.tight, r.map.correct, r.map.classified
        );
        let _ = writeln!(
            s,
            "touches {}, hard {}, unseen {}; belief error max {:.3} m, p95 {:.3} m, heading max {:.1} deg",
            r.touches.count,
            r.touches.hard,
            r.touches.unseen,
            r.belief.error_max_m,
            r.belief.error_p95_m,
            r.belief.heading_error_max_deg
        );
        let _ = writeln!(s, "final cell {:?}, Cute believes {:?}", r.final_cell, r.cute_cell);
        let _ = writeln!(
            s,
            "localisation {} samples, position error max {:.3} m, heading error max {:.1} deg",
            r.localisation.samples, r.localisation.position_error_max_m, r.localisation.heading_error_max_deg
        );
        let _ = writeln!(
            s,
            "final pose x {:.2} m, y {:.2} m, heading {:.0} deg",
            r.final_pose.0, r.final_pose.1, r.final_pose.2
        );
        for l in &r.links {
            let _ = writeln!(
                s,
                "link {}: out {} B / {} frames / {} errors, in {} B / {} frames / {} errors",
                l.name,
                l.outbound.bytes,
                l.outbound.frames,
                l.outbound.errors,
                l.inbound.bytes,
                l.inbound.frames,
                l.inbound.errors
            );
        }
        let _ = writeln!(s, "faults injected {}", r.faults_injected);
        for c in &r.checks {
            let _ = writeln!(
                s,
                "check {} expected {} got {}: {}",
                c.name,
                c.expected,
                c.actual,
                if c.pass { "pass" } else { "FAIL" }
            );
        }
        s
    }
}

#[cfg(test)]
mod tests;
