//! The run's report, read from counters kept as the run went (nothing is decoded again).

use crate::oracle::Oracle;
use crate::record::hash_logs;
use crate::report::{DirectionStats, LinkStats, MapScore, Report};
use transport::TraceTotals;

use super::{Lockstep, fault_total};

impl Lockstep {
    /// The report of the run so far; `wall_time_s` is the caller's measurement.
    pub fn report(&self, wall_time_s: f64) -> Report {
        let scenario = &self.loaded.scenario;
        let map = MapScore::score(&self.truth, self.scored_set(), &self.known_cells());
        let moves = self.cute.cute().counters().moves_sent;
        let pose = self.twin.body().pose();
        let sim_time_s = self.now.as_secs_f64();
        let cute = self.cute.cute();
        let (cx, cy, _) = cute.robot();
        let links = self.link_stats();
        let faults_injected = self.cute.wrapper().fault_counts
            + self.cute.link().map_or(0, |l| fault_total(l.inner()))
            + self.carto.motor_link().map_or(0, |l| fault_total(l.inner()))
            + self.carto.sensor_link().map_or(0, |l| fault_total(l.inner()));
        let mut report = Report {
            scenario: scenario.name.clone(),
            seed: self.seed,
            known_room: self.loaded.oracle() == Oracle::Room,
            known_echoes: self.loaded.oracle() == Oracle::Echoes,
            sim_time_s,
            wall_time_s,
            real_time_factor: sim_time_s / wall_time_s.max(1e-9),
            steps: self.steps,
            mission_complete: self.operator.finished_at.is_some(),
            mission_time_s: self.operator.finished_at.map(|t| t.as_secs_f64()),
            mission_errors: self.operator.errors.clone(),
            grid: (self.truth.rows, self.truth.cols),
            coverage: map.coverage(),
            map_accuracy: map.accuracy(),
            map,
            moves,
            collisions: self.twin.body().world().collisions(),
            touches: self.touches.report(moves, sim_time_s),
            belief: self.belief.report(),
            first_contact: self.first_contact.clone(),
            unphysical: self.twin.body().world().unphysical(),
            final_pose: (f64::from(pose.x), f64::from(pose.y), f64::from(pose.theta.to_degrees())),
            final_cell: self.truth.frame.cell_at(pose.x, pose.y),
            cute_cell: (cx, cy),
            localisation: self.localisation.clone(),
            links,
            faults_injected,
            reconnects: self.cute.connects().saturating_sub(1),
            // Hashing every byte of a long run costs; a report taken while the run goes on has
            // none. An interactive run past its headless end keeps the logs of the headless run
            // (see `interactive`), so it has the headless run's hash.
            link_log_sha256: if self.is_finished() || self.headless_end.is_some() {
                self.final_hash.get_or_init(|| hash_logs(&self.logs)).clone()
            } else {
                String::new()
            },
            checks: Vec::new(),
            passed: false,
        };
        report.check(&scenario.expect);
        report
    }

    /// Bytes through the tracer of `link` at `endpoint`.
    fn traced(&self, link: &str, endpoint: &str) -> TraceTotals {
        self.traces
            .iter()
            .find(|(l, e, _)| l == link && e == endpoint)
            .map_or_else(TraceTotals::default, |(_, _, h)| h.totals())
    }

    /// Every link's bytes, frames and errors, read from counters kept as the run went: bytes from
    /// each endpoint's tracer, frames and errors from the decoder of the endpoint that received
    /// them (the board twins for what Carto sent, Carto for what the boards and Cute sent, Cute
    /// for what Carto sent it, per connection). Nothing is decoded again here.
    fn link_stats(&self) -> Vec<LinkStats> {
        let carto = self.carto.carto().stats();
        let motor_board = self.twin.motor_board().decoder_stats();
        let sensor_board = self.twin.sensor_board().decoder_stats();
        let motor = LinkStats {
            name: "motor".to_string(),
            outbound: DirectionStats {
                bytes: self.traced("motor", "carto").written,
                frames: motor_board.frames,
                errors: motor_board.checksum_errors + motor_board.length_errors,
            },
            inbound: DirectionStats {
                bytes: self.traced("motor", "board").written,
                frames: carto.motor_frames_in,
                errors: carto.motor_errors,
            },
        };
        let sensor = LinkStats {
            name: "sensor".to_string(),
            outbound: DirectionStats {
                bytes: self.traced("sensor", "carto").written,
                frames: sensor_board.frames,
                errors: sensor_board.errors,
            },
            inbound: DirectionStats {
                bytes: self.traced("sensor", "board").written,
                frames: carto.sensor_frames_in,
                errors: carto.sensor_errors,
            },
        };
        // Cute's tracer sits before its fault injector: its written bytes are what Cute sent.
        let cute = self.cute.cute().counters();
        let gui = LinkStats {
            name: "gui".to_string(),
            outbound: DirectionStats {
                bytes: self.cute.wrapper().traces.iter().map(|h| h.totals().written).sum(),
                frames: carto.client_frames_in,
                errors: carto.protocol_errors + carto.fatal_errors,
            },
            inbound: DirectionStats {
                bytes: self.carto.stats().client_bytes_out,
                frames: cute.frames_in,
                errors: cute.decode_errors,
            },
        };
        vec![motor, sensor, gui]
    }
}
