//! The run list: which rooms, which seeds, in which order, and which share of it this process
//! runs.
//!
//! Order: rooms in the order given (scenario files as listed on the command line, then each
//! `--generate STYLE:COUNT` in order, generator seeds `1..=COUNT`), and for each room its seeds
//! in `--seeds` order. Run `i` of that list has index `i`; `--shard K/N` takes the runs with
//! `i % N == K - 1`.

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::SweepError;
use twin::oracle::Oracle;
use twin::setup::RunSetup;
use twin_roomgen::{RoomStyle, generate};

/// Seeds to run every room with: `1..10` (inclusive), `7`, or a comma list of both (`1..5,9`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Seeds(pub Vec<u64>);

/// A `--seeds`, `--generate` or `--shard` value, or the shard's environment, that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// Not a whole number.
    #[error("'{0}' is not a seed (a whole number >= 0)")]
    NotASeed(String),
    /// `A..B` with `A > B`.
    #[error("'{0}' is empty: A..B needs A <= B (both inclusive)")]
    EmptyRange(String),
    /// A range too long.
    #[error("'{part}' has more than {max} seeds")]
    TooManySeeds {
        /// The range as written.
        part: String,
        /// The most seeds one range may hold.
        max: u64,
    },
    /// A seed given twice.
    #[error("seed {0} is listed twice")]
    SeedTwice(u64),
    /// No `:` in a `--generate` value.
    #[error("'{spec}' is not STYLE:COUNT (styles: {styles})")]
    NotStyleCount {
        /// The value.
        spec: String,
        /// The style names.
        styles: String,
    },
    /// An unknown style name.
    #[error("unknown style '{style}' (styles: {styles})")]
    UnknownStyle {
        /// The name given.
        style: String,
        /// The style names.
        styles: String,
    },
    /// A room count that is not 1 to 100000.
    #[error("'{0}' is not a room count (1 to 100000)")]
    NotACount(String),
    /// Not `K/N`.
    #[error("'{0}' is not K/N")]
    NotShard(String),
    /// `K/N` out of range.
    #[error("shard {number}/{count}: K/N needs 1 <= K <= N")]
    BadShard {
        /// K.
        number: u64,
        /// N.
        count: u64,
    },
    /// An environment variable that should be a number.
    #[error("{name}={value} is not a number")]
    NotANumber {
        /// The variable.
        name: String,
        /// Its value.
        value: String,
    },
    /// `EXPLOBOT_SHARD` does not parse.
    #[error("EXPLOBOT_SHARD: {0}")]
    ShardVariable(Box<PlanError>),
    /// A Slurm or Kubernetes variable is missing (the message names it).
    #[error("{0}")]
    Missing(&'static str),
    /// A Slurm task id outside its array.
    #[error("SLURM_ARRAY_TASK_ID {id} is not in the range {min}..:{step}: use --array=A-B[:STEP]")]
    NotInArray {
        /// `SLURM_ARRAY_TASK_ID`.
        id: u64,
        /// `SLURM_ARRAY_TASK_MIN`.
        min: u64,
        /// `SLURM_ARRAY_TASK_STEP`.
        step: u64,
    },
    /// `--shard auto` outside any job array.
    #[error(
        "--shard auto found no shard: set EXPLOBOT_SHARD=K/N, run in a Slurm job array, or in a Kubernetes Indexed Job with EXPLOBOT_SHARD_COUNT"
    )]
    NoShard,
}

impl FromStr for Seeds {
    type Err = PlanError;

    fn from_str(s: &str) -> Result<Seeds, PlanError> {
        const MAX: u64 = 1_000_000;
        let mut seeds = Vec::new();
        for part in s.split(',') {
            let part = part.trim();
            let num = |t: &str| t.trim().parse::<u64>().map_err(|_| PlanError::NotASeed(t.to_string()));
            match part.split_once("..") {
                Some((a, b)) => {
                    let (a, b) = (num(a)?, num(b.strip_prefix('=').unwrap_or(b))?);
                    if a > b {
                        return Err(PlanError::EmptyRange(part.to_string()));
                    }
                    if b - a >= MAX {
                        return Err(PlanError::TooManySeeds { part: part.to_string(), max: MAX });
                    }
                    seeds.extend(a..=b);
                }
                None => seeds.push(num(part)?),
            }
        }
        let mut sorted = seeds.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(PlanError::SeedTwice(w[0]));
        }
        Ok(Seeds(seeds))
    }
}

/// `STYLE:COUNT`: generated rooms of one style, generator seeds `1..=COUNT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GenerateSpec {
    /// The generator's style.
    pub style: RoomStyle,
    /// How many rooms (generator seeds 1..=count).
    pub count: u64,
}

impl FromStr for GenerateSpec {
    type Err = PlanError;

    fn from_str(s: &str) -> Result<GenerateSpec, PlanError> {
        let names = || RoomStyle::ALL.map(RoomStyle::name).join(", ");
        let (style, count) = s
            .split_once(':')
            .ok_or_else(|| PlanError::NotStyleCount { spec: s.to_string(), styles: names() })?;
        let style = RoomStyle::ALL
            .into_iter()
            .find(|st| st.name() == style)
            .ok_or_else(|| PlanError::UnknownStyle { style: style.to_string(), styles: names() })?;
        let count = count
            .parse::<u64>()
            .ok()
            .filter(|c| (1..=100_000).contains(c))
            .ok_or_else(|| PlanError::NotACount(count.to_string()))?;
        Ok(GenerateSpec { style, count })
    }
}

/// One share of the run list: runs with `index % count == number - 1` (`number` is 1-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number, `1..=count`.
    pub number: u64,
    /// Number of shards.
    pub count: u64,
}

impl Shard {
    /// The whole run list.
    pub const ALL: Shard = Shard { number: 1, count: 1 };

    /// Whether run `index` belongs to this shard.
    pub fn contains(self, index: usize) -> bool {
        index as u64 % self.count == self.number - 1
    }

    /// The shard from the environment: `EXPLOBOT_SHARD=K/N` (a CI matrix), a Slurm job array
    /// (`SLURM_ARRAY_TASK_ID`, `SLURM_ARRAY_TASK_MIN`, `SLURM_ARRAY_TASK_COUNT`, and
    /// `SLURM_ARRAY_TASK_STEP` when set), or a Kubernetes Indexed Job (`JOB_COMPLETION_INDEX`,
    /// 0-based, with `EXPLOBOT_SHARD_COUNT`), first match wins.
    pub fn from_env(var: impl Fn(&str) -> Option<String>) -> Result<Shard, PlanError> {
        let num = |name: &str| -> Result<Option<u64>, PlanError> {
            match var(name) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse::<u64>()
                    .map(Some)
                    .map_err(|_| PlanError::NotANumber { name: name.to_string(), value: v }),
            }
        };
        if let Some(v) = var("EXPLOBOT_SHARD") {
            return v.parse::<Shard>().map_err(|e| PlanError::ShardVariable(Box::new(e)));
        }
        if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?
                .ok_or(PlanError::Missing("SLURM_ARRAY_TASK_ID without SLURM_ARRAY_TASK_MIN"))?;
            let count = num("SLURM_ARRAY_TASK_COUNT")?
                .ok_or(PlanError::Missing("SLURM_ARRAY_TASK_ID without SLURM_ARRAY_TASK_COUNT"))?;
            let step = num("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            let offset = id.checked_sub(min).filter(|o| o % step == 0).ok_or(PlanError::NotInArray {
                id,
                min,
                step,
            })?;
            return Shard::new(offset / step + 1, count);
        }
        if let Some(index) = num("JOB_COMPLETION_INDEX")? {
            let count = num("EXPLOBOT_SHARD_COUNT")?.ok_or(PlanError::Missing(
                "JOB_COMPLETION_INDEX is set but EXPLOBOT_SHARD_COUNT (the Job's completions) is not",
            ))?;
            return Shard::new(index + 1, count);
        }
        Err(PlanError::NoShard)
    }

    fn new(number: u64, count: u64) -> Result<Shard, PlanError> {
        if count == 0 || number == 0 || number > count {
            return Err(PlanError::BadShard { number, count });
        }
        Ok(Shard { number, count })
    }
}

impl FromStr for Shard {
    type Err = PlanError;

    fn from_str(s: &str) -> Result<Shard, PlanError> {
        let (k, n) = s.split_once('/').ok_or_else(|| PlanError::NotShard(s.to_string()))?;
        let parse = |t: &str| t.trim().parse::<u64>().map_err(|_| PlanError::NotShard(s.to_string()));
        Shard::new(parse(k)?, parse(n)?)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.number, self.count)
    }
}

/// `--shard`: a fixed share or `auto` (from the environment).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardArg {
    /// `K/N`.
    Fixed(Shard),
    /// `auto`.
    Auto,
}

impl FromStr for ShardArg {
    type Err = PlanError;

    fn from_str(s: &str) -> Result<ShardArg, PlanError> {
        if s == "auto" { Ok(ShardArg::Auto) } else { s.parse().map(ShardArg::Fixed) }
    }
}

/// Where a room comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A scenario file, as given on the command line.
    File(PathBuf),
    /// `explobot generate --style STYLE --seed SEED`.
    Generated {
        /// Style.
        style: RoomStyle,
        /// Generator seed (the room's own run seed too).
        seed: u64,
    },
}

/// A room of the sweep, loaded.
#[derive(Debug, Clone)]
pub struct Room {
    /// The room's id in results: the path as given, or `gen:STYLE:SEED` for a generated room.
    pub id: String,
    /// Where it comes from.
    pub source: Source,
    /// The scenario, ready to run.
    pub loaded: RunSetup,
}

impl Room {
    /// The group the summary's pass rates are given for: the file, or `generated STYLE`.
    pub fn group(&self) -> String {
        group_of(&self.id)
    }
}

/// The style and room seed of a generated room's id (`gen:STYLE:SEED`); `None` for a file.
pub fn generated_room(room_id: &str) -> Option<(&str, &str)> {
    room_id.strip_prefix("gen:").and_then(|r| r.split_once(':'))
}

/// The summary group of a room id.
pub fn group_of(room_id: &str) -> String {
    match generated_room(room_id) {
        Some((style, _)) => format!("generated {style}"),
        None => room_id.to_string(),
    }
}

/// The command that re-runs one run.
pub fn rerun_command(room_id: &str, seed: u64) -> String {
    match generated_room(room_id) {
        Some((style, room_seed)) => format!(
            "explobot generate --style {style} --seed {room_seed} --out {style}-{room_seed}.ron && \
             explobot run {style}-{room_seed}.ron --seed {seed}"
        ),
        None => format!("explobot run {room_id} --seed {seed}"),
    }
}

/// One run: a room and a seed, at its place in the run list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Run {
    /// Place in the full run list (0-based).
    pub index: usize,
    /// Index into [`Plan::rooms`].
    pub room: usize,
    /// The run's seed.
    pub seed: u64,
}

/// The whole sweep: rooms, runs, and what identifies it for `merge`.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The rooms, in run-list order.
    pub rooms: Vec<Room>,
    /// Every run of the sweep (all shards), in order.
    pub runs: Vec<Run>,
    /// What identifies the sweep (written as `sweep.json`).
    pub manifest: Manifest,
}

/// `sweep.json`: the run list, so that `merge` can check its shards belong together and are all
/// there. Equal for every shard of a sweep and for a one-machine run of it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    /// Format of the sweep folder.
    pub format: u32,
    /// Runs in the whole sweep.
    pub runs: usize,
    /// `--seeds`, or `None` for each room's own seed.
    pub seeds: Option<Seeds>,
    /// The rooms: id, scenario name, SHA-256 of the scenario text.
    pub rooms: Vec<ManifestRoom>,
    /// `--known-room`: Carto was given each room's surfaces. Written only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub known_room: bool,
    /// `--known-echoes`: Carto was given every point the sonar heard. Written only when set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub known_echoes: bool,
}

/// A room in `sweep.json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ManifestRoom {
    /// Path as given, or `gen:STYLE:SEED`.
    pub id: String,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text.
    pub sha256: String,
}

/// Current `sweep.json` format.
pub const FORMAT: u32 = 1;

impl Plan {
    /// Loads every scenario file, generates every room and lays out the runs; every run gives
    /// Carto what `oracle` says ([`twin::oracle`]).
    pub fn build(
        files: &[PathBuf],
        generated: &[GenerateSpec],
        seeds: Option<&Seeds>,
        oracle: Oracle,
    ) -> Result<Plan, SweepError> {
        let mut rooms = Vec::new();
        for path in files {
            let loaded = RunSetup::load(path).map_err(SweepError::Scenario)?.with_oracle(oracle);
            rooms.push(Room { id: path.display().to_string(), source: Source::File(path.clone()), loaded });
        }
        for spec in generated {
            for seed in 1..=spec.count {
                let text = generate(spec.style, seed).map_err(SweepError::Generate)?.to_ron();
                let id = format!("gen:{}:{seed}", spec.style.name());
                let loaded = RunSetup::from_ron_str(&text, &id, Path::new("."))
                    .map_err(SweepError::Scenario)?
                    .with_oracle(oracle);
                rooms.push(Room { id, source: Source::Generated { style: spec.style, seed }, loaded });
            }
        }
        if rooms.is_empty() {
            return Err(SweepError::Input(
                "nothing to run: give scenario files or --generate STYLE:COUNT".into(),
            ));
        }
        let mut runs = Vec::new();
        for (r, room) in rooms.iter().enumerate() {
            let own = [room.loaded.scenario.seed];
            let list = seeds.map_or(&own[..], |s| &s.0[..]);
            for &seed in list {
                runs.push(Run { index: runs.len(), room: r, seed });
            }
        }
        let manifest = Manifest {
            format: FORMAT,
            runs: runs.len(),
            seeds: seeds.cloned(),
            rooms: rooms
                .iter()
                .map(|r| ManifestRoom {
                    id: r.id.clone(),
                    scenario: r.loaded.scenario.name.clone(),
                    sha256: hex::encode(Sha256::digest(r.loaded.text.as_bytes())),
                })
                .collect(),
            known_room: oracle == Oracle::Room,
            known_echoes: oracle == Oracle::Echoes,
        };
        Ok(Plan { rooms, runs, manifest })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_parse_ranges_lists_and_reject_nonsense() {
        assert_eq!("1..3".parse::<Seeds>(), Ok(Seeds(vec![1, 2, 3])));
        assert_eq!("1..=2,9".parse::<Seeds>(), Ok(Seeds(vec![1, 2, 9])));
        assert_eq!("7".parse::<Seeds>(), Ok(Seeds(vec![7])));
        for bad in ["", "a..3", "5..1", "1..3,2", "-1", "1..99999999999"] {
            assert!(bad.parse::<Seeds>().is_err(), "{bad}");
        }
    }

    #[test]
    fn generate_specs_name_a_style_and_a_count() {
        assert_eq!("flat:3".parse::<GenerateSpec>(), Ok(GenerateSpec { style: RoomStyle::Flat, count: 3 }));
        for bad in ["flat", "castle:3", "flat:0", "flat:x"] {
            assert!(bad.parse::<GenerateSpec>().is_err(), "{bad}");
        }
    }

    #[test]
    fn shards_split_the_run_list_round_robin() {
        let s: Shard = "2/3".parse().unwrap_or(Shard::ALL);
        let mine: Vec<usize> = (0..8).filter(|&i| s.contains(i)).collect();
        assert_eq!(mine, [1, 4, 7]);
        for bad in ["0/3", "4/3", "1/0", "1", "a/b"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| vars.iter().find(|(k, _)| *k == name).map(|(_, v)| v.to_string())
    }

    #[test]
    fn shard_auto_reads_slurm_kubernetes_and_ci() {
        // sbatch --array=10-13: ids 10..=13, min 10, count 4.
        let slurm =
            [("SLURM_ARRAY_TASK_ID", "12"), ("SLURM_ARRAY_TASK_MIN", "10"), ("SLURM_ARRAY_TASK_COUNT", "4")];
        assert_eq!(Shard::from_env(env(&slurm)), Ok(Shard { number: 3, count: 4 }));
        // --array=0-6:2 → ids 0, 2, 4, 6.
        let stepped = [
            ("SLURM_ARRAY_TASK_ID", "6"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
        ];
        assert_eq!(Shard::from_env(env(&stepped)), Ok(Shard { number: 4, count: 4 }));
        let k8s = [("JOB_COMPLETION_INDEX", "0"), ("EXPLOBOT_SHARD_COUNT", "5")];
        assert_eq!(Shard::from_env(env(&k8s)), Ok(Shard { number: 1, count: 5 }));
        assert_eq!(Shard::from_env(env(&[("EXPLOBOT_SHARD", "2/2")])), Ok(Shard { number: 2, count: 2 }));
        assert!(
            Shard::from_env(env(&[("JOB_COMPLETION_INDEX", "5"), ("EXPLOBOT_SHARD_COUNT", "5")])).is_err()
        );
        assert!(Shard::from_env(env(&[("JOB_COMPLETION_INDEX", "0")])).is_err());
        assert!(Shard::from_env(env(&[])).is_err());
    }

    #[test]
    fn groups_and_rerun_commands() {
        assert_eq!(group_of("scenarios/noisy.ron"), "scenarios/noisy.ron");
        assert_eq!(group_of("gen:flat:3"), "generated flat");
        assert_eq!(rerun_command("scenarios/noisy.ron", 6), "explobot run scenarios/noisy.ron --seed 6");
        assert_eq!(
            rerun_command("gen:office:2", 9),
            "explobot generate --style office --seed 2 --out office-2.ron && explobot run office-2.ron --seed 9"
        );
    }
}
