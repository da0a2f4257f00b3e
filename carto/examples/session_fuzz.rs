//! A stable-toolchain fuzzer for [`carto::fuzzing::run`] (issue 45), for machines where
//! libFuzzer (`carto/fuzz/`, which wants `cargo fuzz` on nightly) cannot run: it mutates seed
//! inputs (the `carto/fuzz/corpus/session/` files written from recorded runs) with a seeded RNG
//! and runs each, catching panics, for a bounded time. No coverage feedback: it is a blind
//! mutator, so it complements, not replaces, libFuzzer. Failing inputs are written to
//! `--artifacts` and the run exits 1.
//!
//! ```sh
//! cargo run --release -p carto --example session_fuzz -- \
//!     --corpus carto/fuzz/corpus/session --seconds 300 --seed 1
//! ```

#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::path::PathBuf;
use std::time::{Duration, Instant};

use carto::fuzzing::{MAX_INPUT, run};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

struct Args {
    corpus: PathBuf,
    artifacts: PathBuf,
    seconds: u64,
    seed: u64,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        corpus: PathBuf::from("carto/fuzz/corpus/session"),
        artifacts: PathBuf::from("carto/fuzz/artifacts/session"),
        seconds: 60,
        seed: 1,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or_else(|| format!("{flag} needs a value"))?;
        match flag.as_str() {
            "--corpus" => a.corpus = value.into(),
            "--artifacts" => a.artifacts = value.into(),
            "--seconds" => a.seconds = value.parse().map_err(|e| format!("--seconds: {e}"))?,
            "--seed" => a.seed = value.parse().map_err(|e| format!("--seed: {e}"))?,
            other => return Err(format!("unknown flag {other}")),
        }
    }
    Ok(a)
}

/// One to eight random edits: byte flips, inserts, deletes, duplicated ranges, splices with
/// another seed, and new op tags.
fn mutate(rng: &mut ChaCha8Rng, input: &mut Vec<u8>, other: &[u8]) {
    for _ in 0..rng.random_range(1..=8) {
        let len = input.len();
        match rng.random_range(0..7) {
            0 if len > 0 => {
                let i = rng.random_range(0..len);
                input[i] ^= 1 << rng.random_range(0..8);
            }
            1 => {
                let i = rng.random_range(0..=len);
                let b: u8 = rng.random();
                input.insert(i, b);
            }
            2 if len > 1 => {
                let i = rng.random_range(0..len);
                let n = rng.random_range(1..=(len - i).min(64));
                input.drain(i..i + n);
            }
            3 if len > 1 => {
                let i = rng.random_range(0..len);
                let n = rng.random_range(1..=(len - i).min(256));
                let chunk = input[i..i + n].to_vec();
                let at = rng.random_range(0..=input.len());
                input.splice(at..at, chunk);
            }
            4 if !other.is_empty() => {
                let i = rng.random_range(0..other.len());
                let n = rng.random_range(1..=(other.len() - i).min(512));
                let at = rng.random_range(0..=input.len());
                input.splice(at..at, other[i..i + n].iter().copied());
            }
            5 => {
                // an op tag: a disconnect, connect, link toggle or dictionary frame
                let tags = [4u8, 12, 5, 6, 7 | (rng.random_range(0..16u8) << 3)];
                let at = rng.random_range(0..=len);
                input.insert(at, tags[rng.random_range(0..tags.len())]);
            }
            _ => {
                let at = rng.random_range(0..=len);
                input.insert(at, 3 | (rng.random_range(0..32u8) << 3)); // time passes
            }
        }
    }
    input.truncate(MAX_INPUT);
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("session_fuzz: {e}");
            std::process::exit(2);
        }
    };
    let mut seeds: Vec<Vec<u8>> = match std::fs::read_dir(&args.corpus) {
        Ok(dir) => dir.flatten().filter_map(|e| std::fs::read(e.path()).ok()).collect(),
        Err(e) => {
            eprintln!("session_fuzz: no corpus at {} ({e}): random inputs only", args.corpus.display());
            Vec::new()
        }
    };
    seeds.sort();
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let start = Instant::now();
    let limit = Duration::from_secs(args.seconds);
    let (mut execs, mut steps, mut moving, mut failures) = (0u64, 0u64, 0u64, 0u64);
    // The seeds themselves first, unchanged.
    for s in &seeds {
        match run(s) {
            Ok(o) => {
                execs += 1;
                steps += o.steps;
                moving += o.moving_drives;
            }
            Err(v) => {
                failures += 1;
                eprintln!("a seed fails: {v}");
            }
        }
    }
    let seed_execs = execs;
    let mut last_report = Instant::now();
    // Quiet the panic hook: panics are counted and saved.
    std::panic::set_hook(Box::new(|_| {}));
    while start.elapsed() < limit {
        let mut input = if seeds.is_empty() || rng.random_range(0..10) == 0 {
            (0..rng.random_range(1..512)).map(|_| rng.random()).collect()
        } else {
            seeds[rng.random_range(0..seeds.len())].clone()
        };
        let other =
            if seeds.is_empty() { Vec::new() } else { seeds[rng.random_range(0..seeds.len())].clone() };
        mutate(&mut rng, &mut input, &other);
        let result = std::panic::catch_unwind(|| run(&input));
        execs += 1;
        let why = match result {
            Ok(Ok(o)) => {
                steps += o.steps;
                moving += o.moving_drives;
                None
            }
            Ok(Err(v)) => Some(v.to_string()),
            Err(p) => Some(format!(
                "panic: {}",
                p.downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()
            )),
        };
        if let Some(why) = why {
            failures += 1;
            let _ = std::fs::create_dir_all(&args.artifacts);
            let path = args.artifacts.join(format!("crash-{execs}"));
            let _ = std::fs::write(&path, &input);
            eprintln!("finding after {execs} executions: {why} (input in {})", path.display());
        }
        if last_report.elapsed() >= Duration::from_secs(10) {
            last_report = Instant::now();
            println!(
                "#{execs} execs, {:.0} s, {steps} virtual ms, {failures} findings",
                start.elapsed().as_secs_f64()
            );
        }
    }
    let secs = start.elapsed().as_secs_f64();
    let peak_rss = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM")).map(|l| l.to_owned()))
        .unwrap_or_default();
    println!(
        "done: {execs} executions ({seed_execs} seeds from {} files, the rest mutated) in {secs:.0} s \
         ({:.0}/s), {steps} virtual ms ({:.1} h), {moving} moving drive frames, {failures} findings; {peak_rss}",
        seeds.len(),
        execs as f64 / secs,
        steps as f64 / 3.6e6,
    );
    if failures > 0 {
        std::process::exit(1);
    }
}
