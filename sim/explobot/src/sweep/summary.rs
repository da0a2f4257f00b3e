//! `summary.md` and `junit.xml`, computed from the `results.jsonl` lines alone (parsed back into
//! [`RunRecord`]s), so a one-machine sweep and a merge of its shards write the same bytes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::exec::Verdict;
use super::plan::{Manifest, generated_room, group_of, rerun_command};
use super::record::RunRecord;
use super::stats::{Figures, pass_cell, pass_rate_text};
use twin::report::{ContactCause, FirstContact, HEARD_NEAR_M, Heard};

/// Most runs listed by name in `summary.md`'s failure tables.
const MAX_LISTED: usize = 50;

fn seeds_text(seeds: &[u64]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < seeds.len() {
        let mut j = i;
        while j + 1 < seeds.len() && seeds[j + 1] == seeds[j] + 1 {
            j += 1;
        }
        parts.push(if j > i { format!("{}..{}", seeds[i], seeds[j]) } else { seeds[i].to_string() });
        i = j + 1;
    }
    parts.join(",")
}

fn pct(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{:.1}%", v * 100.0))
}

fn cell(text: &str) -> String {
    text.replace('|', "\\|").replace('\n', " ")
}

/// Runs grouped by scenario file or generated style, in run-list order of first appearance.
fn groups(records: &[RunRecord]) -> Vec<(String, Vec<&RunRecord>)> {
    let mut order: Vec<String> = Vec::new();
    let mut by: BTreeMap<String, Vec<&RunRecord>> = BTreeMap::new();
    for r in records {
        let g = group_of(&r.room);
        if !by.contains_key(&g) {
            order.push(g.clone());
        }
        by.entry(g).or_default().push(r);
    }
    order
        .into_iter()
        .map(|g| {
            let runs = by.remove(&g).unwrap_or_default();
            (g, runs)
        })
        .collect()
}

/// `summary.md`: the verdict, the pass rate per scenario or style, the worst runs, and the
/// commands that re-run the failures.
pub fn summary(manifest: &Manifest, records: &[RunRecord]) -> String {
    let passed = records.iter().filter(|r| r.verdict.passed()).count();
    let mut s = String::new();
    let _ = writeln!(s, "# Sweep: {} runs pass\n", pass_rate_text(passed, records.len()));
    let seeds = manifest
        .seeds
        .as_ref()
        .map_or("each room's own seed".into(), |x| format!("seeds {}", seeds_text(&x.0)));
    let _ = writeln!(s, "{} rooms × {seeds}: {} runs.", manifest.rooms.len(), manifest.runs);
    if manifest.known_room {
        let _ = writeln!(
            s,
            "\n**Known room** (`--known-room`): Carto was given every surface of each room beforehand, as if \
             its sonar saw everything. These figures are a ceiling for perfect perception, not what the \
             robot achieves."
        );
    }
    if manifest.known_echoes {
        let _ = writeln!(
            s,
            "\n**Known echoes** (`--known-echoes`): Carto was given every point its sonar heard, where it \
             really lies, never forgotten. These figures are a ceiling for a perfect memory of the echoes, \
             not what the robot achieves."
        );
    }
    if records.len() != manifest.runs {
        let _ = writeln!(s, "This folder holds {} of them (one shard).", records.len());
    }
    let _ = writeln!(s, "\n## Pass rate per scenario or style\n");
    let _ = writeln!(
        s,
        "| scenario or style | runs | pass | pass rate | min coverage | min accuracy | max collisions | failing |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---|");
    for (group, runs) in groups(records) {
        let ok = runs.iter().filter(|r| r.verdict.passed()).count();
        let min = |f: fn(&RunRecord) -> Option<f64>| runs.iter().filter_map(|r| f(r)).reduce(f64::min);
        let max_collisions = runs.iter().filter_map(|r| r.collisions).max();
        let failing: Vec<String> =
            runs.iter().filter(|r| !r.verdict.passed()).map(|r| r.room_label()).collect();
        let _ = writeln!(
            s,
            "| {} | {} | {ok} | {:.1}% | {} | {} | {} | {} |",
            cell(&group),
            runs.len(),
            100.0 * ok as f64 / runs.len().max(1) as f64,
            pct(min(|r| r.coverage)),
            pct(min(|r| r.map_accuracy)),
            max_collisions.map_or("-".into(), |c| c.to_string()),
            failing.join(", ")
        );
    }
    figures_table(&mut s, records);
    first_contacts(&mut s, records);
    not_physical_runs(&mut s, records);
    let mut worst: Vec<&RunRecord> = records.iter().filter(|r| !r.verdict.passed()).collect();
    worst.sort_by(|a, b| {
        (a.verdict, std::cmp::Reverse(a.failed_checks()))
            .cmp(&(b.verdict, std::cmp::Reverse(b.failed_checks())))
            .then(a.coverage.unwrap_or(0.0).total_cmp(&b.coverage.unwrap_or(0.0)))
            .then(b.collisions.cmp(&a.collisions))
            .then(a.index.cmp(&b.index))
    });
    if worst.is_empty() {
        let _ = writeln!(s, "\nEvery run passes.");
        return s;
    }
    let _ = writeln!(s, "\n## Failing runs, worst first\n");
    let _ = writeln!(
        s,
        "Panics, setup errors and timeouts first, then by failed expectations, coverage, collisions.\n"
    );
    let _ = writeln!(s, "| run | scenario | seed | verdict | coverage | accuracy | collisions | why |");
    let _ = writeln!(s, "|---:|---|---:|---|---:|---:|---:|---|");
    for r in worst.iter().take(MAX_LISTED) {
        let verdict = serde_json::to_value(r.verdict)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {verdict} | {} | {} | {} | {} |",
            r.index,
            cell(&r.room),
            r.seed,
            pct(r.coverage),
            pct(r.map_accuracy),
            r.collisions.map_or("-".into(), |c| c.to_string()),
            cell(r.reason.as_deref().unwrap_or(""))
        );
    }
    if worst.len() > MAX_LISTED {
        let _ = writeln!(s, "\n…and {} more in results.jsonl.", worst.len() - MAX_LISTED);
    }
    let _ = writeln!(s, "\n## Re-run a failure\n\n```sh");
    let oracle = if manifest.known_room {
        " --known-room"
    } else if manifest.known_echoes {
        " --known-echoes"
    } else {
        ""
    };
    for r in worst.iter().take(MAX_LISTED) {
        let _ = writeln!(s, "{}{oracle}", rerun_command(&r.room, r.seed));
    }
    let _ = writeln!(s, "```");
    s
}

/// The "Figures" table: pass rate with its interval and the continuous figures, for all runs and
/// per scenario or style ([`Figures`]).
fn figures_table(s: &mut String, records: &[RunRecord]) {
    let _ = writeln!(s, "\n## Figures\n");
    let _ = writeln!(
        s,
        "Pass rate with its Wilson 95 % interval; touches per 100 moves pooled over the runs; hard \
         collisions (began at 0.10 m/s or more, or pushed the body 2 cm or more) in all; the median of \
         each run's 95th-percentile belief error (Carto's belief against the true body); coverage of the \
         scored set (the cells the robot reaches keeping its clearance), the mean over the runs.\n"
    );
    let _ = writeln!(
        s,
        "| runs of | runs | pass | touches / 100 moves | no touch | hard collisions (runs) | belief error p95, median | belief error, largest | mean coverage |"
    );
    let _ = writeln!(s, "|---|---:|---|---:|---:|---:|---:|---:|---:|");
    let all = ("all".to_string(), records.iter().collect::<Vec<_>>());
    let groups = groups(records);
    let rows = if groups.len() > 1 { std::iter::once(all).chain(groups).collect() } else { vec![all] };
    for (group, runs) in rows {
        let f = Figures::of(runs.iter().copied());
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2} | {} | {} ({}) | {:.3} m | {:.3} m | {:.1}% |",
            cell(&group),
            f.runs,
            pass_cell(f.passed, f.runs),
            f.touches_per_100_moves,
            f.runs_without_touch,
            f.hard_collisions,
            f.runs_with_hard,
            f.belief_p95_median_m,
            f.belief_max_m,
            100.0 * f.mean_coverage
        );
    }
}

/// The "First contacts" table: how many runs met something first while doing what (see
/// [`ContactCause`]), and which. Nothing when no run touched anything.
fn first_contacts(s: &mut String, records: &[RunRecord]) {
    let mut by_cause: BTreeMap<ContactCause, Vec<&RunRecord>> = BTreeMap::new();
    for r in records {
        if let Some(c) = &r.first_contact {
            by_cause.entry(c.cause).or_default().push(r);
        }
    }
    if by_cause.is_empty() {
        return;
    }
    let touched: usize = by_cause.values().map(Vec::len).sum();
    let _ = writeln!(s, "\n## First contacts\n");
    let _ = writeln!(
        s,
        "{touched} of {} runs touched something. What the robot was doing the first time, and what the \
         ground truth says of it:\n",
        records.len()
    );
    let _ = writeln!(s, "| first contact | runs | never heard | which |");
    let _ = writeln!(s, "|---|---:|---:|---|");
    for (cause, runs) in &by_cause {
        let which = capped_list(runs, |r| run_name(r));
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            cause.describe(),
            runs.len(),
            never_heard(runs),
            cell(&which)
        );
    }
    let _ = writeln!(
        s,
        "\n\"Never heard\": before the contact, the sonar had reported no echo from the touched \
         shape within {HEARD_NEAR_M:.2} m of where it was touched (no use of the readings could \
         have told Carto that surface was there); runs recorded before this was kept count as heard."
    );
    heard_and_held(s, records);
    touched_first(s, records);
}

/// The "Heard, and held?" table of "First contacts": for the runs whose first touch the sonar
/// had heard, or not, how many touched a spot where Carto still held an echo point
/// ([`FirstContact::touched_held_m`] within [`HEARD_NEAR_M`]).
fn heard_and_held(s: &mut String, records: &[RunRecord]) {
    const CLASSES: [&str; 4] = [
        "never heard there",
        "heard there, only from farther than 1 m",
        "heard there from 1 m or nearer",
        "not recorded",
    ];
    let class = |c: &FirstContact| match c.touched_heard {
        Some(Heard::Never) => CLASSES[0],
        Some(Heard::Before { nearest_m, .. }) if nearest_m > 1.0 => CLASSES[1],
        Some(Heard::Before { .. }) => CLASSES[2],
        None => CLASSES[3],
    };
    let _ = writeln!(
        s,
        "\nHeard, and held? Whether Carto still held an echo point within {HEARD_NEAR_M:.2} m of the \
         spot when the robot touched it (placed where Carto placed it):\n"
    );
    let _ = writeln!(s, "| first touch | runs | Carto held a point there | it did not |");
    let _ = writeln!(s, "|---|---:|---:|---:|");
    for label in CLASSES {
        let runs: Vec<&FirstContact> =
            records.iter().filter_map(|r| r.first_contact.as_ref()).filter(|c| class(c) == label).collect();
        if runs.is_empty() {
            continue;
        }
        let held =
            runs.iter().filter(|c| c.touched_held_m.is_some_and(|d| d <= f64::from(HEARD_NEAR_M))).count();
        let _ = writeln!(s, "| {label} | {} | {held} | {} |", runs.len(), runs.len() - held);
    }
}

/// How many of `runs` first touched something the sonar had never reported an echo from.
fn never_heard(runs: &[&RunRecord]) -> usize {
    runs.iter()
        .filter(|r| r.first_contact.as_ref().is_some_and(|c| c.touched_heard == Some(Heard::Never)))
        .count()
}

/// The second table of "First contacts": what the robot touched
/// ([`twin::world::Touched::class`]), split by what it was doing.
fn touched_first(s: &mut String, records: &[RunRecord]) {
    let mut by_class: BTreeMap<&str, Vec<&RunRecord>> = BTreeMap::new();
    for r in records {
        if let Some(c) = &r.first_contact {
            by_class.entry(c.touched.map_or("not recorded", |t| t.class())).or_default().push(r);
        }
    }
    let _ = writeln!(s, "\nWhat the robot touched first, and while doing what:\n");
    let _ = writeln!(
        s,
        "| touched first | runs | during a FORWARD | during a turn | other | never heard | which |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---|");
    let mut rows: Vec<(&str, Vec<&RunRecord>)> = by_class.into_iter().collect();
    rows.sort_by_key(|(class, runs)| (std::cmp::Reverse(runs.len()), *class));
    for (class, runs) in rows {
        let count = |f: fn(ContactCause) -> bool| {
            runs.iter().filter(|r| r.first_contact.as_ref().is_some_and(|c| f(c.cause))).count()
        };
        let forward = count(|c| matches!(c, ContactCause::ForwardBlockedMove | ContactCause::ForwardOffPath));
        let turn = count(|c| matches!(c, ContactCause::TurnWhereNoTurn | ContactCause::TurnOffCentre));
        let which = capped_list(&runs, |r| run_name(r));
        let _ = writeln!(
            s,
            "| {class} | {} | {forward} | {turn} | {} | {} | {} |",
            runs.len(),
            runs.len() - forward - turn,
            never_heard(&runs),
            cell(&which)
        );
    }
}

/// The "Not physical" list: runs in which the body moved faster than its wheels can drive it
/// (`docs/explanation/physical-model.md`, "Contacts"). Nothing when there is none.
fn not_physical_runs(s: &mut String, records: &[RunRecord]) {
    let runs: Vec<(&RunRecord, f64)> =
        records.iter().filter_map(|r| Some((r, r.unphysical.as_ref()?.first_at_s?))).collect();
    if runs.is_empty() {
        return;
    }
    let _ = writeln!(s, "\n## Not physical\n");
    let _ = writeln!(
        s,
        "In {} of {} runs the robot's body moved faster than its wheels can drive it: a fault of \
         the twin's physics (`sim/README.md`, \"Contacts\"). What those runs did after that time \
         is not what the robot would do:\n",
        runs.len(),
        records.len()
    );
    let which = capped_list(&runs, |(r, t)| format!("{} ({t:.1} s)", run_name(r)));
    let _ = writeln!(s, "{which}");
}

/// The first [`MAX_LISTED`] of `items` as `label` names them, joined with commas, and how many
/// more there are.
fn capped_list<T>(items: &[T], label: impl Fn(&T) -> String) -> String {
    let mut which: Vec<String> = items.iter().take(MAX_LISTED).map(label).collect();
    if items.len() > MAX_LISTED {
        which.push(format!("…and {} more", items.len() - MAX_LISTED));
    }
    which.join(", ")
}

/// A run as the summary's lists name it: the room and its label, e.g. "flat room 3 seed 3".
fn run_name(r: &RunRecord) -> String {
    format!("{} {}", short_room(&r.room), r.room_label())
}

/// A room id without the file's folders or the generator's seed (the label has it).
fn short_room(room: &str) -> String {
    match generated_room(room) {
        Some((style, _)) => style.to_string(),
        None => Path::new(room).file_stem().map_or(room.to_string(), |f| f.to_string_lossy().into_owned()),
    }
}

fn xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\n' | '\t') => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// `junit.xml`: one test suite per scenario or style, one test case per run; `fail` and
/// `timeout` are failures, `panic` and `error` are errors. No times.
pub fn junit(records: &[RunRecord]) -> String {
    let count = |rs: &[&RunRecord], f: fn(Verdict) -> bool| rs.iter().filter(|r| f(r.verdict)).count();
    let is_failure = |v| matches!(v, Verdict::Fail | Verdict::Timeout);
    let is_error = |v| matches!(v, Verdict::Panic | Verdict::Error);
    let all: Vec<&RunRecord> = records.iter().collect();
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        s,
        "<testsuites name=\"explobot sweep\" tests=\"{}\" failures=\"{}\" errors=\"{}\">",
        all.len(),
        count(&all, is_failure),
        count(&all, is_error)
    );
    for (group, runs) in groups(records) {
        let _ = writeln!(
            s,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\">",
            xml(&group),
            runs.len(),
            count(&runs, is_failure),
            count(&runs, is_error)
        );
        for r in runs {
            let name = format!("{} {}", r.room, r.room_label());
            let open = format!("    <testcase classname=\"{}\" name=\"{}\"", xml(&r.scenario), xml(&name));
            let reason = xml(r.reason.as_deref().unwrap_or(""));
            let kind = if is_error(r.verdict) { "error" } else { "failure" };
            if r.verdict.passed() {
                let _ = writeln!(s, "{open}/>");
            } else {
                let _ = writeln!(s, "{open}>");
                let _ = writeln!(
                    s,
                    "      <{kind} message=\"{reason}\" type=\"{:?}\">{}</{kind}>",
                    r.verdict,
                    xml(&rerun_command(&r.room, r.seed))
                );
                let _ = writeln!(s, "    </testcase>");
            }
        }
        let _ = writeln!(s, "  </testsuite>");
    }
    s.push_str("</testsuites>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn consecutive_seeds_read_as_ranges() {
        assert_eq!(seeds_text(&[1, 2, 3, 5, 7, 8]), "1..3,5,7..8");
        assert_eq!(seeds_text(&[4]), "4");
    }

    #[test]
    fn first_contacts_are_counted_by_cause_and_name_their_runs() {
        let line = |i: usize, room: &str, cause: Option<&str>| {
            // the first two touched a leg, the third a turned box; older lines have no `touched`
            let touched = match i {
                0 => r#","touched":{"kind":"leg","width_m":0.03},"touched_heard":"never""#,
                1 => {
                    r#","touched":{"kind":"leg","width_m":0.03},"touched_heard":{"before":{"first_s":0.5,"nearest_m":0.3}},"touched_held_m":0.04"#
                }
                2 => r#","touched":{"kind":"box","off_grid_deg":30.0},"touched_heard":"never""#,
                _ => "",
            };
            let contact = cause.map_or("null".to_string(), |c| {
                format!(
                    r#"{{"t_s":1.0,"cell":[0,1],"carto_activity":"driving forward","off_centre_m":0.1,"belief_error_m":null,"cause":"{c}"{touched}}}"#
                )
            });
            RunRecord::parse(
                &format!(r#"{{"index":{i},"room":"{room}","scenario":"s","seed":{i},"verdict":"fail","first_contact":{contact}}}"#),
                "t",
            )
            .unwrap()
        };
        let records = [
            line(0, "gen:flat:3", Some("forward-blocked-move")),
            line(1, "scenarios/furnished.ron", Some("forward-blocked-move")),
            line(2, "gen:office:1", Some("turn-where-no-turn")),
            line(3, "gen:office:2", None),
        ];
        let mut s = String::new();
        first_contacts(&mut s, &records);
        assert!(s.contains("3 of 4 runs touched something"), "{s}");
        assert!(
            s.contains(&format!(
                "| {} | 2 | 1 | flat room 3 seed 0, furnished seed 1 |",
                ContactCause::ForwardBlockedMove.describe()
            )),
            "{s}"
        );
        assert!(s.contains(&format!(
            "| {} | 1 | 1 | office room 1 seed 2 |",
            ContactCause::TurnWhereNoTurn.describe()
        )));
        // what they touched, most first, split by what the robot was doing
        assert!(
            s.contains(
                "| leg (8 cm or thinner) | 2 | 2 | 0 | 0 | 1 | flat room 3 seed 0, furnished seed 1 |"
            ),
            "{s}"
        );
        assert!(
            s.contains("| box turned past 22.5° from the grid | 1 | 0 | 1 | 0 | 1 | office room 1 seed 2 |"),
            "{s}"
        );
        // heard and held: the furnished run's spot was heard from 0.3 m and Carto held a point
        // 4 cm from it; the two never heard were not held
        assert!(s.contains("| never heard there | 2 | 0 | 2 |"), "{s}");
        assert!(s.contains("| heard there from 1 m or nearer | 1 | 1 | 0 |"), "{s}");
        assert!(!s.contains("farther than 1 m |"), "{s}");
        let older = [line(3, "gen:office:2", Some("other"))];
        let mut s = String::new();
        first_contacts(&mut s, &older);
        assert!(s.contains("| not recorded | 1 | 0 | 0 | 1 | 0 | office room 2 seed 3 |"), "{s}");
        assert!(s.contains("| not recorded | 1 | 0 | 1 |"), "{s}");
        // An older results.jsonl line without the field still reads; no contact, no table.
        let mut none = String::new();
        first_contacts(&mut none, &[line(0, "gen:flat:3", None)]);
        assert!(none.is_empty());
    }

    #[test]
    fn runs_that_left_physics_are_listed_with_the_time() {
        let line = |i: usize, room: &str, unphysical: &str| {
            RunRecord::parse(
                &format!(
                    r#"{{"index":{i},"room":"{room}","scenario":"s","seed":{i},"verdict":"fail"{unphysical}}}"#
                ),
                "t",
            )
            .unwrap()
        };
        let fast = r#","unphysical":{"steps":12,"first_at_s":25.6,"fastest_m_s":14.0,"fastest_rad_s":157.0}"#;
        let sound = r#","unphysical":{"steps":0,"first_at_s":null,"fastest_m_s":0.3,"fastest_rad_s":2.0}"#;
        let records =
            [line(0, "gen:irregular:2", fast), line(1, "gen:flat:1", sound), line(2, "old.ron", "")];
        let mut s = String::new();
        not_physical_runs(&mut s, &records);
        assert!(s.contains("In 1 of 3 runs the robot's body moved faster"), "{s}");
        assert!(s.contains("irregular room 2 seed 0 (25.6 s)"), "{s}");
        let mut none = String::new();
        not_physical_runs(&mut none, &records[1..]);
        assert!(none.is_empty(), "{none}");
    }

    #[test]
    fn xml_text_is_escaped() {
        assert_eq!(xml("a <= 0 & \"b\"\u{1}"), "a &lt;= 0 &amp; &quot;b&quot; ");
    }
}
