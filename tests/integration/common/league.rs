//! The invariants every league keeps, whatever kills it (tests/integration/league.rs,
//! tests/integration/workers.rs).
#![allow(dead_code)]

use league::run::folder::layout::LeagueDir;
use league::store::{Kind, Store};
use std::collections::BTreeSet;
use t2e_core::env::Side;
use t2e_learners::learn::persist::RunDir;

/// The tiny league of tests/integration/league.rs: two learners (K = 2, tiny networks)
/// and the evaluator, 9,600 env steps each.
pub const TINY_LEAGUE: &str = include_str!("tiny_league.toml");

/// Runs a league to its end in the foreground; its stderr on failure.
pub fn run_to_the_end(dir: &std::path::Path, config: &std::path::Path) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_t2e-league"))
        .args(["run", "--config"])
        .arg(config)
        .arg("--dir")
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Checks the invariants; returns (matches, per-learner env steps of their
/// resume points).
pub fn check(dir: &LeagueDir) -> (u64, Vec<u64>) {
    let store = Store::open(&dir.store).unwrap();
    let players = store.players().unwrap();
    // No duplicate member: one row per name (the schema) and per snapshot.
    let mut seen = BTreeSet::new();
    for p in &players {
        assert!(
            seen.insert((
                p.side.name(),
                p.kind.name(),
                p.parent,
                p.env_steps,
                p.name.clone()
            )),
            "duplicate {p:?}"
        );
    }
    let snapshots: Vec<_> = players
        .iter()
        .filter(|p| p.kind == Kind::Snapshot)
        .collect();
    let mut steps = BTreeSet::new();
    for s in &snapshots {
        assert!(
            steps.insert((s.side.name(), s.parent, s.env_steps)),
            "two snapshots of one state: {s:?}"
        );
    }
    // No orphan file: every snapshot folder has a row, every row its files.
    let rels: BTreeSet<String> = players
        .iter()
        .filter_map(|p| p.checkpoint.as_ref().map(|c| c.0.clone()))
        .collect();
    if let Ok(entries) = std::fs::read_dir(dir.players_dir()) {
        for e in entries {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue; // a temporary a killed writer left: removed at the next start
            }
            if !rels.contains(&dir.relative(&path)) {
                // A writer killed between the folder and its row leaves a
                // complete snapshot that the next start adopts.
                let meta = t2e_learners::nn::checkpoint::read_meta(&path)
                    .unwrap_or_else(|e| panic!("orphan {}: {e:#}", path.display()));
                assert!(
                    league::run::folder::pool::PoolMembership::of(&meta)
                        .unwrap()
                        .is_some(),
                    "orphan {}",
                    path.display()
                );
                t2e_learners::nn::PolicySnapshot::load(&path, meta.side).unwrap();
            }
        }
    }
    for s in &snapshots {
        if s.quarantined.is_none() {
            let (rel, sha) = s.checkpoint.as_ref().unwrap();
            let meta = dir.root.join(rel).join("meta.json");
            assert_eq!(&t2e_core::util::sha256_file(&meta).unwrap(), sha, "{rel}");
            t2e_learners::nn::PolicySnapshot::load(&dir.root.join(rel), s.side).unwrap();
        }
    }
    // Matches reference known players; keys are unique (schema) and name their recorder.
    let ids: BTreeSet<i64> = players.iter().map(|p| p.id).collect();
    for r in store.payoff().unwrap() {
        assert!(ids.contains(&r.captor) && ids.contains(&r.target));
    }
    let resume: Vec<u64> = [Side::Captors, Side::Target]
        .iter()
        .map(|&side| {
            RunDir::new(dir.learner_dir(side))
                .read_state()
                .map(|s| s.env_steps)
                .unwrap_or(0)
        })
        .collect();
    (store.match_count().unwrap(), resume)
}
