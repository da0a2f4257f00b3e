//! Every scenario in `scenarios/` runs headless in the lockstep runner (Cute ⇄ Carto ⇄ board
//! twins ⇄ physics, real bytes on every link). Each must meet its own expectations, and a short
//! text report is snapshot with insta: a change in behaviour shows up as a snapshot diff
//! (`cargo insta review`), a failed expectation as a test failure.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

use twin::runner::Lockstep;
use twin::setup::RunSetup;

fn scenario(path: &Path) -> datatest_stable::Result<()> {
    let loaded = RunSetup::load(path)?;
    let name = loaded.scenario.name.clone();
    let mut run = Lockstep::new(loaded, None)?;
    run.run_to_end(|_| {});
    let report = run.report(0.0);
    insta::with_settings!({ snapshot_path => "snapshots", prepend_module_to_snapshot => false }, {
        insta::assert_snapshot!(name.clone(), report.summary_text());
    });
    if !report.passed {
        return Err(format!("scenario {name} failed its expectations:\n{}", report.to_text()).into());
    }
    Ok(())
}

datatest_stable::harness! {
    { test = scenario, root = "../scenarios", pattern = r"^[^/]+\.ron$" },
}
