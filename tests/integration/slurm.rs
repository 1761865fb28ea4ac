//! scripts/slurm/league.sbatch run as Slurm runs it: the script itself,
//! with bash, once per array task, under the variables Slurm sets
//! (SLURM_JOB_ID, SLURM_ARRAY_JOB_ID, SLURM_ARRAY_TASK_ID, ...), on one
//! local SQLite store. No Slurm is needed: what the script does with
//! those variables is what is under test.

use crate::common;

use common::league::TINY_LEAGUE;
use league::store::{BeatState, Presence, SeatRow, Store, StoreUrl};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const JOB: &str = "4242";

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm/league.sbatch")
}

/// One array task of job JOB on node `node-TASK` with `cpus` CPUs, as
/// `bash league.sbatch` from the project root.
fn task(tmp: &Path, store: &str, id: usize, cpus: usize) -> Command {
    let mut cmd = Command::new("bash");
    cmd.arg(script())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("T2E_STORE", store)
        .env("T2E_POOL", tmp.join("pool"))
        .env("T2E_CONFIG", tmp.join("league.toml"))
        .env("T2E_BIN", env!("CARGO_BIN_EXE_t2e-league"))
        .env("T2E_LOGS", tmp.join("logs"))
        .env("T2E_WAIT_S", "120")
        .env_remove("T2E_SEATS")
        .env_remove("T2E_HOST")
        .env("SLURM_JOB_ID", (4242 + id).to_string())
        .env("SLURM_ARRAY_JOB_ID", JOB)
        .env("SLURM_ARRAY_TASK_ID", id.to_string())
        .env("SLURM_ARRAY_TASK_COUNT", "2")
        .env("SLURM_CPUS_PER_TASK", cpus.to_string())
        .env("SLURMD_NODENAME", format!("node-{id}"))
        .stdout(Stdio::null());
    cmd
}

fn host(id: usize) -> String {
    format!("node-{id}-{JOB}-{id}")
}

fn spawn(tmp: &Path, store: &str, id: usize, cpus: usize) -> Child {
    let log = std::fs::File::create(tmp.join(format!("task-{id}.log"))).unwrap();
    task(tmp, store, id, cpus).stderr(log).spawn().unwrap()
}

fn seats(url: &StoreUrl) -> Vec<SeatRow> {
    if Store::presence(url).ok() != Some(Presence::Present) {
        return Vec::new();
    }
    Store::open_existing(url)
        .and_then(|s| s.seats())
        .unwrap_or_default()
}

fn wait_exit(child: &mut Child, what: &str, limit: Duration) -> std::process::ExitStatus {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if Instant::now() > deadline {
            child.kill().ok();
            panic!("{what} did not finish within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Task 0 (the manager, with the workers its CPUs hold) and task 1 (a
/// worker) share the league's three seats as their CPUs say: one for the
/// 1-CPU task 0, two for the 2-CPU task 1, at threads_per_learner = 1.
/// Then SIGINT, as `--signal=B:INT` sends it before the time limit: every
/// task exits cleanly and gives its seats back, once each.
#[test]
fn an_array_runs_the_manager_and_a_worker_sized_by_their_cpus() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    assert!(TINY_LEAGUE.contains("threads_per_learner = 1"));
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = tmp.join("league.db").display().to_string();
    let url = StoreUrl::parse(&raw).unwrap();
    // The worker first: it must wait for the manager's seats, not take an
    // empty league for a finished one.
    let mut worker = spawn(tmp, &raw, 1, 2);
    std::thread::sleep(Duration::from_secs(2));
    assert!(
        worker.try_wait().unwrap().is_none(),
        "the worker did not wait for the manager: {}",
        std::fs::read_to_string(tmp.join("task-1.log")).unwrap()
    );
    let mut manager = spawn(tmp, &raw, 0, 1);
    let tasks_log = || {
        ["task-0.log", "task-1.log"]
            .map(|f| std::fs::read_to_string(tmp.join(f)).unwrap_or_default())
            .join("\n")
    };
    let deadline = Instant::now() + Duration::from_secs(180);
    let held = loop {
        let seats = seats(&url);
        let held: Vec<(String, String)> = seats
            .iter()
            .filter_map(|s| Some((s.name.clone(), s.host.clone()?)))
            .collect();
        let training = Store::open_existing(&url).is_ok_and(|s| {
            s.match_count().unwrap_or(0) > 0
                && s.heartbeats().is_ok_and(|b| {
                    b.iter()
                        .filter(|b| b.state == BeatState::Training && b.env_steps > 0)
                        .count()
                        == 2
                })
        });
        if held.len() == 3 && training {
            break held;
        }
        for (what, child) in [("task 0", &mut manager), ("task 1", &mut worker)] {
            if let Some(s) = child.try_wait().unwrap() {
                panic!(
                    "{what} exited ({s}) before the league ran:\n{}",
                    tasks_log()
                );
            }
        }
        assert!(
            Instant::now() < deadline,
            "the seats were not all held and training: {seats:?}\n{}",
            tasks_log()
        );
        std::thread::sleep(Duration::from_millis(300));
    };
    let on = |h: &str| held.iter().filter(|(_, x)| x == h).count();
    assert_eq!(
        (on(&host(0)), on(&host(1))),
        (1, 2),
        "seats per task: {held:?}"
    );
    for child in [&manager, &worker] {
        // exec: the task's shell is the program, as Slurm signals it.
        // SAFETY: signalling a process this test started.
        unsafe {
            libc::kill(child.id() as i32, libc::SIGINT);
        }
    }
    for (what, child) in [("task 1", &mut worker), ("task 0", &mut manager)] {
        let status = wait_exit(child, what, Duration::from_secs(120));
        assert!(status.success(), "{what}: {status}\n{}", tasks_log());
    }
    let log = tasks_log();
    assert!(
        log.contains("task 0 of job 4242 on node-0-4242-0, 1 CPUs, 1 seats"),
        "{log}"
    );
    assert!(
        log.contains("task 1 of job 4242 on node-1-4242-1, 2 CPUs, 2 seats"),
        "{log}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_t2e-league"))
        .args(["status", "--json", "--store", &raw])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let seats = json["seats"].as_array().unwrap();
    assert_eq!(seats.len(), 3, "{seats:?}");
    for s in seats {
        // Given back at the signal, taken once: no seat ran twice.
        assert_eq!(s["state"], "open", "{s}");
        assert_eq!(s["claims"], 1, "{s}");
    }
    let hosts: Vec<&str> = json["learners"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|l| l["host"].as_str())
        .collect();
    // The two learners and the evaluator, each under its task's name.
    assert_eq!(hosts.len(), 3, "{}", json["learners"]);
    for h in [host(0), host(1)] {
        assert_eq!(
            hosts.iter().filter(|x| **x == h).count(),
            on(&h),
            "{hosts:?}"
        );
    }
    assert!(
        json["matches"].as_u64().unwrap_or(0) > 0,
        "no match recorded: {json}"
    );
}

/// What the script needs and Slurm does not give is named before anything
/// runs.
#[test]
fn a_missing_store_pool_or_array_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let store = tmp.join("league.db").display().to_string();
    let cases: [(&str, &str); 3] = [
        ("T2E_STORE", "set T2E_STORE to the league store URL"),
        ("T2E_POOL", "set T2E_POOL to the pool folder"),
        ("SLURM_ARRAY_TASK_ID", "submit as an array"),
    ];
    for (unset, says) in cases {
        let out = task(tmp, &store, 0, 1).env_remove(unset).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "ran without {unset}: {err}");
        assert!(err.contains(says), "without {unset}: {err}");
    }
    assert!(!tmp.join("pool").exists() && !tmp.join("league.db").exists());
}
