//! The statistics a sweep is judged by: a pass rate with its Wilson 95 % interval, the continuous
//! figures of a set of runs, and McNemar's exact test for two sweeps of the same runs.
//!
//! With three run seeds per room and a pass rate near a few per cent, one sweep's count moves by
//! several runs between equally good binaries; the interval says how far, and the paired test
//! says whether a change of the count is more than that.
//!
//! ```
//! use explobot::sweep::stats::{mcnemar_exact_p, wilson_95};
//! let (lo, hi) = wilson_95(12, 200);
//! assert!((lo - 0.0347).abs() < 1e-3 && (hi - 0.1017).abs() < 1e-3);
//! // 9 runs flipped to pass and 1 to fail: unlikely to be noise (p ≈ 0.021).
//! assert!(mcnemar_exact_p(1, 9) < 0.05);
//! assert!(mcnemar_exact_p(3, 5) > 0.5);
//! ```

use super::record::RunRecord;

/// z for a two-sided 95 % interval.
const Z95: f64 = 1.959_963_984_540_054;

/// Wilson's 95 % score interval of a proportion `k` of `n`, as fractions (0, 1 for no runs).
pub fn wilson_95(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let z2 = Z95 * Z95;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = Z95 * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Two-sided exact McNemar p-value for `b` pairs that went one way and `c` the other: the
/// binomial probability, at one half, of a split at least this uneven (1 when nothing flipped).
pub fn mcnemar_exact_p(b: usize, c: usize) -> f64 {
    let n = b + c;
    if n == 0 {
        return 1.0;
    }
    let k = b.min(c);
    // ln C(n, i) − n ln 2, summed for i = 0..=k
    let ln_half_n = -(n as f64) * std::f64::consts::LN_2;
    let mut ln_choose = 0.0;
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_choose += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_choose + ln_half_n).exp();
    }
    (2.0 * tail).min(1.0)
}

/// The pass rate of `k` of `n` and its Wilson 95 % interval, in per cent.
fn rate_pct(k: usize, n: usize) -> (f64, f64, f64) {
    let (lo, hi) = wilson_95(k, n);
    let pct = if n == 0 { 0.0 } else { 100.0 * k as f64 / n as f64 };
    (pct, 100.0 * lo, 100.0 * hi)
}

/// "12 of 600 (2.0 %, Wilson 95 % 1.1–3.5 %)".
pub fn pass_rate_text(k: usize, n: usize) -> String {
    let (pct, lo, hi) = rate_pct(k, n);
    format!("{k} of {n} ({pct:.1} %, Wilson 95 % {lo:.1}–{hi:.1} %)")
}

/// A table cell: "12 (2.0 %, 1.1–3.5 %)".
pub fn pass_cell(k: usize, n: usize) -> String {
    let (pct, lo, hi) = rate_pct(k, n);
    format!("{k} ({pct:.1} %, {lo:.1}–{hi:.1} %)")
}

/// The continuous figures of a set of runs (those with a report).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Figures {
    /// Runs counted.
    pub runs: usize,
    /// Runs that passed.
    pub passed: usize,
    /// Touches per 100 moves, pooled: all touches over all moves.
    pub touches_per_100_moves: f64,
    /// Hard collisions, all runs together.
    pub hard_collisions: u64,
    /// Runs with at least one hard collision.
    pub runs_with_hard: usize,
    /// Runs with no touch at all.
    pub runs_without_touch: usize,
    /// Median over the runs of each run's 95th-percentile belief error, metres.
    pub belief_p95_median_m: f64,
    /// Largest belief error of any run, metres.
    pub belief_max_m: f64,
    /// Contacts judged three `MOVE_DONE`s after (`twin::belief`), all runs together.
    pub after_contact: u64,
    /// Of those, how many left the belief error over 3 cm.
    pub after_contact_unrecovered: u64,
    /// Mean coverage of the scored set.
    pub mean_coverage: f64,
    /// Runs whose results carry touch figures (results of older binaries do not).
    pub with_touches: usize,
    /// Runs whose results carry belief figures.
    pub with_belief: usize,
}

impl Figures {
    /// The figures of `runs`.
    pub fn of<'a>(runs: impl IntoIterator<Item = &'a RunRecord>) -> Figures {
        let runs: Vec<&RunRecord> = runs.into_iter().collect();
        let mut f = Figures {
            runs: runs.len(),
            passed: runs.iter().filter(|r| r.verdict.passed()).count(),
            ..Figures::default()
        };
        let (mut touches, mut moves) = (0u64, 0u64);
        let mut p95s = Vec::new();
        let mut coverage = (0.0, 0usize);
        for r in &runs {
            if let Some(t) = &r.touches {
                f.with_touches += 1;
                touches += u64::from(t.count);
                f.hard_collisions += u64::from(t.hard);
                f.runs_with_hard += usize::from(t.hard > 0);
                f.runs_without_touch += usize::from(t.count == 0);
            }
            moves += r.moves.unwrap_or(0);
            if let Some(b) = &r.belief {
                f.with_belief += 1;
                p95s.push(b.error_p95_m);
                f.belief_max_m = f.belief_max_m.max(b.error_max_m);
                f.after_contact += b.after_contact;
                f.after_contact_unrecovered += b.after_contact_unrecovered;
            }
            if let Some(c) = r.coverage {
                coverage = (coverage.0 + c, coverage.1 + 1);
            }
        }
        f.touches_per_100_moves = if moves == 0 { 0.0 } else { 100.0 * touches as f64 / moves as f64 };
        f.belief_p95_median_m = twin::belief::percentile(&p95s, 0.5);
        f.mean_coverage = if coverage.1 == 0 { 0.0 } else { coverage.0 / coverage.1 as f64 };
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_matches_published_values() {
        // Newcombe (1998), example: 81 of 263 → 0.2553–0.3662.
        let (lo, hi) = wilson_95(81, 263);
        assert!((lo - 0.2553).abs() < 5e-4 && (hi - 0.3662).abs() < 5e-4, "{lo} {hi}");
        // 0 of 10 → 0–0.2775; 10 of 10 → 0.7225–1.
        let (lo, hi) = wilson_95(0, 10);
        assert!(lo == 0.0 && (hi - 0.2775).abs() < 5e-4);
        let (lo, hi) = wilson_95(10, 10);
        assert!((lo - 0.7225).abs() < 5e-4 && (hi - 1.0).abs() < 1e-12);
    }

    #[test]
    fn mcnemar_is_the_two_sided_binomial_tail() {
        // b = 0, c = 6: 2 × 0.5⁶ = 0.03125.
        assert!((mcnemar_exact_p(0, 6) - 0.03125).abs() < 1e-12);
        // b = 2, c = 8: 2 × (1 + 10 + 45) / 1024 = 0.109375.
        assert!((mcnemar_exact_p(2, 8) - 0.109_375).abs() < 1e-12);
        assert_eq!(mcnemar_exact_p(4, 4), 1.0);
        assert_eq!(mcnemar_exact_p(0, 0), 1.0);
        // Large counts do not underflow.
        let p = mcnemar_exact_p(300, 400);
        assert!(p > 0.0 && p < 0.001, "{p}");
    }
}
