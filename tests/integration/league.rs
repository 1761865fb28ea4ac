//! The league end to end, as processes: `t2e-league run` with a tiny config,
//! killed with SIGKILL at random moments (the manager or a learner), run
//! again, until both learners reach their budget. After every kill and at
//! the end, the store and the directory must hold: no match counted twice,
//! none lost from what was recorded, no duplicate member, no orphan file,
//! and learners that continue from their last checkpoints.

use crate::common;
use common::league::run_to_the_end;

use league::run::folder::layout::LeagueDir;
use league::store::{BeatState, Kind, Store};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use t2e_core::env::Side;

const CONFIG: &str = common::league::TINY_LEAGUE;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_t2e-league")
}

fn start(dir: &Path, config: &Path) -> Child {
    Command::new(bin())
        .args(["run", "--config"])
        .arg(config)
        .arg("--dir")
        .arg(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

fn sigkill(pid: i64) {
    // SAFETY: signalling a process this test started (or its child).
    unsafe {
        libc::kill(pid as i32, libc::SIGKILL);
    }
}

/// The learner processes the manager `manager` spawned.
fn learner_pids(manager: u32) -> Vec<i64> {
    common::children_of(manager, "league-learner")
}

#[test]
fn killed_at_random_moments_the_league_loses_and_duplicates_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let config = tmp.path().join("league.toml");
    std::fs::write(&config, CONFIG).unwrap();
    let dir = LeagueDir::new(tmp.path().join("league"));
    let mut rng_state = 0x9e37_79b9u64;
    let mut next = |n: u64| {
        rng_state ^= rng_state << 13;
        rng_state ^= rng_state >> 7;
        rng_state ^= rng_state << 17;
        rng_state % n
    };
    let (mut matches, mut resume) = (0u64, vec![0u64, 0]);
    let started = Instant::now();
    for round in 0..5 {
        let mut manager = start(&dir.root, &config);
        std::thread::sleep(Duration::from_millis(2500 + 500 * next(6)));
        let victim = if next(2) == 0 { "manager" } else { "learner" };
        match victim {
            "manager" => sigkill(manager.id() as i64),
            _ => {
                let pids = learner_pids(manager.id());
                if !pids.is_empty() {
                    sigkill(pids[next(pids.len() as u64) as usize]);
                }
                std::thread::sleep(Duration::from_millis(300 + 100 * next(5)));
                sigkill(manager.id() as i64);
            }
        }
        let _ = manager.wait();
        // Children die with the manager (PR_SET_PDEATHSIG); give them a moment.
        std::thread::sleep(Duration::from_millis(500));
        let (m, r) = common::league::check(&dir);
        assert!(
            m >= matches,
            "round {round}: matches went from {matches} to {m}"
        );
        for (side, (before, now)) in resume.iter().zip(&r).enumerate() {
            assert!(
                now >= before,
                "round {round}, learner {side}: resume point went back from {before} to {now}"
            );
        }
        eprintln!("round {round}: killed the {victim}; {m} matches, resume points {r:?}");
        (matches, resume) = (m, r);
    }
    // A crashed learner is restarted: kill one and let the manager notice.
    let mut manager = start(&dir.root, &config);
    let deadline = Instant::now() + Duration::from_secs(240);
    let mut killed_once = false;
    loop {
        if let Some(status) = manager.try_wait().unwrap() {
            assert!(status.success(), "the last run should finish: {status:?}");
            break;
        }
        if !killed_once && started.elapsed() > Duration::from_secs(1) {
            std::thread::sleep(Duration::from_millis(1500));
            if let Some(pid) = learner_pids(manager.id()).first() {
                sigkill(*pid);
                killed_once = true;
            }
        }
        assert!(
            Instant::now() < deadline,
            "the league did not finish in time"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    let (m, r) = common::league::check(&dir);
    assert!(m >= matches);
    assert_eq!(r, vec![9_600, 9_600], "both learners reach their budget");
    let store = Store::open(&dir.store).unwrap();
    let beats = store.heartbeats().unwrap();
    assert!(
        beats.iter().all(|b| b.state == BeatState::Done),
        "{beats:?}"
    );
    if killed_once {
        assert!(
            !store.crashes().unwrap().is_empty(),
            "the killed learner is recorded as a crash"
        );
    }
    // status: every player, ratings for those who played, a payoff row per pair.
    let report = league::run::status::report(&dir).unwrap();
    assert_eq!(report.matches, m);
    assert!(report.players.iter().any(|p| p.name == "rule-based-target"));
    let games: u64 = report.payoff.iter().map(|p| p.games).sum();
    assert_eq!(games, m, "the payoff table holds every match once");
    for p in report.players.iter().filter(|p| p.games > 0) {
        assert!(
            p.rating.is_finite() && p.rating_sigma > 0.0 && p.bt_elo.is_finite(),
            "{p:?}"
        );
    }
    let json: serde_json::Value = serde_json::to_value(&report).unwrap();
    for key in [
        "league",
        "matches",
        "players",
        "curriculum",
        "learners",
        "payoff",
        "crashes",
    ] {
        assert!(json.get(key).is_some(), "status --json lacks {key}");
    }
    let text = t2e::cli::status_text::render(&report);
    assert!(
        text.contains("payoff") && text.contains("captors-main"),
        "{text}"
    );
    let png = tmp.path().join("status.png");
    league::run::status::plot(&dir, &report, &png).unwrap();
    assert!(image::open(&png).unwrap().width() >= 900);

    // export: a self-contained folder that plays as ckpt:FOLDER, with a
    // manifest that matches its files.
    let best = league::run::status::best_player(&report, Side::Target).unwrap();
    let out = tmp.path().join("exported");
    league::run::status::export(&dir, &best, &out).unwrap();
    let sums = std::fs::read_to_string(out.join("SHA256SUMS")).unwrap();
    for line in sums.lines() {
        let (sha, name) = line.split_once("  ").unwrap();
        assert_eq!(
            t2e_core::util::sha256_file(&out.join(name)).unwrap(),
            sha,
            "{name}"
        );
    }
    for f in [
        "actor.safetensors",
        "meta.json",
        "league-config.toml",
        "ratings.csv",
        "player.json",
    ] {
        assert!(sums.contains(f), "{f} missing from the export");
    }
    let spec: t2e_learners::controllers::ControllerSpec =
        format!("ckpt:{}", out.display()).parse().unwrap();
    let cfg = t2e_core::env::EnvConfig {
        num_captors: 2,
        ..Default::default()
    };
    spec.check(Side::Target, &cfg).unwrap();
    assert!(
        league::run::status::export(&dir, "no-such-player", &tmp.path().join("x"))
            .unwrap_err()
            .to_string()
            .contains("no player")
    );

    // A second manager on a live league is refused.
    let _held = league::run::processes::spawn::try_lock(&dir.root.join("league.lock"))
        .unwrap()
        .unwrap();
    let out = Command::new(bin())
        .args(["run", "--dir"])
        .arg(&dir.root)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("already running"), "{err}");
}

/// The tiny league cut to 3,200 env steps per learner, no evaluator.
fn short_league_without_evaluator() -> String {
    CONFIG
        .replace(
            "env_steps_per_learner = 9_600",
            "env_steps_per_learner = 3_200",
        )
        .replace(
            "[evaluator]\nepisodes = 3",
            "[evaluator]\nenabled = false\nepisodes = 3",
        )
}

#[test]
fn exploiters_play_the_main_learners_join_the_pool_and_start_again() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = LeagueDir::new(tmp.path().join("league"));
    let config = tmp.path().join("league.toml");
    let text = short_league_without_evaluator()
        + "[exploiters]\ncaptors = true\ntarget = true\nwin_rate = 0.99\ntimeout_env_steps = 960\n";
    std::fs::write(&config, text).unwrap();
    run_to_the_end(&dir.root, &config);

    let store = Store::open(&dir.store).unwrap();
    let players = store.players().unwrap();
    let id = |name: &str| players.iter().find(|p| p.name == name).map(|p| p.id);
    let payoff = store.payoff().unwrap();
    for side in [Side::Captors, Side::Target] {
        let other = match side {
            Side::Captors => Side::Target,
            Side::Target => Side::Captors,
        };
        let exploiter = players
            .iter()
            .find(|p| p.name == format!("{}-exploiter", side.name()))
            .unwrap_or_else(|| panic!("no {} exploiter in {players:?}", side.name()));
        assert_eq!(exploiter.kind, Kind::Exploiter);
        // It snapshots into the pool (the timeout: it cannot reach 99%)...
        let snaps: Vec<_> = players
            .iter()
            .filter(|p| p.parent == Some(exploiter.id))
            .collect();
        assert!(!snaps.is_empty(), "no snapshot of {}", exploiter.name);
        for s in &snaps {
            assert_eq!(s.kind, Kind::Snapshot);
            assert!(
                s.name.starts_with(&format!("{}-snap-", exploiter.name)),
                "{}",
                s.name
            );
        }
        // ...then starts again from its initial weights.
        let log = std::fs::read_to_string(
            dir.root
                .join("logs")
                .join(format!("{}.log", exploiter.name)),
        )
        .unwrap();
        assert!(log.contains("back to its initial weights"), "{log}");
        // It plays only the other side's main learner (its snapshots), or
        // the heuristic member before the main learner has one.
        let main = id(&format!("{}-main", other.name())).unwrap();
        let heuristic = id(&league::rules::players::heuristic_name(other)).unwrap();
        let mut games = 0;
        for r in &payoff {
            let (me, them) = match side {
                Side::Captors => (r.captor, r.target),
                Side::Target => (r.target, r.captor),
            };
            if me != exploiter.id {
                continue;
            }
            games += r.games;
            let opponent = players.iter().find(|p| p.id == them).unwrap();
            assert!(
                them == heuristic || opponent.parent == Some(main),
                "{} played {}",
                exploiter.name,
                opponent.name
            );
        }
        assert!(games > 0, "{} recorded no match", exploiter.name);
    }
}

#[test]
fn held_out_opponents_play_every_snapshot_but_never_the_league() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = LeagueDir::new(tmp.path().join("league"));
    let config = tmp.path().join("league.toml");
    let text = CONFIG.replace(
        "env_steps_per_learner = 9_600",
        "env_steps_per_learner = 3_200",
    ) + "held_out_captors = [\"random\"]\nheld_out_targets = [\"still\"]\n";
    assert!(
        text.trim_end().ends_with("held_out_targets = [\"still\"]") && text.contains("[evaluator]")
    );
    std::fs::write(&config, text).unwrap();
    run_to_the_end(&dir.root, &config);

    let store = Store::open(&dir.store).unwrap();
    let players = store.players().unwrap();
    assert!(
        players
            .iter()
            .all(|p| p.name != "random" && p.name != "still"),
        "a held-out opponent is no member: {players:?}"
    );
    let snapshots: Vec<_> = players
        .iter()
        .filter(|p| p.kind == Kind::Snapshot)
        .collect();
    assert!(snapshots.len() >= 2, "{players:?}");
    // Every snapshot played its 3 panel episodes against the other side's
    // heuristic (matches) and 3 against its held-out opponent (apart).
    let episodes = 3 * snapshots.len() as u64;
    assert_eq!(store.matches_recorded_by("evaluator").unwrap(), episodes);
    assert_eq!(store.held_out_count().unwrap(), episodes);
    let held_out = store.held_out_results().unwrap();
    for s in &snapshots {
        let want = match s.side {
            Side::Captors => "still",
            Side::Target => "random",
        };
        let rows: Vec<_> = held_out.iter().filter(|r| r.member == s.id).collect();
        assert_eq!(rows.len(), 1, "{}: {rows:?}", s.name);
        assert_eq!((rows[0].opponent.as_str(), rows[0].episodes), (want, 3));
    }
    drop(store);
    let report = league::run::status::report(&dir).unwrap();
    let marked: Vec<_> = report.panel.iter().filter(|r| r.held_out).collect();
    assert_eq!(marked.len(), snapshots.len());
    assert!(marked.iter().all(|r| r.opponent == 0 && r.episodes == 3));
    let evaluator = report
        .learners
        .iter()
        .find(|l| l.name == "evaluator")
        .unwrap();
    assert_eq!(evaluator.env_steps, 2 * episodes, "panel episodes counted");
    let text = t2e::cli::status_text::render(&report);
    assert!(
        text.contains("random (held out)") && text.contains("still (held out)"),
        "{text}"
    );
}

#[test]
fn extra_heuristic_members_join_the_pool_and_play_the_learners() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = LeagueDir::new(tmp.path().join("league"));
    let config = tmp.path().join("league.toml");
    let text = short_league_without_evaluator()
        + "[members]\ncaptors = [\"greedy:4\"]\ntarget = [\"still\"]\n";
    std::fs::write(&config, text).unwrap();
    run_to_the_end(&dir.root, &config);

    let store = Store::open(&dir.store).unwrap();
    let players = store.players().unwrap();
    let payoff = store.payoff().unwrap();
    for (name, side, learner) in [
        ("greedy:4-captors", Side::Captors, "target-main"),
        ("still-target", Side::Target, "captors-main"),
    ] {
        let member = players
            .iter()
            .find(|p| p.name == name)
            .unwrap_or_else(|| panic!("no {name} in {players:?}"));
        assert_eq!((member.kind, member.side), (Kind::Heuristic, side));
        let learner = players.iter().find(|p| p.name == learner).unwrap();
        let games: u64 = payoff
            .iter()
            .filter(|r| match side {
                Side::Captors => r.captor == member.id && r.target == learner.id,
                Side::Target => r.target == member.id && r.captor == learner.id,
            })
            .map(|r| r.games)
            .sum();
        assert!(games > 0, "{} never played {name}", learner.name);
    }
    // The config names the members: a store's stored config keeps them.
    let stored = std::fs::read_to_string(dir.root.join("config.toml")).unwrap();
    assert!(
        stored.contains("[members]") && stored.contains("greedy:4"),
        "{stored}"
    );
}

/// A tiny trained captor team (K = 2, held-out protocol) saved under `runs`.
fn tiny_captors(runs: &Path) -> std::path::PathBuf {
    let shipped = t2e_core::map::catalog::load_prepared("shipped").unwrap();
    let cfg = common::tiny_train_config("member", t2e_core::protocol::Protocol::HeldOut, "shipped");
    let mut trainer = t2e_learners::learn::train::Trainer::new(cfg, shipped).unwrap();
    trainer.iterate().unwrap();
    trainer.save(runs).unwrap().remove(0)
}

#[test]
fn a_trained_team_joins_the_pool_as_a_frozen_member_and_a_paper_one_is_refused() {
    tch::set_num_threads(1);
    let tmp = tempfile::tempdir().unwrap();
    let source = tiny_captors(&tmp.path().join("runs/coop"));
    let dir = LeagueDir::new(tmp.path().join("league"));
    let config = tmp.path().join("league.toml");
    let text = short_league_without_evaluator()
        + &format!(
            "[matchmaking]\nmembers_share = 0.5\n[members]\ncaptors = [\"ckpt:{}\"]\n",
            source.display()
        );
    std::fs::write(&config, &text).unwrap();
    run_to_the_end(&dir.root, &config);

    let name = format!(
        "coop@{}-captors",
        source.file_name().unwrap().to_string_lossy()
    );
    let store = Store::open(&dir.store).unwrap();
    let players = store.players().unwrap();
    let member = players
        .iter()
        .find(|p| p.name == name)
        .unwrap_or_else(|| panic!("no {name} in {players:?}"));
    // A snapshot without a learner behind it, its weights a copy of the source's.
    assert_eq!(
        (member.kind, member.side, member.parent),
        (Kind::Snapshot, Side::Captors, None)
    );
    let (rel, sha) = member.checkpoint.clone().unwrap();
    assert_eq!(rel, format!("players/{name}"));
    for file in ["meta.json", "actor.safetensors"] {
        assert_eq!(
            std::fs::read(dir.root.join(&rel).join(file)).unwrap(),
            std::fs::read(source.join(file)).unwrap(),
            "{file}"
        );
    }
    assert_eq!(
        t2e_core::util::sha256_file(&source.join("meta.json")).unwrap(),
        sha
    );
    let target_main = players.iter().find(|p| p.name == "target-main").unwrap();
    let games: u64 = store
        .payoff()
        .unwrap()
        .iter()
        .filter(|r| r.captor == member.id && r.target == target_main.id)
        .map(|r| r.games)
        .sum();
    assert!(games > 0, "target-main never played {name}");

    // Started again without its source, the league keeps the copy it recorded.
    std::fs::remove_dir_all(&source).unwrap();
    run_to_the_end(&dir.root, &config);
    let again = Store::open(&dir.store).unwrap().players().unwrap();
    assert_eq!(again.iter().filter(|p| p.name == name).count(), 1);
    assert_eq!(
        again.iter().find(|p| p.name == name).unwrap().checkpoint,
        Some((rel, sha))
    );

    // A team trained on the Gibson test maps cannot join a held-out league.
    let paper = tiny_captors(&tmp.path().join("runs/paper"));
    let meta = paper.join("meta.json");
    let edited = std::fs::read_to_string(&meta)
        .unwrap()
        .replace("\"held-out\"", "\"paper\"");
    std::fs::write(&meta, edited).unwrap();
    // As if trained so: the manifest made again over the edit.
    t2e_learners::nn::checkpoint::write_manifest(&paper).unwrap();
    let config = tmp.path().join("paper.toml");
    std::fs::write(
        &config,
        short_league_without_evaluator()
            + &format!("[members]\ncaptors = [\"ckpt:{}\"]\n", paper.display()),
    )
    .unwrap();
    let paper_league = tmp.path().join("paper-league");
    let out = Command::new(bin())
        .args(["run", "--config"])
        .arg(&config)
        .arg("--dir")
        .arg(&paper_league)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("paper.toml: members.captors = \"ckpt:") && err.contains("paper protocol"),
        "{err}"
    );
    // Refused before anything is written: the mended config can start there.
    assert!(!paper_league.exists());
}
