//! A real one-node Slurm cluster on localhost runs a sweep as a 4-task job array through
//! `deploy/slurm/sweep.sbatch`; the merged shards must equal a local `--jobs 2` run.
//!
//! Needs Debian's `slurm-wlm` and `munge` (`.ci/run` installs them) and root (slurmd starts
//! jobs as their user). It fails, never skips, when either is missing. It writes its own
//! `slurm.conf` and munge key in a temp folder, starts `munged`, `slurmctld` and `slurmd` in the
//! foreground on 127.0.0.1 (free ports, `proctrack/linuxproc`, no cgroup plugins) and stops them
//! when it ends, also when it fails (a guard that kills their process groups); after a failure
//! its temp folder (`explobot-slurm-PID`, with every log) stays for reading. Every wait is
//! bounded.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::os::unix::fs::PermissionsExt;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use explobot::sweep::output::compare_folders;

/// The longest the cluster may take to come up, and the job array to finish.
const LIMIT: Duration = Duration::from_secs(120);

fn repo() -> PathBuf {
    std::env::current_dir().unwrap().parent().unwrap().to_path_buf()
}

fn explobot_path() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let path = exe.parent().and_then(Path::parent).unwrap().join("explobot");
    assert!(path.exists(), "{} missing: cargo build --release -p explobot --bin explobot", path.display());
    path
}

fn require(program: &str) -> PathBuf {
    for dir in ["/usr/sbin", "/usr/bin", "/sbin", "/bin", "/usr/local/sbin", "/usr/local/bin"] {
        let p = Path::new(dir).join(program);
        if p.exists() {
            return p;
        }
    }
    panic!("{program} is missing: apt-get install -y slurm-wlm munge (or run .ci/run)");
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// The daemons and the job: cancelled and killed on drop, whatever happened.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(String, Child)>,
}

impl Cluster {
    fn start(&mut self, name: &str, mut cmd: Command) {
        let log = std::fs::File::create(self.dir.join(format!("{name}.out"))).unwrap();
        cmd.stdin(Stdio::null()).stdout(log.try_clone().unwrap()).stderr(log).process_group(0);
        let child = cmd.spawn().unwrap_or_else(|e| panic!("starting {name}: {e}"));
        self.daemons.push((name.to_string(), child));
    }

    fn slurm(&self, program: &str) -> Command {
        let mut c = Command::new(require(program));
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// Every log the cluster wrote, for a failure message.
    fn logs(&self) -> String {
        let mut out = String::new();
        let mut files: Vec<_> = std::fs::read_dir(&self.dir).unwrap().flatten().map(|e| e.path()).collect();
        files.sort();
        for f in files.iter().filter(|f| f.extension().is_some_and(|e| e == "out" || e == "log")) {
            let text = std::fs::read_to_string(f).unwrap_or_default();
            let tail: Vec<&str> = text.lines().rev().take(15).collect();
            out +=
                &format!("== {}\n{}\n", f.display(), tail.into_iter().rev().collect::<Vec<_>>().join("\n"));
        }
        out
    }

    /// Polls `done` every 200 ms until it holds or [`LIMIT`] passes.
    fn wait_for(&self, what: &str, mut done: impl FnMut() -> bool) {
        let start = Instant::now();
        while !done() {
            assert!(start.elapsed() < LIMIT, "{what}: not within {LIMIT:?}\n{}", self.logs());
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if !self.daemons.is_empty() {
            let _ = self.slurm("scancel").arg("--user=root").status();
        }
        for (_, child) in self.daemons.iter_mut().rev() {
            let group = format!("-{}", child.id());
            let _ = Command::new("kill").args(["-TERM", "--", &group]).status();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(5) {
                if matches!(child.try_wait(), Ok(Some(_))) {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = Command::new("kill").args(["-KILL", "--", &group]).status();
            let _ = child.wait();
        }
    }
}

#[test]
fn a_slurm_job_array_gives_the_same_sweep_as_one_machine() {
    let began = Instant::now();
    let (munged, slurmctld, slurmd) = (require("munged"), require("slurmctld"), require("slurmd"));
    for p in ["sbatch", "sinfo", "scancel"] {
        require(p);
    }
    let uid = Command::new("id").arg("-u").output().unwrap();
    assert_eq!(String::from_utf8_lossy(&uid.stdout).trim(), "0", "the Slurm test runs its daemons as root");
    let explobot = explobot_path();

    let dir = std::env::temp_dir().join(format!("explobot-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for sub in ["state", "spool", "out"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    // munged wants its socket's folder searchable by everyone and its key readable by root only.
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    let key = dir.join("munge.key");
    let key_bytes: Vec<u8> = (0..1024u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect();
    std::fs::write(&key, key_bytes).unwrap();
    std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).unwrap();

    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
    let host = host.trim().split('.').next().unwrap().to_string();
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let d = dir.display();
    let conf = dir.join("slurm.conf");
    std::fs::write(
        &conf,
        format!(
            "ClusterName=explobot\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmctldPort={ctld}\nSlurmdPort={slurmd}\n\
             CommunicationParameters=NoInAddrAny\n\
             AuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket={d}/munge.socket\n\
             SlurmUser=root\nSlurmdUser=root\n\
             StateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/slurmctld.log\nSlurmdLogFile={d}/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n\
             JobCompType=jobcomp/none\nSwitchType=switch/none\nMpiDefault=none\nPlugStackConfig=/dev/null\n\
             SchedulerType=sched/builtin\nSelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n\
             ReturnToService=2\n\
             NodeName=explobot NodeHostname={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=sweep Nodes=explobot Default=YES MaxTime=INFINITE State=UP\n",
            ctld = free_port(),
            slurmd = free_port(),
        ),
    )
    .unwrap();

    let mut cluster = Cluster { dir: dir.clone(), conf: conf.clone(), daemons: Vec::new() };
    let mut cmd = Command::new(munged);
    cmd.arg("--foreground")
        .arg(format!("--key-file={}", key.display()))
        .arg(format!("--socket={d}/munge.socket"))
        .arg(format!("--pid-file={d}/munged.pid"))
        .arg(format!("--log-file={d}/munged.log"))
        .arg(format!("--seed-file={d}/munged.seed"));
    cluster.start("munged", cmd);
    cluster.wait_for("munged's socket", || dir.join("munge.socket").exists());
    let mut cmd = Command::new(slurmctld);
    cmd.args(["-D", "-f"]).arg(&conf);
    cluster.start("slurmctld", cmd);
    let mut cmd = Command::new(slurmd);
    cmd.args(["-D", "-N", "explobot", "-f"]).arg(&conf);
    cluster.start("slurmd", cmd);
    cluster.wait_for("the node to come up idle", || {
        let out = cluster.slurm("sinfo").args(["-h", "-N", "-o", "%T"]).output().unwrap();
        String::from_utf8_lossy(&out.stdout).trim() == "idle"
    });
    let up = began.elapsed();

    // 2 scenarios × 4 seeds, 4 tasks of one CPU each, through the shipped batch script.
    let sweep = ["scenarios/empty.ron", "scenarios/pocket.ron", "--seeds", "1..4"];
    let mut sbatch = cluster.slurm("sbatch");
    sbatch
        .current_dir(repo())
        .env("EXPLOBOT", &explobot)
        .env("SWEEP_DIR", dir.join("out"))
        .args(["--wait", "--array=1-4", "--cpus-per-task=1"])
        .arg(format!("--output={d}/job-%A_%a.log"))
        .arg("deploy/slurm/sweep.sbatch")
        .args(sweep)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut job = sbatch.spawn().unwrap();
    let mut job_status = None;
    cluster.wait_for("the job array", || {
        job_status = job.try_wait().unwrap();
        job_status.is_some()
    });
    let job_out = job.wait_with_output().unwrap();
    let job_code = job_status.and_then(|s| s.code());

    let shards: Vec<PathBuf> = (1..=4).map(|k| dir.join("out").join(format!("shard-{k}"))).collect();
    let merged = Command::new(&explobot)
        .args(["sweep", "merge"])
        .args(&shards)
        .arg("--out")
        .arg(dir.join("merged"))
        .output()
        .unwrap();
    let local = Command::new(&explobot)
        .current_dir(repo())
        .arg("sweep")
        .args(sweep)
        .args(["--jobs", "2", "--quiet", "--out"])
        .arg(dir.join("local"))
        .output()
        .unwrap();
    assert!(
        matches!(local.status.code(), Some(0 | 1)),
        "local sweep: {}",
        String::from_utf8_lossy(&local.stderr)
    );
    assert_eq!(
        merged.status.code(),
        local.status.code(),
        "merge: {}\nsbatch: {}\n{}",
        String::from_utf8_lossy(&merged.stderr),
        String::from_utf8_lossy(&job_out.stderr),
        cluster.logs()
    );
    // sbatch --wait exits with the highest exit code of the array's tasks.
    assert_eq!(job_code, local.status.code(), "{}", cluster.logs());
    for shard in &shards {
        let lines = std::fs::read_to_string(shard.join("results.jsonl")).unwrap();
        assert_eq!(lines.lines().count(), 2, "{}", shard.display());
    }
    compare_folders(&dir.join("local"), &dir.join("merged")).unwrap();
    eprintln!("slurm test: cluster up in {:.1?}, whole test {:.1?}", up, began.elapsed());
    drop(cluster);
    std::fs::remove_dir_all(&dir).unwrap();
}
