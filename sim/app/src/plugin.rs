//! [`SimPlugin`]: the simulation as Bevy sees it — the [`Sim`] resource (the lockstep run) and
//! one system in `FixedUpdate`, in the public [`SimSystems`] set.
//!
//! The plugin only registers the system; the app builder (`crate::app::make_app`) inserts the
//! resources. The render side (feature `window`) sits above this module and orders its own
//! systems after [`SimSystems::Step`].
//!
//! ```
//! use bevy::app::App;
//! use twin_app::plugin::{Sim, SimPlugin, StepsPerTick};
//! let run = twin::runner::Lockstep::new(twin::setup::RunSetup::builtin_default()?, None)?;
//! let mut app = App::new();
//! app.insert_resource(Sim(run)).insert_resource(StepsPerTick(1)).add_plugins(SimPlugin);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use bevy::app::{App, FixedUpdate, Plugin};
use bevy::ecs::schedule::{IntoScheduleConfigs, SystemSet};
use bevy::ecs::system::{Res, ResMut};
use bevy::prelude::Resource;

use twin::runner::Lockstep;

/// How many lockstep steps one `FixedUpdate` tick runs; the fixed timestep is this many `dt`.
/// Headless runs batch `crate::app::HEADLESS_STEPS_PER_TICK` steps so that Bevy's per-tick cost (about
/// 1.6 µs measured here, half a physics step) stays small; tests that want one physics step per
/// `app.update()` use `crate::app::make_app_with` and 1.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepsPerTick(pub u32);

/// The run being simulated.
#[derive(Resource)]
pub struct Sim(pub Lockstep);

/// The simulation's systems, in `FixedUpdate`.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum SimSystems {
    /// One lockstep step: boards, Carto, Cute, physics.
    Step,
}

/// Registers the fixed-step system (the app builder inserts [`Sim`] and [`StepsPerTick`]).
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
