//! `explobot sweep compare OLD NEW`: two sweeps of the same runs, paired.
//!
//! Runs are paired by room and run seed. The comparison prints, as Markdown: each sweep's pass
//! rate with its Wilson 95 % interval over the paired runs, every run that flipped (pass → fail,
//! fail → pass) with its room and seed, McNemar's exact test of the flips (a change of the pass
//! rate is called significant at p < 0.05), the change of each continuous figure
//! ([`super::stats::Figures`]), and how many pairs moved the same bytes on every link
//! (equal `link_log_sha256`) — a change meant to alter no behaviour shows all of them equal.
//! Runs of one sweep without a partner are counted, not compared.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::SweepError;
use super::record::RunRecord;
use super::stats::{Figures, mcnemar_exact_p, pass_rate_text};

/// Arguments of `explobot sweep compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct CompareArgs {
    /// The sweep folder before.
    pub old: PathBuf,
    /// The sweep folder after.
    pub new: PathBuf,
}

impl CompareArgs {
    /// Prints the comparison; exit code 0.
    pub fn run(&self) -> Result<ExitCode, SweepError> {
        let text = compare(&read_records(&self.old)?, &read_records(&self.new)?, &self.old, &self.new);
        // the comparison is all there is: a closed standard output loses nothing else
        let _ = crate::output::print_stdout(&text);
        Ok(ExitCode::SUCCESS)
    }
}

/// The runs of a sweep folder's `results.jsonl`.
pub fn read_records(dir: &Path) -> Result<Vec<RunRecord>, SweepError> {
    let path = dir.join("results.jsonl");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| SweepError::Io { path: path.display().to_string(), message: e.to_string() })?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| RunRecord::parse(l, &format!("{}:{}", path.display(), i + 1)))
        .collect()
}

/// The comparison of `old` and `new` (named `old_name`, `new_name`), as Markdown.
pub fn compare(old: &[RunRecord], new: &[RunRecord], old_name: &Path, new_name: &Path) -> String {
    let key = |r: &RunRecord| (r.room.clone(), r.seed);
    let old_by: BTreeMap<(String, u64), &RunRecord> = old.iter().map(|r| (key(r), r)).collect();
    let new_by: BTreeMap<(String, u64), &RunRecord> = new.iter().map(|r| (key(r), r)).collect();
    let pairs: Vec<(&RunRecord, &RunRecord)> =
        old_by.iter().filter_map(|(k, a)| new_by.get(k).map(|b| (*a, *b))).collect();
    let mut s = String::new();
    let _ = writeln!(s, "# Sweep comparison\n");
    let _ = writeln!(s, "- old: `{}` ({} runs)", old_name.display(), old.len());
    let _ = writeln!(s, "- new: `{}` ({} runs)", new_name.display(), new.len());
    let _ = writeln!(
        s,
        "- paired by room and seed: {} runs ({} only in old, {} only in new)\n",
        pairs.len(),
        old_by.len() - pairs.len(),
        new_by.len() - pairs.len()
    );
    let passed = |f: fn(&(&RunRecord, &RunRecord)) -> bool| pairs.iter().filter(|p| f(p)).count();
    let (old_pass, new_pass) = (passed(|p| p.0.verdict.passed()), passed(|p| p.1.verdict.passed()));
    let _ = writeln!(s, "## Pass rate\n");
    let _ = writeln!(s, "- old: {}", pass_rate_text(old_pass, pairs.len()));
    let _ = writeln!(s, "- new: {}", pass_rate_text(new_pass, pairs.len()));
    let broke: Vec<&(&RunRecord, &RunRecord)> =
        pairs.iter().filter(|p| p.0.verdict.passed() && !p.1.verdict.passed()).collect();
    let fixed: Vec<&(&RunRecord, &RunRecord)> =
        pairs.iter().filter(|p| !p.0.verdict.passed() && p.1.verdict.passed()).collect();
    let p = mcnemar_exact_p(broke.len(), fixed.len());
    let verdict = if p < 0.05 { "significant" } else { "not significant" };
    let _ = writeln!(
        s,
        "- flips: {} pass → fail, {} fail → pass; McNemar's exact test p = {p:.4} ({verdict} at 0.05)\n",
        broke.len(),
        fixed.len()
    );
    for (title, list) in [("Pass → fail", &broke), ("Fail → pass", &fixed)] {
        if list.is_empty() {
            continue;
        }
        let _ = writeln!(s, "### {title}\n");
        for (a, b) in list.iter() {
            let _ = writeln!(
                s,
                "- {} seed {}: coverage {} → {}{}",
                a.room,
                a.seed,
                pct(a.coverage),
                pct(b.coverage),
                b.reason
                    .as_deref()
                    .filter(|_| !b.verdict.passed())
                    .map_or(String::new(), |r| format!("; {r}"))
            );
        }
        let _ = writeln!(s);
    }
    let (fo, fnew) = (Figures::of(pairs.iter().map(|p| p.0)), Figures::of(pairs.iter().map(|p| p.1)));
    let _ = writeln!(s, "## Figures over the paired runs\n");
    let _ = writeln!(s, "| figure | old | new | change |");
    let _ = writeln!(s, "|---|---:|---:|---:|");
    // A figure a sweep's results do not carry (an older binary's) is shown as "-".
    let touch = |f: &Figures, v: f64| (f.with_touches > 0).then_some(v);
    let belief = |f: &Figures, v: f64| (f.with_belief > 0).then_some(v);
    let unrecovered = |f: &Figures| {
        (f.after_contact > 0).then(|| 100.0 * f.after_contact_unrecovered as f64 / f.after_contact as f64)
    };
    let rows: [(&str, Option<f64>, Option<f64>, usize); 8] = [
        (
            "touches per 100 moves",
            touch(&fo, fo.touches_per_100_moves),
            touch(&fnew, fnew.touches_per_100_moves),
            2,
        ),
        (
            "runs with no touch",
            touch(&fo, fo.runs_without_touch as f64),
            touch(&fnew, fnew.runs_without_touch as f64),
            0,
        ),
        (
            "hard collisions",
            touch(&fo, fo.hard_collisions as f64),
            touch(&fnew, fnew.hard_collisions as f64),
            0,
        ),
        (
            "runs with a hard collision",
            touch(&fo, fo.runs_with_hard as f64),
            touch(&fnew, fnew.runs_with_hard as f64),
            0,
        ),
        (
            "belief error p95, median (m)",
            belief(&fo, fo.belief_p95_median_m),
            belief(&fnew, fnew.belief_p95_median_m),
            3,
        ),
        ("belief error, largest (m)", belief(&fo, fo.belief_max_m), belief(&fnew, fnew.belief_max_m), 3),
        ("contacts with belief > 3 cm three moves on (%)", unrecovered(&fo), unrecovered(&fnew), 1),
        ("mean coverage (%)", Some(100.0 * fo.mean_coverage), Some(100.0 * fnew.mean_coverage), 1),
    ];
    let show = |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
    for (name, a, b, digits) in rows {
        let change = a.zip(b).map_or("-".to_string(), |(a, b)| format!("{:+.digits$}", b - a));
        let _ = writeln!(s, "| {name} | {} | {} | {change} |", show(a, digits), show(b, digits));
    }
    let hashed: Vec<_> = pairs
        .iter()
        .filter_map(|(a, b)| Some((a.link_log_sha256.as_ref()?, b.link_log_sha256.as_ref()?)))
        .filter(|(a, b)| !a.is_empty() && !b.is_empty())
        .collect();
    let same = hashed.iter().filter(|(a, b)| a == b).count();
    let _ = writeln!(
        s,
        "\n## Link bytes\n\n{same} of {} paired runs with a link-log hash moved the same bytes on every link.",
        hashed.len()
    );
    s
}

fn pct(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{:.1}%", v * 100.0))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn run(room: &str, seed: u64, pass: bool, hash: &str) -> RunRecord {
        let line = format!(
            r#"{{"index":0,"room":"{room}","scenario":"s","seed":{seed},"verdict":"{}","coverage":0.5,"moves":100,
               "touches":{{"count":2,"hard":0,"unseen":1,"per_100_moves":2.0,"fastest_approach_m_s":0.05,"largest_push_m":0.01}},
               "link_log_sha256":"{hash}"}}"#,
            if pass { "pass" } else { "fail" }
        );
        RunRecord::parse(&line.replace('\n', ""), "test").unwrap()
    }

    #[test]
    fn flips_are_listed_and_tested() {
        let old = [
            run("gen:flat:1", 1, true, "a"),
            run("gen:flat:1", 2, false, "b"),
            run("gen:flat:2", 1, false, "c"),
        ];
        let new = [
            run("gen:flat:1", 1, false, "x"),
            run("gen:flat:1", 2, false, "b"),
            run("gen:flat:3", 1, true, "d"),
        ];
        let text = compare(&old, &new, Path::new("old"), Path::new("new"));
        assert!(text.contains("paired by room and seed: 2 runs (1 only in old, 1 only in new)"), "{text}");
        assert!(text.contains("1 pass → fail, 0 fail → pass"), "{text}");
        assert!(text.contains("- gen:flat:1 seed 1: coverage 50.0% → 50.0%"), "{text}");
        assert!(text.contains("p = 1.0000 (not significant"), "{text}");
        assert!(text.contains("1 of 2 paired runs with a link-log hash moved the same bytes"), "{text}");
        assert!(text.contains("| touches per 100 moves | 2.00 | 2.00 | +0.00 |"), "{text}");
    }
}
