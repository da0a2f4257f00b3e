//! The twin's egui panels: time controls over the world view (speed buttons, Step, Restart, the
//! scenario's figures, where the script stands and its verdict) and the status bar along the
//! bottom (sim time, the speed achieved, the script or the user driving, Cute's status, coverage,
//! and bytes and frames per link).
//!
//! Invariants: the status bar's report is rebuilt at most every [`REPORT_EVERY_S`] of wall time
//! (and at once when paused, so a screenshot shows the figures of its instant); the speed shown
//! is measured ([`Pacing::achieved`]) or says that it is being measured, never a stale zero.

use bevy::ecs::system::{Query, Res, ResMut};
use bevy::prelude::With;
use bevy::time::{Real, Time};
use bevy::window::{PrimaryWindow, Window};
use cute::gui::ButtonRects;
use cute::gui::bevy_egui::{EguiContexts, egui};

use super::carto_layer::CartoLayer;
use super::layout::STATUS_HEIGHT;
use super::session::{Handover, ScriptState, StatusCache};
use crate::pacing::{Pacing, Speed};
use crate::plugin::Sim;

/// How often the status bar's report is rebuilt, wall seconds.
const REPORT_EVERY_S: f64 = 0.5;

pub(super) fn time_controls(
    mut contexts: EguiContexts,
    mut pacing: ResMut<Pacing>,
    mut handover: ResMut<Handover>,
    mut rects: ResMut<ButtonRects>,
    mut layer: ResMut<CartoLayer>,
    sim: Res<Sim>,
) -> bevy::ecs::error::Result {
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("twin-time-controls")).fixed_pos(egui::pos2(14.0, 6.0)).show(ctx, |ui| {
        ui.horizontal(|ui| {
            ui.strong("Twin");
            for speed in [Speed::Paused, Speed::RealTime, Speed::Times10, Speed::Max] {
                let button = ui.selectable_label(pacing.speed == speed, speed.label());
                rects.record(speed.label(), &button);
                if button.clicked() && pacing.speed != speed {
                    pacing.speed = speed;
                    pacing.stop_at = None;
                    pacing.forget_speed();
                }
            }
            let step = ui.button("Step").on_hover_text("pause and run one physics step");
            rects.record("Step", &step);
            if step.clicked() {
                pacing.speed = Speed::Paused;
                pacing.stop_at = None;
                pacing.single_steps += 1;
            }
            let restart =
                ui.button("Restart").on_hover_text("the scenario again from its start pose, same seed");
            rects.record("Restart", &restart);
            if restart.clicked() {
                handover.restart = true;
            }
            let carto = ui.selectable_label(layer.shown, "Carto's map").on_hover_text(
                "Carto's own evidence grid (cyan free, teal occupied) and its belief (orange, with the \
                 2-sigma ellipse of its position) over the true room",
            );
            rects.record("Carto's map", &carto);
            if carto.clicked() {
                layer.toggle();
            }
        });
        let run = &sim.0;
        let s = &run.loaded().scenario;
        ui.label(format!(
            "scenario '{}' (seed {}), {}x{} cells of {:.2} m, step {} ms, headless limit {:.0} s",
            s.name,
            run.seed(),
            run.frame().rows,
            run.frame().cols,
            run.frame().cell,
            run.dt().as_secs_f64() * 1000.0,
            run.time_limit().as_secs_f64(),
        ));
        let mut colour = egui::Color32::from_rgb(170, 180, 200);
        let mut line = match (handover.verdict_line(), ScriptState::of(run)) {
            (Some(verdict), state) => {
                let passed = handover.verdict.as_ref().is_some_and(|r| r.passed);
                colour = if passed {
                    egui::Color32::from_rgb(120, 220, 140)
                } else {
                    egui::Color32::from_rgb(250, 130, 110)
                };
                match state {
                    ScriptState::Done(at) => format!("script done at {:.1} s: {verdict}", at.as_secs_f64()),
                    ScriptState::NoScript => format!("no script: you drive from the start ({verdict})"),
                    ScriptState::LimitPassed { limit, .. } => {
                        format!("at the headless limit {:.0} s: {verdict}", limit.as_secs_f64())
                    }
                    _ => verdict,
                }
            }
            (None, ScriptState::NoScript) => "no script: you drive from the start".to_string(),
            (None, _) => "the script plays first, then you drive".to_string(),
        };
        if let Some(e) = &handover.error {
            line = format!("{line} | {e}");
        }
        ui.label(egui::RichText::new(line).color(colour)).on_hover_text(
            "the scenario's script plays first; when it is done (or at once when there is none) the \
             expectations are checked and you drive: Cartography, Stop, Reset map, click a free cell",
        );
    });
    Ok(())
}

/// The speed as the status bar words it: `paused`, `Max: 85x real time`, `1x: measuring`.
pub(super) fn speed_text(speed: Speed, achieved: Option<f64>) -> String {
    match (speed, achieved) {
        (Speed::Paused, _) => "paused".to_string(),
        (s, None) => format!("{}: measuring", s.label()),
        (s, Some(x)) if x >= 9.95 => format!("{}: {x:.0}x real time", s.label()),
        (s, Some(x)) if x >= 0.095 => format!("{}: {x:.1}x real time", s.label()),
        (s, Some(_)) => format!("{}: below 0.1x real time", s.label()),
    }
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
    let speed = speed_text(pacing.speed, pacing.achieved);
    let script = ScriptState::of(run);
    let mut line1 = format!(
        "t = {:.2} s | {speed} | {} | Cute: {:?}",
        run.now().as_secs_f64(),
        script.text(),
        run.cute().status(),
    );
    let mut line2 = String::new();
    if let Some(r) = cache.report.as_ref() {
        line1 += &format!(
            " | coverage {:.0} % accuracy {:.0} % touches {} ({} hard) belief error {:.1} cm",
            r.coverage * 100.0,
            r.map_accuracy * 100.0,
            r.collisions,
            r.touches.hard,
            r.belief.error_max_m * 100.0
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn issue_16_speed_is_measured_or_paused_never_zero() {
        assert_eq!(speed_text(Speed::Paused, Some(3.0)), "paused");
        assert_eq!(speed_text(Speed::Max, None), "Max: measuring");
        assert_eq!(speed_text(Speed::Max, Some(85.3)), "Max: 85x real time");
        assert_eq!(speed_text(Speed::RealTime, Some(0.98)), "1x: 1.0x real time");
        assert_eq!(speed_text(Speed::Times10, Some(0.0)), "10x: below 0.1x real time");
    }
}
