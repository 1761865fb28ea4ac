//! A league folder made by today's binary opens, resumes, exports and
//! exploits, with its store on SQLite (league.db in the league folder) and
//! on PostgreSQL (a fresh database on the server of common/postgres.rs,
//! snapshots in a --pool folder): the round trip a user makes, as
//! processes. The manager is killed with SIGKILL once both learners have
//! a checkpoint, so the second `run` has work left to resume; the
//! invariants after the kill and at the end are `common::league::check`'s.
//! tests/integration/stored_runs.rs holds the same guarantee for a league
//! folder of an earlier build.

use crate::common;

use common::league::{check, TINY_LEAGUE};
use league::run::folder::layout::LeagueDir;
use league::store::StoreUrl;
use serde_json::Value;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};
use t2e_core::env::Side;
use t2e_learners::learn::persist::RunDir;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_t2e-league")
}

/// Env steps per learner: the tiny league cut to a third (as league.rs's
/// short leagues), so the resumed run is most of the work and still quick.
const BUDGET: u64 = 3_200;

/// The tiny league at `BUDGET`, with a validation panel for the target
/// snapshots (3 episodes of one randomised expert team on a generated map
/// nobody trains on): what `export --best target` chooses by.
fn config() -> String {
    let text = TINY_LEAGUE
        .replace(
            "env_steps_per_learner = 9_600",
            &format!("env_steps_per_learner = {BUDGET}"),
        )
        .replace(
            "[evaluator]\n",
            "[evaluator]\nvalidation_maps = \"generated:1@1001:small\"\nvalidation_captors = [\"expert:1\"]\n",
        );
    assert!(
        text.contains(&format!("env_steps_per_learner = {BUDGET}"))
            && text.contains("validation_captors"),
        "tiny_league.toml changed shape: {text}"
    );
    text
}

/// Where a league's store is, and how each command is told so.
enum Backend {
    /// league.db in the league folder: `--dir` alone.
    Sqlite,
    /// A PostgreSQL database: `--store URL --pool POOL` (and, for `run`,
    /// `--dir` for the local workers' logs).
    Postgres(String),
}

/// One league under test: its temporary folder and where its parts are.
struct Folder {
    tmp: PathBuf,
    backend: Backend,
}

impl Folder {
    /// The league folder (SQLite), or the shared pool (PostgreSQL).
    fn root(&self) -> PathBuf {
        match self.backend {
            Backend::Sqlite => self.tmp.join("league"),
            Backend::Postgres(_) => self.tmp.join("pool"),
        }
    }

    /// Where the learners' and workers' logs are.
    fn logs(&self) -> PathBuf {
        match self.backend {
            Backend::Sqlite => self.tmp.join("league").join("logs"),
            Backend::Postgres(_) => self.tmp.join("manager").join("logs"),
        }
    }

    fn dir(&self) -> LeagueDir {
        match &self.backend {
            Backend::Sqlite => LeagueDir::new(self.root()),
            Backend::Postgres(url) => {
                LeagueDir::with_store(self.root(), StoreUrl::parse(url).unwrap())
            }
        }
    }

    /// The arguments that name the league to `status`, `export`, `exploit`.
    fn league_args(&self) -> Vec<OsString> {
        match &self.backend {
            Backend::Sqlite => vec!["--dir".into(), self.root().into()],
            Backend::Postgres(url) => vec![
                "--store".into(),
                url.into(),
                "--pool".into(),
                self.root().into(),
            ],
        }
    }

    /// `run`'s arguments: with a store, `--dir` is the local logs' folder.
    fn run_args(&self) -> Vec<OsString> {
        let mut args: Vec<OsString> = vec!["run".into()];
        if let Backend::Postgres(_) = self.backend {
            args.extend(["--dir".into(), self.tmp.join("manager").into()]);
        }
        args.extend(self.league_args());
        args
    }

    /// `t2e-league COMMAND LEAGUE-ARGS ARGS`, required to succeed.
    fn t2e(&self, command: &str, args: &[&str]) -> Output {
        let out = Command::new(bin())
            .arg(command)
            .args(self.league_args())
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "t2e-league {command} {args:?}: {}\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        out
    }

    fn status(&self) -> Value {
        let out = self.t2e("status", &["--json"]);
        serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("status --json: not JSON ({e})"))
    }

    fn read(&self, file: &str) -> String {
        std::fs::read_to_string(self.tmp.join(file)).unwrap_or_default()
    }
}

/// The env steps of each main learner's resume point (its state.json), if
/// it has one yet.
fn resume_points(dir: &LeagueDir) -> Vec<Option<u64>> {
    [Side::Captors, Side::Target]
        .iter()
        .map(|&side| {
            RunDir::new(dir.learner_dir(side))
                .read_state()
                .ok()
                .map(|s| s.env_steps)
        })
        .collect()
}

/// Every process below `pid` (the manager's workers and learners).
fn descendants(pid: u32) -> Vec<i64> {
    let mut out = Vec::new();
    let mut stack = vec![pid as i64];
    while let Some(p) = stack.pop() {
        for c in common::children_of(p as u32, "") {
            out.push(c);
            stack.push(c);
        }
    }
    out
}

/// Gone, or a zombie nobody reaped yet: it writes nothing any more.
fn is_gone(pid: i64) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Err(_) => true,
        Ok(stat) => stat
            .rsplit_once(')')
            .is_some_and(|(_, rest)| rest.trim_start().starts_with('Z')),
    }
}

fn players(status: &Value) -> &Vec<Value> {
    status["players"]
        .as_array()
        .unwrap_or_else(|| panic!("no players in {status}"))
}

fn player<'a>(status: &'a Value, name: &str) -> &'a Value {
    players(status)
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("no player {name} in {status}"))
}

fn learner_steps(status: &Value, name: &str) -> u64 {
    status["learners"]
        .as_array()
        .unwrap_or_else(|| panic!("no learners in {status}"))
        .iter()
        .find(|l| l["name"] == name)
        .unwrap_or_else(|| panic!("no learner {name} in {status}"))["env_steps"]
        .as_u64()
        .unwrap()
}

fn json_file(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// An export folder holds what its SHA256SUMS lists, each file matching.
fn assert_export_intact(out: &Path) {
    let sums = std::fs::read_to_string(out.join("SHA256SUMS"))
        .unwrap_or_else(|e| panic!("{}: no SHA256SUMS ({e})", out.display()));
    for file in ["actor.safetensors", "meta.json", "player.json"] {
        assert!(sums.contains(file), "{file} missing from {}", out.display());
    }
    for line in sums.lines() {
        let (sha, name) = line.split_once("  ").unwrap();
        assert_eq!(
            t2e_core::util::sha256_file(&out.join(name)).unwrap(),
            sha,
            "{}/{name}",
            out.display()
        );
    }
}

/// Starts the league (`run --config`), its output in run-1.log.
fn start(f: &Folder) -> Child {
    std::fs::write(f.tmp.join("league.toml"), config()).unwrap();
    let log = std::fs::File::create(f.tmp.join("run-1.log")).unwrap();
    Command::new(bin())
        .args(f.run_args())
        .arg("--config")
        .arg(f.tmp.join("league.toml"))
        .stdout(Stdio::from(log.try_clone().unwrap()))
        .stderr(Stdio::from(log))
        .spawn()
        .unwrap()
}

/// The round trip on one backend: make, kill -9, open, resume, export,
/// evaluate the exports, exploit one, read the result in `status`.
fn round_trip(backend: Backend) {
    let tmp = tempfile::tempdir().unwrap();
    let f = Folder {
        tmp: tmp.path().to_path_buf(),
        backend,
    };
    let dir = f.dir();

    // 1. Made by today's binary; killed with SIGKILL (no Ctrl-C, no
    // checkpoint on the way out) once both main learners have a resume
    // point, long before their budget.
    let mut manager = start(&f);
    let deadline = Instant::now() + Duration::from_secs(300);
    let below = loop {
        if let Some(status) = manager.try_wait().unwrap() {
            panic!(
                "the league stopped by itself ({status}) before both learners checkpointed: {}",
                f.read("run-1.log")
            );
        }
        if resume_points(&dir).iter().all(|r| r.is_some_and(|s| s > 0)) {
            break descendants(manager.id());
        }
        if Instant::now() > deadline {
            manager.kill().ok();
            manager.wait().ok();
            panic!(
                "no checkpoint of both learners in 300 s: {:?}\n{}",
                resume_points(&dir),
                f.read("run-1.log")
            );
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    manager.kill().unwrap(); // SIGKILL
    manager.wait().unwrap();
    // Its workers and learners die with it (PR_SET_PDEATHSIG); wait until
    // none can write a checkpoint any more, so what is read next stays.
    let deadline = Instant::now() + Duration::from_secs(30);
    while !below.iter().all(|&p| is_gone(p)) {
        assert!(
            Instant::now() < deadline,
            "the manager's children outlived it by 30 s: {below:?}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let (matches, killed_at) = check(&dir);
    assert!(
        killed_at.iter().all(|&s| s > 0 && s < BUDGET),
        "killed at {killed_at:?}: the resumed run needs work left below {BUDGET}"
    );

    // 2. It opens: status reads the players and the learners of the
    // killed league. A learner beats after each iteration, its checkpoint
    // first: a kill between the two leaves the last beat one iteration
    // behind the resume point, never at 0 once a checkpoint was written.
    let opened = f.status();
    assert_eq!(opened["league"], "kill-test", "{opened}");
    assert!(opened["matches"].as_u64().unwrap() >= matches, "{opened}");
    for name in [
        "expert-captors",
        "rule-based-target",
        "captors-main",
        "target-main",
    ] {
        assert_eq!(player(&opened, name)["quarantined"], Value::Null, "{name}");
    }
    for name in ["captors-main", "target-main"] {
        let steps = learner_steps(&opened, name);
        assert!(steps > 0 && steps < BUDGET, "{name}: status says {steps}");
    }

    // 3. It resumes without its config, from each learner's resume point,
    // to the budget.
    let out = Command::new(bin()).args(f.run_args()).output().unwrap();
    let said = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "the resumed league: {}\n{said}",
        out.status
    );
    assert!(said.contains("resuming the league kill-test"), "{said}");
    let (m, done) = check(&dir);
    assert!(m > matches, "matches went from {matches} to {m}");
    assert_eq!(
        done,
        vec![BUDGET, BUDGET],
        "both learners reach their budget"
    );
    for (side, at) in ["captors", "target"].iter().zip(&killed_at) {
        let log = f.logs().join(format!("{side}-main.log"));
        let log =
            std::fs::read_to_string(&log).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
        assert!(
            log.contains(&format!("{side}-main: resuming at {at} env steps")),
            "{side}-main did not resume from {at}: {log}"
        );
    }
    let resumed = f.status();
    assert!(resumed["matches"].as_u64().unwrap() >= m, "{resumed}");
    assert_eq!(resumed["crashes"], Value::Array(vec![]), "{resumed}");
    for p in players(&opened) {
        let now = player(&resumed, p["name"].as_str().unwrap());
        assert_eq!((&now["id"], &now["side"]), (&p["id"], &p["side"]), "{now}");
    }
    for name in ["captors-main", "target-main"] {
        let (before, after) = (learner_steps(&opened, name), learner_steps(&resumed, name));
        assert!(after >= before, "{name}: {before} env steps, then {after}");
        assert_eq!(player(&resumed, name)["env_steps"], BUDGET, "{name}");
    }

    // 4. It exports: the validation panel's best target snapshot and the
    // main captors, each a self-contained folder that plays as ckpt:.
    let best = f.tmp.join("best-target");
    f.t2e(
        "export",
        &["--best", "target", "--out", best.to_str().unwrap()],
    );
    assert_export_intact(&best);
    let best_name = json_file(&best.join("player.json"))["player"]
        .as_str()
        .unwrap()
        .to_string();
    let chosen = player(&resumed, &best_name);
    assert_eq!(
        (&chosen["side"], &chosen["kind"]),
        (&Value::from("target"), &Value::from("snapshot")),
        "{chosen}"
    );
    let captors = f.tmp.join("captors-main");
    f.t2e(
        "export",
        &["captors-main", "--out", captors.to_str().unwrap()],
    );
    assert_export_intact(&captors);
    let eval = f.tmp.join("eval");
    let out = Command::new(bin())
        .arg("eval")
        .arg("--captors")
        .arg(format!("ckpt:{}", captors.display()))
        .arg("--target")
        .arg(format!("ckpt:{}", best.display()))
        .args(["--k", "2", "--maps", "shipped", "--episodes", "2"])
        .args(["--episode-length", "40", "--quiet", "--out"])
        .arg(&eval)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "eval of the exports: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary = json_file(&eval.join("summary.json"));
    assert_eq!(summary[0]["episodes"], 2, "{summary}");
    assert_eq!(summary[0]["captors_learner"], "MAPPO", "{summary}");

    // 5. It exploits: a best response to the exported snapshot (named by
    // its folder) trains two iterations, and status shows its result
    // against that player.
    f.t2e(
        "exploit",
        &[
            best.to_str().unwrap(),
            "--budget",
            "320",
            "--maps",
            "shipped",
            "--episodes",
            "2",
            "--episode-length",
            "40",
            "--quiet",
        ],
    );
    let exploited = f.status();
    let rows = exploited["exploits"].as_array().unwrap();
    assert_eq!(rows.len(), 1, "one map set, one row: {exploited}");
    let r = &rows[0];
    assert_eq!(r["player_name"], best_name.as_str(), "{r}");
    assert_eq!(r["side"], "target", "{r}");
    assert_eq!(r["best_response"], "captors mappo", "{r}");
    assert_eq!(r["env_steps"], 320, "{r}");
    assert_eq!(r["episodes"], 2, "{r}");
    assert!(r["best_response_wins"].as_u64().unwrap() <= 2, "{r}");
    assert_eq!(r["outdated"], false, "{r}");
    let text = f.t2e("status", &[]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("exploitability") && text.contains(&best_name),
        "{text}"
    );
    // Nothing of the above harmed the league.
    let (after, resume) = check(&dir);
    assert_eq!((after, resume), (m, vec![BUDGET, BUDGET]));
}

#[test]
fn a_sqlite_league_folder_opens_resumes_exports_and_exploits() {
    round_trip(Backend::Sqlite);
}

/// PostgreSQL is required, as in workers.rs: no server, no pass.
#[test]
fn a_postgres_league_folder_opens_resumes_exports_and_exploits() {
    let url = common::postgres::fresh_database(common::postgres::server(), "folders");
    round_trip(Backend::Postgres(url));
}
