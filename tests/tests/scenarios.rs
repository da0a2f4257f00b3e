//! Every scenario in `scenarios/` runs headless in the lockstep runner (Cute ⇄ Carto ⇄ board
//! twins ⇄ physics, real bytes on every link). Each must meet its own expectations, and a short
//! text report is snapshot with insta: a change in behaviour shows up as a snapshot diff
//! (`cargo insta review`), a failed expectation as a test failure.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::fmt::Write as _;
use std::path::Path;

use sim::report::Report;
use sim::runner::Lockstep;
use sim::scenario::LoadedScenario;

fn snapshot_text(r: &Report) -> String {
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
    let _ = writeln!(
        s,
        "coverage {}/{}, accuracy {}/{}",
        r.map.reachable_known_free, r.map.reachable, r.map.correct, r.map.classified
    );
    let _ = writeln!(s, "final cell {:?}, Cute believes {:?}", r.final_cell, r.cute_cell);
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

fn scenario(path: &Path) -> datatest_stable::Result<()> {
    let loaded = LoadedScenario::load(path)?;
    let name = loaded.scenario.name.clone();
    let mut run = Lockstep::new(loaded, None)?;
    run.run_to_end(|_| {});
    let report = run.report(0.0);
    insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false }, {
        insta::assert_snapshot!(name.clone(), snapshot_text(&report));
    });
    if !report.passed {
        return Err(format!("scenario {name} failed its expectations:\n{}", report.to_text()).into());
    }
    Ok(())
}

datatest_stable::harness! {
    { test = scenario, root = "../scenarios", pattern = r"^[^/]+\.ron$" },
}
