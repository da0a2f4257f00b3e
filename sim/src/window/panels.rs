//! The twin's egui panels: time controls over the world view (speed buttons, Step, the
//! scenario's figures) and the status bar along the bottom (sim time, achieved speed, Cute's
//! status, coverage, and bytes and frames per link).
//!
//! Invariant: the status bar's report is rebuilt at most every [`REPORT_EVERY_S`] of wall time
//! (and at once when paused, so a screenshot shows the figures of its instant).

use bevy::ecs::system::{Query, Res, ResMut};
use bevy::prelude::{Resource, With};
use bevy::time::{Real, Time};
use bevy::window::{PrimaryWindow, Window};
use cute::gui::bevy_egui::{EguiContexts, egui};
use robot_model::time::Instant;

use super::layout::STATUS_HEIGHT;
use crate::pacing::{Pacing, Speed};
use crate::plugin::Sim;
use crate::report::Report;

/// How often the status bar's report is rebuilt, wall seconds.
const REPORT_EVERY_S: f64 = 0.5;

/// The last report (rebuilt every [`REPORT_EVERY_S`]) and when it was made.
#[derive(Resource, Default)]
pub(super) struct StatusCache {
    report: Option<Report>,
    made_at_s: f64,
    sim_at: Option<Instant>,
}

pub(super) fn time_controls(
    mut contexts: EguiContexts,
    mut pacing: ResMut<Pacing>,
    sim: Res<Sim>,
) -> bevy::ecs::error::Result {
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("twin-time-controls")).fixed_pos(egui::pos2(14.0, 6.0)).show(ctx, |ui| {
        ui.horizontal(|ui| {
            ui.strong("Twin");
            for speed in [Speed::Paused, Speed::RealTime, Speed::Times10, Speed::Max] {
                if ui.selectable_label(pacing.speed == speed, speed.label()).clicked() {
                    pacing.speed = speed;
                    pacing.stop_at = None;
                }
            }
            let step = ui.button("Step").on_hover_text("pause and run one physics step");
            if step.clicked() {
                pacing.speed = Speed::Paused;
                pacing.stop_at = None;
                pacing.single_steps += 1;
            }
        });
        let run = &sim.0;
        let s = &run.loaded().scenario;
        ui.label(format!(
            "scenario '{}' (seed {}), {}x{} cells of {:.2} m, step {} ms",
            s.name,
            run.seed(),
            run.frame().rows,
            run.frame().cols,
            run.frame().cell,
            run.dt().as_secs_f64() * 1000.0
        ));
        ui.label(
            egui::RichText::new("true world: walls, obstacles, robot + wheels, sonar rays, trail")
                .color(egui::Color32::from_rgb(170, 180, 200)),
        );
    });
    Ok(())
}

fn kilo(bytes: u64) -> String {
    if bytes >= 10_000 { format!("{:.0} kB", bytes as f64 / 1000.0) } else { format!("{bytes} B") }
}

pub(super) fn status_bar(
    mut contexts: EguiContexts,
    sim: Res<Sim>,
    pacing: Res<Pacing>,
    time: Res<Time<Real>>,
    mut cache: ResMut<StatusCache>,
    window: Query<&Window, With<PrimaryWindow>>,
) -> bevy::ecs::error::Result {
    let Ok(window) = window.single() else {
        return Ok(());
    };
    let run = &sim.0;
    let wall = time.elapsed_secs_f64();
    // Paused, the report catches up at once (a screenshot shows the figures of its instant).
    let stale = wall - cache.made_at_s >= REPORT_EVERY_S || pacing.speed == Speed::Paused;
    if cache.report.is_none() || (stale && cache.sim_at != Some(run.now())) {
        cache.report = Some(run.report(wall));
        cache.made_at_s = wall;
        cache.sim_at = Some(run.now());
    }
    let ctx = contexts.ctx_mut()?;
    let height = window.size().y;
    let speed = match pacing.speed {
        Speed::Paused => "paused".to_string(),
        s => format!("{} (achieved {:.1}x)", s.label(), pacing.achieved),
    };
    let finished = if run.is_finished() { " (run finished)" } else { "" };
    let mut line1 = format!(
        "t = {:.2} s / {:.0} s{finished} | {speed} | Cute: {:?}",
        run.now().as_secs_f64(),
        run.time_limit().as_secs_f64(),
        run.cute().status(),
    );
    let mut line2 = String::new();
    if let Some(r) = cache.report.as_ref() {
        line1 += &format!(
            " | coverage {:.0} % accuracy {:.0} % collisions {}",
            r.coverage * 100.0,
            r.map_accuracy * 100.0,
            r.collisions
        );
        let links: Vec<String> = r
            .links
            .iter()
            .map(|l| {
                format!(
                    "{} {} {} fr / {} {} fr",
                    l.name,
                    kilo(l.outbound.bytes),
                    l.outbound.frames,
                    kilo(l.inbound.bytes),
                    l.inbound.frames,
                )
            })
            .collect();
        let errors: u64 = r.links.iter().map(|l| l.outbound.errors + l.inbound.errors).sum();
        line2 = format!("links out / in: {} | frame errors {errors}", links.join(" | "));
    }
    egui::Area::new(egui::Id::new("twin-status"))
        .fixed_pos(egui::pos2(14.0, height - STATUS_HEIGHT + 4.0))
        .show(ctx, |ui| {
            ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Truncate);
            ui.set_max_width(window.size().x - 28.0);
            ui.label(egui::RichText::new(line1).monospace());
            ui.label(egui::RichText::new(line2).monospace());
        });
    Ok(())
}
