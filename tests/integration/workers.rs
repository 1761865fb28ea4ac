//! A league on PostgreSQL with workers on several "hosts" (separate local
//! folders, HOME and host names; one shared pool folder; one server started
//! by scripts/postgres.sh): kill -9 of a worker and of the manager, 8
//! workers and a status poller contending, a 30 s server outage, and bad
//! input. The invariants are tests/integration/league.rs's (`common::league::check`).

use crate::common;

use common::league::{check, TINY_LEAGUE};
use common::postgres::{cluster_dir, fresh_database, server, start_cluster, stop_cluster};
use league::run::folder::layout::{LeagueDir, LeagueIdentity};
use league::store::{BeatState, Kind, NewPlayer, Presence, SeatState, Store, StoreUrl};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_t2e-league")
}

fn log_file(path: &Path) -> Stdio {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    Stdio::from(std::fs::File::create(path).unwrap())
}

/// The manager: `run --store URL --pool POOL`, with `workers` local workers.
fn manager(tmp: &Path, url: &str, workers: usize, config: bool, extra: &[&str]) -> Child {
    let mut cmd = Command::new(bin());
    cmd.arg("run");
    if config {
        cmd.arg("--config").arg(tmp.join("league.toml"));
    }
    cmd.arg("--dir")
        .arg(tmp.join("manager"))
        .arg("--store")
        .arg(url)
        .arg("--pool")
        .arg(tmp.join("pool"))
        .arg("--workers")
        .arg(workers.to_string())
        .args(extra)
        .stdout(Stdio::null())
        .stderr(log_file(&tmp.join(format!(
            "manager-{}.log",
            RUNS.fetch_add(1, std::sync::atomic::Ordering::SeqCst)
        ))));
    cmd.spawn().unwrap()
}

/// A worker on host `host`: its own local folder and HOME.
fn worker(tmp: &Path, url: &str, host: &str, seats: usize) -> Child {
    let local = tmp.join(host);
    std::fs::create_dir_all(local.join("home")).unwrap();
    Command::new(bin())
        .arg("worker")
        .arg("--pool")
        .arg(tmp.join("pool"))
        .arg("--dir")
        .arg(&local)
        .arg("--seats")
        .arg(seats.to_string())
        .arg("--host")
        .arg(host)
        .arg("--lease")
        .arg("4s")
        .env("HOME", local.join("home"))
        .env("T2E_STORE", url)
        .stdout(Stdio::null())
        .stderr(log_file(&local.join("worker.log")))
        .spawn()
        .unwrap()
}

fn wait_until(what: &str, limit: Duration, mut ok: impl FnMut() -> bool) {
    let deadline = Instant::now() + limit;
    while !ok() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(200));
    }
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

fn store(url: &StoreUrl) -> Option<Store> {
    (Store::presence(url).ok()? == Presence::Present)
        .then(|| Store::open_existing(url).ok())
        .flatten()
}

fn sigkill(child: &mut Child) {
    child.kill().unwrap();
    child.wait().unwrap();
}

#[test]
fn two_hosts_share_a_pool_and_kill_9_loses_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = fresh_database(server(), "hosts");
    let url = StoreUrl::parse(&raw).unwrap();
    let dir = LeagueDir::with_store(tmp.join("pool"), url.clone());
    let mut boss = manager(tmp, &raw, 0, true, &[]);
    wait_until("the seats", Duration::from_secs(60), || {
        store(&url).is_some_and(|s| s.seats().is_ok_and(|x| x.len() == 3))
    });
    let mut host_a = worker(tmp, &raw, "host-a", 2);
    wait_until("host-a to take two seats", Duration::from_secs(30), || {
        let seats = store(&url).unwrap().seats().unwrap();
        seats
            .iter()
            .filter(|s| s.host.as_deref() == Some("host-a"))
            .count()
            == 2
    });
    let mut host_b = worker(tmp, &raw, "host-b", 3);
    // host-a's learners train, then host-a dies with them (kill -9).
    wait_until("host-a to train", Duration::from_secs(60), || {
        store(&url).unwrap().heartbeats().unwrap().iter().any(|b| {
            b.host.as_deref() == Some("host-a") && b.state == BeatState::Training && b.env_steps > 0
        })
    });
    let held_by_a: Vec<String> = store(&url)
        .unwrap()
        .seats()
        .unwrap()
        .into_iter()
        .filter(|s| s.host.as_deref() == Some("host-a"))
        .map(|s| s.name)
        .collect();
    sigkill(&mut host_a);
    let (matches, resume) = check(&dir);
    // The manager dies too, and comes back without its config (a resume).
    std::thread::sleep(Duration::from_secs(2));
    sigkill(&mut boss);
    let (m, r) = check(&dir);
    assert!(m >= matches && r.iter().zip(&resume).all(|(a, b)| a >= b));
    let mut boss = manager(tmp, &raw, 0, false, &[]);
    let status = wait_exit(&mut boss, "the resumed manager", Duration::from_secs(300));
    assert!(status.success(), "{status:?}: see {}", tmp.display());
    assert!(wait_exit(&mut host_b, "host-b", Duration::from_secs(30)).success());
    let (m, r) = check(&dir);
    assert!(m >= matches);
    assert_eq!(r, vec![9_600, 9_600], "both learners reach their budget");
    let s = store(&url).unwrap();
    let seats = s.seats().unwrap();
    assert!(
        seats.iter().all(|x| x.state == SeatState::Done),
        "{seats:?}"
    );
    for name in &held_by_a {
        let seat = seats.iter().find(|x| &x.name == name).unwrap();
        assert!(seat.claims >= 2, "{name} was not taken over: {seat:?}");
        let beat = s
            .heartbeats()
            .unwrap()
            .into_iter()
            .find(|b| &b.learner == name)
            .unwrap();
        assert_eq!(beat.host.as_deref(), Some("host-b"), "{beat:?}");
        assert_eq!(beat.state, BeatState::Done);
    }
    let payoff: u64 = s.payoff().unwrap().iter().map(|p| p.games).sum();
    assert_eq!(payoff, s.match_count().unwrap(), "a match counted twice");
    // status from "another host": JSON with the host of every learner.
    let out = Command::new(bin())
        .args(["status", "--json", "--store", &raw])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["learners"]
        .as_array()
        .unwrap()
        .iter()
        .all(|l| l["host"].is_string()));
    assert!(!String::from_utf8_lossy(&out.stdout).contains(raw.split(':').nth(2).unwrap()));
    // export from "another host": the store and the shared pool.
    let out = Command::new(bin())
        .args(["export", "captors-main", "--store", &raw, "--pool"])
        .arg(tmp.join("pool"))
        .arg("--out")
        .arg(tmp.join("exported"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(tmp.join("exported").join("meta.json").is_file());
}

#[test]
fn eight_workers_and_a_status_poller_contend_without_loss() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = fresh_database(server(), "contention");
    let url = StoreUrl::parse(&raw).unwrap();
    let dir = LeagueDir::with_store(tmp.join("pool"), url.clone());
    let mut boss = manager(tmp, &raw, 8, true, &["--for", "25s"]);
    let mut polls = 0;
    let mut last_matches = 0;
    let started = Instant::now();
    while boss.try_wait().unwrap().is_none() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "the league hung"
        );
        let out = Command::new(bin())
            .args(["status", "--json", "--store", &raw])
            .output()
            .unwrap();
        if out.status.success() {
            let json: serde_json::Value = serde_json::from_slice(&out.stdout)
                .unwrap_or_else(|e| panic!("poll {polls}: not JSON ({e})"));
            let m = json["matches"].as_u64().unwrap();
            assert!(
                m >= last_matches,
                "matches went back from {last_matches} to {m}"
            );
            last_matches = m;
            polls += 1;
        } else {
            // Only before the league exists.
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(err.contains("holds no league"), "{err}");
        }
        std::thread::sleep(Duration::from_millis(300));
    }
    assert!(boss.wait().unwrap().success());
    // How many polls fit in the league's 25 s depends on the machine's
    // load (each is a process); a few are enough to contend, and at least
    // one must have seen the league at work.
    assert!(polls >= 3, "only {polls} polls");
    assert!(last_matches > 0, "no poll saw a match being recorded");
    let (m, _) = check(&dir);
    assert!(m >= last_matches && m > 0);
    let s = store(&url).unwrap();
    let payoff: u64 = s.payoff().unwrap().iter().map(|p| p.games).sum();
    assert_eq!(payoff, m, "a match counted twice or lost");
    // Each seat ran on one worker at a time: the seats were taken once
    // each, unless a worker gave one back at --for.
    for seat in s.seats().unwrap() {
        assert!(seat.claims >= 1, "{seat:?}");
        assert!(
            !seat.held_at(league::store::now_ms()),
            "a lease outlived its worker: {seat:?}"
        );
    }
}

#[test]
fn a_30_s_server_outage_is_waited_out() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = start_cluster("outage");
    let raw = fresh_database(&raw, "outage");
    let url = StoreUrl::parse(&raw).unwrap();
    let dir = LeagueDir::with_store(tmp.join("pool"), url.clone());
    let mut boss = manager(tmp, &raw, 3, true, &[]);
    wait_until("the learners to train", Duration::from_secs(90), || {
        store(&url).is_some_and(|s| {
            s.heartbeats()
                .unwrap_or_default()
                .iter()
                .filter(|b| b.state == BeatState::Training && b.env_steps > 0)
                .count()
                == 2
        })
    });
    let before = check(&dir);
    stop_cluster("outage");
    std::thread::sleep(Duration::from_secs(30));
    assert!(
        boss.try_wait().unwrap().is_none(),
        "the manager gave up during the outage"
    );
    start_cluster("outage");
    let status = wait_exit(
        &mut boss,
        "the league after the outage",
        Duration::from_secs(300),
    );
    assert!(
        status.success(),
        "{status:?} (logs in {})",
        cluster_dir("outage").display()
    );
    let (m, r) = check(&dir);
    assert!(m >= before.0);
    assert_eq!(r, vec![9_600, 9_600]);
    let s = store(&url).unwrap();
    assert!(
        s.crashes().unwrap().is_empty(),
        "a process crashed: {:?}",
        s.crashes().unwrap()
    );
    let logs =
        std::fs::read_to_string(tmp.join("manager").join("logs").join("captors-main.log")).unwrap();
    assert!(logs.contains("retrying with back-off"), "{logs}");
}

fn run_cli(args: &[&str], store: Option<&str>) -> Output {
    let mut cmd = Command::new(bin());
    cmd.args(args);
    match store {
        Some(s) => cmd.env("T2E_STORE", s),
        None => cmd.env_remove("T2E_STORE"),
    };
    cmd.output().unwrap()
}

#[test]
fn bad_input_gets_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    let raw = fresh_database(server(), "bad");
    let url = StoreUrl::parse(&raw).unwrap();
    let pool = tmp.join("pool");
    std::fs::create_dir_all(&pool).unwrap();
    let pool_s = pool.to_str().unwrap();
    let local = tmp.join("local");
    let local_s = local.to_str().unwrap();
    let err = |o: Output| String::from_utf8_lossy(&o.stderr).into_owned();
    // --seats 0, and a worker without a store.
    let e = err(run_cli(
        &["worker", "--pool", pool_s, "--dir", local_s, "--seats", "0"],
        Some(&raw),
    ));
    assert!(e.contains("--seats 0"), "{e}");
    let e = err(run_cli(
        &["worker", "--pool", pool_s, "--dir", local_s],
        None,
    ));
    assert!(e.contains("--store"), "{e}");
    // Unreachable, and a password that is never printed.
    let e = err(run_cli(
        &["worker", "--pool", pool_s, "--dir", local_s],
        Some("postgres://t2e:hunter2@127.0.0.1:1/t2e"),
    ));
    assert!(
        e.contains("cannot connect") && !e.contains("hunter2"),
        "{e}"
    );
    let e = err(run_cli(&["status", "--store", &format!("{raw}/x")], None));
    assert!(e.contains("stray path"), "{e}");
    // A league whose pool this worker cannot see.
    let cfg = league::rules::config::LeagueConfig::parse(TINY_LEAGUE).unwrap();
    let s = Store::open(&url).unwrap();
    s.config_once(&toml::to_string_pretty(&cfg).unwrap())
        .unwrap();
    let id = s.set_league_id_once("0123456789abcdef").unwrap();
    let e = err(run_cli(
        &["worker", "--pool", pool_s, "--dir", local_s],
        Some(&raw),
    ));
    assert!(e.contains("league.json") && e.contains("shared"), "{e}");
    let dir = LeagueDir::with_store(&pool, url.clone());
    dir.write_identity(&LeagueIdentity {
        league_id: id,
        name: cfg.name.clone(),
    })
    .unwrap();
    std::fs::write(dir.config_path(), toml::to_string_pretty(&cfg).unwrap()).unwrap();
    s.add_player(&NewPlayer {
        name: "captors-snap-1".into(),
        side: t2e_core::env::Side::Captors,
        kind: Kind::Snapshot,
        parent: None,
        env_steps: 640,
        curriculum_stage: 0,
        checkpoint: Some(("players/captors-snap-1".into(), "00".into())),
    })
    .unwrap();
    let e = err(run_cli(
        &["worker", "--pool", pool_s, "--dir", local_s],
        Some(&raw),
    ));
    assert!(
        e.contains("cannot see players/captors-snap-1") && e.contains("not shared"),
        "{e}"
    );
    // A row naming a path outside the pool is refused, written or read.
    let outside = NewPlayer {
        name: "evil".into(),
        side: t2e_core::env::Side::Captors,
        kind: Kind::Snapshot,
        parent: None,
        env_steps: 1,
        curriculum_stage: 0,
        checkpoint: Some(("../../etc".into(), "00".into())),
    };
    assert!(s
        .add_player(&outside)
        .unwrap_err()
        .to_string()
        .contains("outside"));
    common::postgres::sql(
        &raw,
        "INSERT INTO players (name, side, kind, created_at_ms, env_steps, curriculum_stage, checkpoint_path, checkpoint_sha256) VALUES ('evil', 'captors', 'snapshot', 0, 1, 0, '/etc', '00')",
    );
    let e = err(run_cli(
        &["worker", "--pool", pool_s, "--dir", local_s],
        Some(&raw),
    ));
    assert!(e.contains("outside the league's pool folder"), "{e}");
    // status lists the league and flags that one row, rather than refusing.
    let out = run_cli(&["status", "--json", "--store", &raw], None);
    assert!(out.status.success(), "{}", err(out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let evil = json["players"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "evil")
        .unwrap()
        .clone();
    assert!(
        evil["quarantined"].as_str().unwrap().contains("outside"),
        "{evil}"
    );
}

fn status_json(raw: &str) -> serde_json::Value {
    let out = Command::new(bin())
        .args(["status", "--json", "--store", raw])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn snapshot_rows(url: &StoreUrl) -> usize {
    store(url).map_or(0, |s| {
        s.players()
            .unwrap()
            .iter()
            .filter(|p| p.kind == Kind::Snapshot && p.checkpoint.is_some())
            .count()
    })
}

#[test]
fn a_second_manager_never_changes_a_live_leagues_store() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = fresh_database(server(), "second");
    let url = StoreUrl::parse(&raw).unwrap();
    let mut boss = manager(tmp, &raw, 3, true, &[]);
    wait_until("a snapshot in the pool", Duration::from_secs(120), || {
        snapshot_rows(&url) >= 1
    });
    let second = |pool: &Path, host: &str| -> Output {
        Command::new(bin())
            .arg("run")
            .arg("--config")
            .arg(tmp.join("league.toml"))
            .arg("--dir")
            .arg(tmp.join("second"))
            .arg("--store")
            .arg(&raw)
            .arg("--pool")
            .arg(pool)
            .args(["--workers", "1", "--for", "5s"])
            .env("T2E_HOST", host)
            .output()
            .unwrap()
    };
    // Another pool, empty or not there at all: refused, naming both.
    let empty = tmp.join("empty-pool");
    std::fs::create_dir_all(&empty).unwrap();
    for pool in [empty.clone(), tmp.join("no-such-pool")] {
        let out = second(&pool, "elsewhere");
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(!out.status.success(), "a foreign pool was accepted: {err}");
        assert!(
            err.contains(&pool.display().to_string()) && err.contains("not its pool"),
            "{err}"
        );
        assert!(!err.contains("resuming"), "{err}");
    }
    assert_eq!(std::fs::read_dir(&empty).unwrap().count(), 0, "written to");
    assert!(!tmp.join("no-such-pool").exists());
    // The right pool from another host, while the first manager lives.
    let out = second(&tmp.join("pool"), "elsewhere");
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{err}");
    // Refused at the pool's lock (this host sees the first manager's
    // flock) or, where the lock cannot be seen, at the store's lease.
    assert!(
        err.contains("another manager runs this league")
            || err.contains("already running this league"),
        "{err}"
    );
    let s = store(&url).unwrap();
    let quarantined: Vec<_> = s
        .players()
        .unwrap()
        .into_iter()
        .filter(|p| p.quarantined.is_some())
        .collect();
    assert!(quarantined.is_empty(), "{quarantined:?}");
    assert!(s
        .seats()
        .unwrap()
        .iter()
        .all(|x| x.state != SeatState::Failed));
    // The league runs on to its end, unharmed.
    let status = wait_exit(&mut boss, "the first manager", Duration::from_secs(300));
    assert!(status.success(), "{status:?}: see {}", tmp.display());
    let (_, r) = check(&LeagueDir::with_store(tmp.join("pool"), url.clone()));
    assert_eq!(r, vec![9_600, 9_600]);
    assert!(
        store(&url).unwrap().manager().unwrap().is_none(),
        "lease kept"
    );
}

#[test]
fn a_deleted_seat_row_is_defined_again_and_the_league_finishes() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = fresh_database(server(), "seatgone");
    let url = StoreUrl::parse(&raw).unwrap();
    let mut boss = manager(tmp, &raw, 0, true, &[]);
    wait_until("the seats", Duration::from_secs(60), || {
        store(&url).is_some_and(|s| s.seats().is_ok_and(|x| x.len() == 3))
    });
    let mut host = worker(tmp, &raw, "host-a", 3);
    wait_until("captors-main to train", Duration::from_secs(90), || {
        store(&url).unwrap().heartbeats().unwrap().iter().any(|b| {
            b.learner == "captors-main" && b.state == BeatState::Training && b.env_steps > 0
        })
    });
    common::postgres::sql(&raw, "DELETE FROM seats WHERE name = 'captors-main'");
    let log = tmp.join("host-a").join("worker.log");
    wait_until("the worker to notice", Duration::from_secs(120), || {
        std::fs::read_to_string(&log).is_ok_and(|l| l.contains("captors-main"))
            && std::fs::read_to_string(&log)
                .unwrap()
                .contains("seat row is gone")
    });
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(!text.contains("another worker"), "{text}");
    let status = wait_exit(&mut boss, "the manager", Duration::from_secs(300));
    assert!(status.success(), "{status:?}: see {}", tmp.display());
    assert!(wait_exit(&mut host, "the worker", Duration::from_secs(30)).success());
    let (_, r) = check(&LeagueDir::with_store(tmp.join("pool"), url.clone()));
    assert_eq!(r, vec![9_600, 9_600], "both learners reach their budget");
}

#[test]
fn status_shows_a_killed_workers_learners_dead() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    std::fs::write(tmp.join("league.toml"), TINY_LEAGUE).unwrap();
    let raw = fresh_database(server(), "orphans");
    let url = StoreUrl::parse(&raw).unwrap();
    let mut boss = manager(tmp, &raw, 0, true, &[]);
    wait_until("the seats", Duration::from_secs(60), || {
        store(&url).is_some_and(|s| s.seats().is_ok_and(|x| x.len() == 3))
    });
    let mut host = worker(tmp, &raw, "host-a", 3);
    wait_until("both learners to train", Duration::from_secs(90), || {
        store(&url)
            .unwrap()
            .heartbeats()
            .unwrap()
            .iter()
            .filter(|b| b.state == BeatState::Training && b.env_steps > 0)
            .count()
            == 2
    });
    sigkill(&mut host);
    // No worker takes the seats again; once the leases (4 s) have expired
    // nothing of them runs, whatever the last heartbeats said.
    std::thread::sleep(Duration::from_secs(6));
    let json = status_json(&raw);
    for l in json["learners"].as_array().unwrap() {
        assert_ne!(l["state"], "training", "{l}");
    }
    let text = Command::new(bin())
        .args(["status", "--store", &raw])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&text.stdout).into_owned();
    assert!(text.contains("captors-main   dead"), "{text}");
    boss.kill().ok();
    boss.wait().ok();
}
