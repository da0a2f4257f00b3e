//! `explobot calibrate` and `explobot replay --compare`: the profile fitted to a robot's
//! recorded calibration drive, and the gap between a recording and the twin
//! (`twin::calibrate` holds the method; this is the command line and the printing).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use robot_model::profile::RobotProfile;
use twin::calibrate::{Gap, Recorded, best_lag, fit::fit};
use twin::record::Recording;
use twin::scenario::Scenario;

/// The built-in calibration room (`scenarios/calibration/room.ron`).
const CALIBRATION_ROOM: &str = include_str!("../../../scenarios/calibration/room.ron");

/// `explobot calibrate REC --profile BASE --out FITTED [--room ROOM]`.
#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// A recording of the calibration drive (`carto --calibration-drive --record FILE`).
    pub recording: PathBuf,
    /// The profile to start from (default: the built-in default robot).
    #[arg(long, value_name = "FILE")]
    pub profile: Option<PathBuf>,
    /// Where to write the fitted profile.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// The room the drive ran in, the robot at its start (default: the built-in calibration room,
    /// `scenarios/calibration/room.ron`).
    #[arg(long, value_name = "SCENARIO")]
    pub room: Option<PathBuf>,
}

/// The room and the recorded streams.
fn load(recording: &Path, room: Option<&Path>) -> Result<(Scenario, Recorded)> {
    let rec = Recording::load(recording)?;
    let recorded = Recorded::from_recording(&rec).with_context(|| recording.display().to_string())?;
    let room = match room {
        Some(path) => twin::setup::RunSetup::load(path)?.scenario,
        None => Scenario::from_ron_str(CALIBRATION_ROOM, "<built-in calibration room>")?,
    };
    Ok((room, recorded))
}

fn profile(path: Option<&Path>) -> Result<RobotProfile> {
    Ok(match path {
        Some(p) => RobotProfile::load(p)?,
        None => RobotProfile::default(),
    })
}

impl CalibrateArgs {
    /// Fits, prints the table and writes the profile.
    pub fn run(&self) -> Result<String> {
        let (room, rec) = load(&self.recording, self.room.as_deref())?;
        let base = profile(self.profile.as_deref())?;
        let fitted = fit(&room, &base, &rec)?;
        let mut out = format!(
            "calibrated against {} ({} samples, {} twin runs, link round trip {:.0} ms)\n",
            self.recording.display(),
            fitted.samples,
            fitted.evaluations,
            fitted.lag_s * 1000.0
        );
        out.push_str("  value                      base        fitted      ± 1 sigma\n");
        for e in fitted.all() {
            let sigma = e.sigma.map_or("not observable: kept".to_owned(), twin::calibrate::fit::significant);
            let _ = writeln!(out, "  {:<26} {:<11.4} {:<11.4} {sigma} {}", e.name, e.base, e.value, e.unit);
        }
        out.push_str("fit residual (RMS, recorded less twin), base profile → fitted:\n");
        let before = Gap::measure(&room, &base, &rec, fitted.lag_s)?;
        // the fit's own residuals: the twin runs noiseless, so the fitted noise values change nothing
        let after = Gap { profile: fitted.profile.name.clone(), residuals: fitted.residuals.clone() };
        for (b, a) in before.table().iter().zip(after.table()) {
            let _ = writeln!(
                out,
                "  {:<14} {:>8.3} → {:>8.3} {} ({} samples)",
                b.stream, b.rms, a.rms, b.unit, a.samples
            );
        }
        let name = self.recording.display().to_string();
        std::fs::write(&self.out, fitted.profile_ron(&name)?)
            .with_context(|| format!("cannot write {}", self.out.display()))?;
        let _ = writeln!(out, "wrote {}", self.out.display());
        Ok(out)
    }
}

/// One panel of the gap plot: its title and the stream it draws.
type Panel = (&'static str, fn(&Gap) -> &[(f64, f64)]);

/// `explobot replay REC --compare [--profile P]… [--room ROOM] [--plot FILE.svg]`: the gap of each
/// profile, as a table, over time, and as a plot.
pub fn compare(
    recording: &Path,
    profiles: &[PathBuf],
    room: Option<&Path>,
    plot: Option<&Path>,
) -> Result<String> {
    let (room, rec) = load(recording, room)?;
    let mut gaps = Vec::new();
    let paths: Vec<Option<&Path>> =
        if profiles.is_empty() { vec![None] } else { profiles.iter().map(|p| Some(p.as_path())).collect() };
    let mut out =
        format!("the gap between {} and the twin (RMS of recorded less twin):\n", recording.display());
    for path in paths {
        let p = profile(path)?;
        let lag = best_lag(&room, &p, &rec)?;
        let gap = Gap::measure(&room, &p, &rec, lag)?;
        let label = path.map_or("built-in default".to_owned(), |p| p.display().to_string());
        let _ = writeln!(out, "{label} (round trip {:.0} ms):", lag * 1000.0);
        for row in gap.table() {
            let _ = writeln!(
                out,
                "  {:<14} RMS {:>8.3} {:<4} largest {:>8.3} at {:>5.1} s ({} samples)",
                row.stream, row.rms, row.unit, row.max.0, row.max.1, row.samples
            );
        }
        if gap.residuals.range_mismatches > 0 {
            let _ =
                writeln!(out, "  ranges at rest heard on one side only: {}", gap.residuals.range_mismatches);
        }
        out.push_str("  over time (10 s windows): start s, wheel rpm, heading deg, range cm\n");
        for (t, a, b, c) in gap.over_time(10.0) {
            let _ = writeln!(out, "    {t:>5.0} {a:>8.3} {b:>8.3} {c:>8.3}");
        }
        gaps.push((label, gap));
    }
    if let Some(path) = plot {
        std::fs::write(path, svg(&gaps)).with_context(|| format!("cannot write {}", path.display()))?;
        let _ = writeln!(out, "wrote {}", path.display());
    }
    Ok(out)
}

/// Heading and range errors over time, one colour per profile, as SVG.
fn svg(gaps: &[(String, Gap)]) -> String {
    const W: f64 = 900.0;
    const H: f64 = 220.0;
    const COLOURS: [&str; 4] = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd"];
    let end = gaps.iter().flat_map(|(_, g)| g.residuals.heading.last().map(|s| s.0)).fold(1.0, f64::max);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        2.0 * H + 60.0
    );
    let panels: [Panel; 2] = [
        ("heading error, deg (recorded less twin)", |g| &g.residuals.heading),
        ("range error at rest, cm", |g| &g.residuals.range),
    ];
    for (k, (title, series)) in panels.iter().enumerate() {
        let top = 20.0 + k as f64 * (H + 20.0);
        let peak = gaps.iter().flat_map(|(_, g)| series(g).iter().map(|v| v.1.abs())).fold(1e-3, f64::max);
        let _ = writeln!(s, "<text x=\"50\" y=\"{}\">{title} (axis ±{peak:.2})</text>", top + 12.0);
        let _ =
            writeln!(s, "<line x1=\"50\" y1=\"{0}\" x2=\"{W}\" y2=\"{0}\" stroke=\"#999\"/>", top + H / 2.0);
        for (i, (label, g)) in gaps.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points: Vec<String> = series(g)
                .iter()
                .map(|(t, e)| {
                    format!(
                        "{:.1},{:.1}",
                        50.0 + t / end * (W - 60.0),
                        top + H / 2.0 - e / peak * (H / 2.0 - 10.0)
                    )
                })
                .collect();
            let _ = writeln!(
                s,
                "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"1\" points=\"{}\"/>",
                points.join(" ")
            );
            if k == 0 {
                let _ = writeln!(
                    s,
                    "<text x=\"{}\" y=\"{}\" fill=\"{colour}\">{label}</text>",
                    60.0 + 250.0 * i as f64,
                    2.0 * H + 55.0
                );
            }
        }
    }
    s.push_str("</svg>\n");
    s
}
