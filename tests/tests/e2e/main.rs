//! The end-to-end tests of the workspace in one test binary, so the heavy crates (Bevy, rapier,
//! foxglove) are linked once: one module per former test file. Four keep their own binary: the
//! scenario snapshots (`tests/scenarios.rs`, a datatest harness), the Slurm test
//! (`tests/slurm.rs`), the windowed `cute` against the served twin in real time
//! (`tests/serve_e2e.rs`, which must not share the CPU with this binary's other tests), and the
//! fuzz seed check (`tests/carto_fuzz_seeds.rs`, run by name by `carto/fuzz/seed-corpus.sh`).

mod calibration;
mod carto_twin;
mod cli;
mod compat_cute;
mod daemon;
mod determinism;
mod first_contact;
mod foxglove;
mod foxglove_live;
mod generate;
mod generated_runs;
mod grid_coverage;
mod imports;
mod layers;
mod long_mission;
mod measured_rooms;
mod processes;
mod readme;
mod recording;
mod serial_hil;
mod slow_link;
mod sweep;
mod uart_budget;
