//! The Bevy shell around the lockstep runner.
//!
//! [`make_app`] builds the same app for headless runs and (with feature `window`) for the
//! interactive window: it inserts the resources and adds [`SimPlugin`] (headless) or the
//! window's plugins, which sit above [`crate::plugin`] (module order: `plugin` ← `window` ←
//! `app`, no circle). The runner itself is plain Rust ([`twin::runner::Lockstep`]), so a run
//! also works without Bevy.
//!
//! Headless, one `app.update()` runs [`TICKS_PER_UPDATE`] fixed ticks
//! (`TimeUpdateStrategy::FixedTimesteps`) of [`HEADLESS_STEPS_PER_TICK`] lockstep steps each, on
//! single-threaded executors: measured here, Bevy's own overhead per tick would otherwise cost
//! about a third of the run time.
//!
//! ```no_run
//! use twin_app::app::{Mode, Sim, make_app};
//! let run = twin::runner::Lockstep::new(twin::setup::RunSetup::builtin_default()?, None)?;
//! let mut app = make_app(Mode::Headless, run);
//! while !app.world().resource::<Sim>().0.is_finished() {
//!     app.update();
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;

use bevy::MinimalPlugins;
use bevy::app::{App, FixedUpdate, PluginGroup, TaskPoolOptions, TaskPoolPlugin};
use bevy::app::{FixedMain, FixedMainScheduleOrder, Main, MainScheduleOrder, RunFixedMainLoop};
use bevy::ecs::schedule::{InternedScheduleLabel, ScheduleLabel, SingleThreadedExecutor};
use bevy::prelude::{Time, Virtual};
use bevy::time::{Fixed, TimeUpdateStrategy};

pub use crate::plugin::{Sim, SimPlugin, SimSystems, StepsPerTick};
use twin::runner::Lockstep;

/// Fixed ticks per `app.update()` in headless mode.
pub const TICKS_PER_UPDATE: u32 = 20;
/// Lockstep steps per fixed tick in headless mode (see [`StepsPerTick`]).
pub const HEADLESS_STEPS_PER_TICK: u32 = 10;

/// How the app is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// No window: as fast as the CPU allows.
    Headless,
    /// One window, the world beside Cute's map, paced to wall time × a speed factor by the
    /// window's `pace_lockstep` in `Update` (`Time<Fixed>` is not used for pacing). The run is
    /// made [`Lockstep::interactive`]: the script plays, then the user drives until the window
    /// is closed.
    #[cfg(feature = "window")]
    Window,
}

/// What the window writes for tests and docs: a screenshot, a status file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WindowOutputs {
    /// Run at full speed to this many sim seconds, save a PNG of the window there, exit.
    pub screenshot: Option<(PathBuf, f64)>,
    /// Rewrite this file a few times a second with what the window shows, as JSON.
    pub status_file: Option<PathBuf>,
}

/// The headless app no longer held the run at its end (a system removed [`Sim`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the simulation resource disappeared")]
pub struct LostRun;

/// Runs `run` to its end in the headless app, calling `progress` before every `update()` (a
/// progress bar).
pub fn run_headless(run: Lockstep, mut progress: impl FnMut(&Lockstep)) -> Result<Lockstep, LostRun> {
    let mut app = make_app(Mode::Headless, run);
    loop {
        let sim = &app.world().resource::<Sim>().0;
        if sim.is_finished() {
            break;
        }
        progress(sim);
        app.update();
    }
    app.world_mut().remove_resource::<Sim>().map(|sim| sim.0).ok_or(LostRun)
}

/// The window could not be opened.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WindowError {
    /// This build has no window (feature `window` off).
    #[error(
        "this explobot was built without the window; rebuild with `cargo build --release -p explobot --features window`"
    )]
    NotBuilt,
    /// The screenshot time is not a number of seconds >= 0.
    #[error("--screenshot-after must be a number of seconds >= 0")]
    BadScreenshotTime,
}

/// Opens the window on `run` until it is closed (or, with a screenshot asked for, until the
/// picture is saved); whether the app ended well. The script, if any, plays first; then the
/// user drives (see `crate::window`).
pub fn run_window(run: Lockstep, outputs: &WindowOutputs) -> Result<bool, WindowError> {
    let shot = outputs.screenshot.clone();
    #[cfg(feature = "window")]
    {
        let mut app = make_app(Mode::Window, run);
        if let Some((path, after_s)) = shot {
            crate::window::request_screenshot(&mut app, path, after_s);
        }
        if let Some(path) = &outputs.status_file {
            crate::window::request_status_file(&mut app, path.clone());
        }
        Ok(app.run().is_success())
    }
    #[cfg(not(feature = "window"))]
    {
        let _ = (run, shot);
        Err(WindowError::NotBuilt)
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
    // In the window the user ends the run: the script plays first, then the user drives.
    #[cfg(feature = "window")]
    let run = if mode == Mode::Window { run.interactive() } else { run };
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
