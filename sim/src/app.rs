//! The Bevy shell around the lockstep runner.
//!
//! [`make_app`] builds the same app for headless runs and (with feature `window`) for the
//! interactive window. [`SimPlugin`] only registers the [`Sim`] resource and one system in
//! `FixedUpdate`, in the public [`SimSystems`] set; the runner itself is plain Rust
//! ([`crate::runner::Lockstep`]), so a run also works without Bevy.
//!
//! Headless, one `app.update()` runs [`TICKS_PER_UPDATE`] fixed ticks
//! (`TimeUpdateStrategy::FixedTimesteps`) of [`HEADLESS_STEPS_PER_TICK`] lockstep steps each, on
//! single-threaded executors: measured here, Bevy's own overhead per tick would otherwise cost
//! about a third of the run time.
//!
//! ```no_run
//! use sim::app::{Mode, Sim, make_app};
//! let run = sim::runner::Lockstep::new(sim::scenario::LoadedScenario::builtin_default()?, None)?;
//! let mut app = make_app(Mode::Headless, run);
//! while !app.world().resource::<Sim>().0.is_finished() {
//!     app.update();
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use bevy::MinimalPlugins;
use bevy::app::{App, FixedUpdate, Plugin, PluginGroup, TaskPoolOptions, TaskPoolPlugin};
use bevy::app::{FixedMain, FixedMainScheduleOrder, Main, MainScheduleOrder, RunFixedMainLoop};
use bevy::ecs::schedule::{
    InternedScheduleLabel, IntoScheduleConfigs, ScheduleLabel, SingleThreadedExecutor, SystemSet,
};
use bevy::ecs::system::{Res, ResMut};
use bevy::prelude::{Resource, Time, Virtual};
use bevy::time::{Fixed, TimeUpdateStrategy};

use crate::runner::Lockstep;

/// Fixed ticks per `app.update()` in headless mode.
pub const TICKS_PER_UPDATE: u32 = 20;
/// Lockstep steps per fixed tick in headless mode (see [`StepsPerTick`]).
pub const HEADLESS_STEPS_PER_TICK: u32 = 10;

/// How many lockstep steps one `FixedUpdate` tick runs; the fixed timestep is this many `dt`.
/// Headless runs batch [`HEADLESS_STEPS_PER_TICK`] steps so that Bevy's per-tick cost (about
/// 1.6 µs measured here, half a physics step) stays small; tests that want one physics step per
/// `app.update()` use [`make_app_with`] and 1.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepsPerTick(pub u32);

/// How the app is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// No window: as fast as the CPU allows.
    Headless,
    /// One window, the world beside Cute's map, paced to wall time × a speed factor by
    /// `crate::window::pace_lockstep` in `Update` (`Time<Fixed>` is not used for pacing).
    #[cfg(feature = "window")]
    Window,
}

/// The run being simulated.
#[derive(Resource)]
pub struct Sim(pub Lockstep);

/// The simulation's systems, in `FixedUpdate`.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum SimSystems {
    /// One lockstep step: boards, Carto, Cute, physics.
    Step,
}

/// Registers the run and the fixed-step system.
pub struct SimPlugin;

impl Plugin for SimPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(FixedUpdate, step_lockstep.in_set(SimSystems::Step));
    }
}

fn step_lockstep(mut sim: ResMut<Sim>, steps: Res<StepsPerTick>) {
    for _ in 0..steps.0 {
        if !sim.0.step() {
            break;
        }
    }
}

/// Builds the app for `run` with the mode's defaults.
pub fn make_app(mode: Mode, run: Lockstep) -> App {
    match mode {
        Mode::Headless => make_app_with(mode, run, HEADLESS_STEPS_PER_TICK, TICKS_PER_UPDATE),
        #[cfg(feature = "window")]
        Mode::Window => make_app_with(mode, run, 1, 1),
    }
}

/// Builds the app with `steps_per_tick` lockstep steps per fixed tick and `ticks_per_update`
/// fixed ticks per `app.update()` (headless).
pub fn make_app_with(mode: Mode, run: Lockstep, steps_per_tick: u32, ticks_per_update: u32) -> App {
    let steps_per_tick = steps_per_tick.max(1);
    let ticks_per_update = ticks_per_update.max(1);
    let tick = std::time::Duration::from_micros(run.dt().total_micros()) * steps_per_tick;
    let mut app = App::new();
    match mode {
        Mode::Headless => {
            app.add_plugins(
                MinimalPlugins
                    .set(TaskPoolPlugin { task_pool_options: TaskPoolOptions::with_num_threads(1) }),
            );
            app.insert_resource(TimeUpdateStrategy::FixedTimesteps(ticks_per_update));
        }
        #[cfg(feature = "window")]
        Mode::Window => crate::window::add_window_plugins(&mut app, &run),
    }
    app.insert_resource(Time::<Fixed>::from_duration(tick));
    // Many ticks per update exceed Bevy's default 250 ms cap on one update's virtual time.
    let mut virt = Time::<Virtual>::default();
    virt.set_max_delta(tick * (ticks_per_update + 1));
    app.insert_resource(virt);
    app.insert_resource(StepsPerTick(steps_per_tick));
    app.insert_resource(Sim(run));
    if mode == Mode::Headless {
        app.add_plugins(SimPlugin);
        single_threaded(&mut app);
    }
    app
}

/// Puts every schedule of the main and fixed loops on the single-threaded executor. The
/// multi-threaded one wakes worker threads for every fixed step: measured here, the full stack
/// ran at 155x real time with it (futex-bound) instead of over 1000x.
///
/// The fixed loop is also trimmed to `FixedUpdate` alone: the four other fixed schedules are empty
/// headless, but looking each of them up costs more per step than the physics does.
fn single_threaded(app: &mut App) {
    let mut labels: Vec<InternedScheduleLabel> =
        vec![Main.intern(), FixedMain.intern(), RunFixedMainLoop.intern()];
    if let Some(order) = app.world().get_resource::<MainScheduleOrder>() {
        labels.extend(order.labels.iter().chain(order.startup_labels.iter()).copied());
    }
    if let Some(order) = app.world().get_resource::<FixedMainScheduleOrder>() {
        labels.extend(order.labels.iter().copied());
    }
    for label in labels {
        app.edit_schedule(label, |schedule| {
            schedule.set_executor(SingleThreadedExecutor::new());
        });
    }
    if let Some(mut order) = app.world_mut().get_resource_mut::<FixedMainScheduleOrder>() {
        order.labels = vec![FixedUpdate.intern()];
    }
}
