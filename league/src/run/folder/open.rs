//! Opening a league directory: every check before any write.
//!
//! A league is its directory: `config.toml`, `league.json` (its identity),
//! `league.db` (the store) and the files the store names. They must agree
//! before anything runs, because SQLite opens a missing or truncated
//! database as a new, empty one, and a store copied from another league
//! opens as well as this league's own. So:
//! - `plan_start` (the manager) reads everything and writes nothing; it
//!   refuses a store that is missing, empty or another league's beside a
//!   league's files, and a config that differs from the store's. Only
//!   then does the manager write (`config.toml` restored from the store,
//!   the identity of a league from before identities existed).
//! - `open_process` (learners, the evaluator) opens the existing store and
//!   checks its identity against `league.json`.
//! - `open_read_only` (`status`, `export`) changes nothing on disk.

use crate::error::{LeagueError, Result};
use crate::rules::config::LeagueConfig;
use crate::run::folder::layout::{LeagueDir, LeagueIdentity};
use crate::store::{Presence, Store, StoreUrl};
use std::path::Path;

/// Ends the function with a `LeagueError::Folder`: the directory (or the
/// store beside it) is not the league it should be.
macro_rules! refuse {
    ($($why:tt)*) => {
        return Err(LeagueError::Folder(format!($($why)*)))
    };
}

/// A league directory opened by a process of the league.
pub struct Opened {
    pub cfg: LeagueConfig,
    pub store: Store,
    pub league_id: String,
}

/// What the manager does with its directory, decided before any write.
#[derive(Debug)]
pub enum StartPlan {
    /// Nothing of a league is there: start one with this config.
    New(LeagueConfig),
    /// Resume the league the directory holds.
    Resume {
        cfg: LeagueConfig,
        /// config.toml is missing: write it back from the store.
        restore_config: bool,
        identity: LeagueIdentity,
        /// league.json is missing (or the store has no identity: a league
        /// from before identities): write what is missing.
        write_identity: bool,
        set_store_identity: bool,
    },
}

/// Decides how `run` starts in `dir` (with `--config given`, if any),
/// reading only.
pub fn plan_start(dir: &LeagueDir, given: Option<&Path>) -> Result<StartPlan> {
    let db = &dir.store;
    let files = dir.league_files();
    let given_cfg = given.map(LeagueConfig::load).transpose()?;
    let (store, stored_toml) = match held_store(dir)? {
        Ok(held) => held,
        Err(what) if !files.is_empty() => return Err(lost_store(dir, what, &files)),
        Err(_) => return plan_new(dir, given_cfg),
    };
    let stored_cfg = LeagueConfig::parse(&stored_toml).map_err(|e| {
        LeagueError::from(e).context(format!("{db}: the config it holds is invalid"))
    })?;
    let on_disk = check_configs(dir, &stored_cfg, given_cfg.as_ref())?;
    let file_identity = dir.identity()?;
    let store_identity = store.league_id()?;
    let identity = resume_identity(dir, &stored_cfg, &store_identity, &file_identity)?;
    check_pool_identity(dir, &identity.league_id, db)?;
    if dir.store != StoreUrl::in_dir(&dir.root) {
        check_pool_holds_league(dir, &store, file_identity.is_some())?;
    }
    Ok(StartPlan::Resume {
        cfg: stored_cfg,
        restore_config: on_disk.is_none(),
        write_identity: file_identity.is_none(),
        set_store_identity: store_identity.is_none(),
        identity,
    })
}

/// The store and the config it holds, opened read-only; else what is
/// wrong with it (missing, empty, holding no league), for `plan_start` to
/// decide whether that is a new league or a lost store.
fn held_store(dir: &LeagueDir) -> Result<std::result::Result<(Store, String), &'static str>> {
    let (root, db) = (dir.root.display(), &dir.store);
    Ok(match Store::presence(db)? {
        Presence::Missing => Err("missing"),
        Presence::Empty => Err("empty (0 bytes)"),
        Presence::Present => {
            // Read-only: a file that is not this league's store (another
            // program's database, a corrupt one) is refused untouched.
            let store = Store::inspect(db).map_err(|e| {
                LeagueError::Folder(format!(
                    "{e}. Nothing was changed; restore the store from a backup, or move {root} aside"
                ))
            })?;
            match store.stored_config()? {
                Some(toml) => Ok((store, toml)),
                None => Err("holds no league (its tables are empty: truncated, or its write-ahead log league.db-wal was lost)"),
            }
        }
    })
}

/// The refusal when the store is `what` but the folder holds a league's
/// `files`: a new store would not know the league.
fn lost_store(dir: &LeagueDir, what: &str, files: &[String]) -> LeagueError {
    let (root, db) = (dir.root.display(), &dir.store);
    let restore = match db {
        StoreUrl::Sqlite(_) => {
            "Restore league.db (with league.db-wal beside it, if there was one) from a backup"
        }
        StoreUrl::Postgres(_) => "Point --store at this league's database",
    };
    LeagueError::Folder(format!(
        "{db}: {what}, but {root} holds a league ({}). Refusing to start: a new store would not know its pool, matches or learners. \
         {restore}, or move {root} aside and start a new league in an empty directory",
        files.join(", ")
    ))
}

/// A new league, where there is no store and nothing of a league: its
/// config is the one given, or the config.toml an interrupted start left.
fn plan_new(dir: &LeagueDir, given_cfg: Option<LeagueConfig>) -> Result<StartPlan> {
    let root = dir.root.display();
    refuse_foreign_files(dir)?;
    // No store and nothing of a league: a new league, or a start
    // that was interrupted before anything but its config existed.
    let cfg = match (given_cfg, dir.config_path().is_file()) {
        (Some(cfg), _) => cfg,
        (None, true) => dir.config()?,
        (None, false) => {
            refuse!("{root} holds no league: give --config configs/league-*.toml to start one")
        }
    };
    Ok(StartPlan::New(cfg))
}

/// A new league writes its store, players/ and learners/ in its folder:
/// never among a user's own files, where a later `move it aside` or
/// cleanup would take them too.
fn refuse_foreign_files(dir: &LeagueDir) -> Result<()> {
    let (root, db) = (dir.root.display(), &dir.store);
    let Ok(entries) = std::fs::read_dir(&dir.root) else {
        return Ok(());
    };
    let owned = [
        "league.db",
        "league.db-wal",
        "league.db-shm",
        "league.db-journal",
        "league.json",
        "config.toml",
        "league.lock",
        "players",
        "learners",
        "logs",
        "exploits",
    ];
    let mut foreign: Vec<String> = entries
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.') && !owned.contains(&n.as_str()))
        .collect();
    if !foreign.is_empty() {
        foreign.sort();
        let shown: Vec<&str> = foreign.iter().take(5).map(String::as_str).collect();
        refuse!(
            "{root}: holds files that are not a league's ({}{}); a new league starts in an empty or new folder: give another --dir{}",
            shown.join(", "),
            if foreign.len() > shown.len() { ", ..." } else { "" },
            if matches!(db, StoreUrl::Postgres(_)) || dir.store != StoreUrl::in_dir(&dir.root) { " (or --pool)" } else { "" }
        );
    }
    Ok(())
}

/// The config on disk and the one given must be the store's; returns the
/// one on disk (None: config.toml is missing and is restored).
fn check_configs(
    dir: &LeagueDir,
    stored_cfg: &LeagueConfig,
    given_cfg: Option<&LeagueConfig>,
) -> Result<Option<LeagueConfig>> {
    let (root, db) = (dir.root.display(), &dir.store);
    let on_disk = if dir.config_path().is_file() {
        Some(dir.config()?)
    } else {
        None
    };
    if let Some(cfg) = &on_disk {
        if cfg != stored_cfg {
            refuse!(
                "{}: differs from the config the league's store ({db}) was started with; put the league's config back, or pick another --dir",
                dir.config_path().display(),
            );
        }
    }
    if let Some(cfg) = given_cfg {
        if cfg != stored_cfg {
            refuse!(
                "{root} already holds a league started with another config ({}); resume it without --config, or pick another --dir",
                if on_disk.is_some() {
                    dir.config_path().display().to_string()
                } else {
                    format!("the one in {db}")
                }
            );
        }
    }
    Ok(on_disk)
}

/// The identity a resumed league goes on with: the store's, which
/// league.json must match; a new one for a league from before identities.
fn resume_identity(
    dir: &LeagueDir,
    stored_cfg: &LeagueConfig,
    store_identity: &Option<String>,
    file_identity: &Option<LeagueIdentity>,
) -> Result<LeagueIdentity> {
    let db = &dir.store;
    Ok(match (store_identity, file_identity) {
        (Some(s), Some(f)) if *s != f.league_id => refuse!(
            "{db}: belongs to another league (id {s}) than {} (id {}, league {}); put this league's own store back, or pick another --dir",
            dir.identity_path().display(),
            f.league_id,
            f.name
        ),
        (None, Some(f)) => refuse!(
            "{db}: has no league identity, but {} names league {} (id {}): the store is not this league's; put its own store back",
            dir.identity_path().display(),
            f.name,
            f.league_id
        ),
        (Some(s), _) => LeagueIdentity {
            league_id: s.clone(),
            name: stored_cfg.name.clone(),
        },
        (None, None) => LeagueIdentity {
            league_id: crate::run::folder::layout::new_league_id(),
            name: stored_cfg.name.clone(),
        },
    })
}

/// Opens the league for one of its processes (a learner, the evaluator),
/// which the manager starts only after `plan_start`'s checks.
pub fn open_process(dir: &LeagueDir) -> Result<Opened> {
    let store = Store::open_existing(&dir.store)?;
    let league_id = check_identity(dir, &store)?.ok_or_else(|| {
        LeagueError::Folder(format!(
            "{}: has no league identity; start the league with `t2e-league run --dir {}`",
            store.url(),
            dir.root.display()
        ))
    })?;
    Ok(Opened {
        cfg: dir.config()?,
        store,
        league_id,
    })
}

/// Opens a league to read it (`status`, `export`): nothing in the directory
/// is created or changed. A missing config.toml is read from the store.
pub fn open_read_only(dir: &LeagueDir) -> Result<(LeagueConfig, Store)> {
    let db = &dir.store;
    match db {
        StoreUrl::Sqlite(path) if !path.is_file() => refuse!(
            "{}: holds no league (no league.db); start one with `t2e-league run --config configs/league-default.toml --dir {}`",
            dir.root.display(),
            dir.root.display()
        ),
        StoreUrl::Postgres(_) if Store::presence(db)? == Presence::Missing => refuse!(
            "{db}: holds no league; start one with `t2e-league run --config configs/league-default.toml --store URL --pool DIR`"
        ),
        _ => {}
    }
    let store = Store::open_read_only(db)?;
    let Some(stored) = store.stored_config()? else {
        refuse!(
            "{db}: holds no league (its tables are empty: truncated, or its write-ahead log was lost)"
        );
    };
    let stored_cfg = LeagueConfig::parse(&stored).map_err(|e| {
        LeagueError::from(e).context(format!("{db}: the config it holds is invalid"))
    })?;
    if let Some(id) = check_identity(dir, &store)? {
        check_pool_identity(dir, &id, db)?;
    }
    if dir.config_path().is_file() && dir.config()? != stored_cfg {
        refuse!(
            "{}: differs from the config {db} holds: the store is another league's, or config.toml was edited",
            dir.config_path().display(),
        );
    }
    Ok((stored_cfg, store))
}

/// A store kept apart from its pool (PostgreSQL, `--store FILE`) is reached
/// from any folder, so a manager given the wrong `--pool` would otherwise
/// resume there: restore config.toml and league.json into it and quarantine,
/// in the store every host shares, each snapshot it cannot see. Unless the
/// league never got as far as writing files (a start killed right after
/// the store's identity), the pool must show it is this league's: its
/// league.json, or at least one of the snapshot folders the store names.
fn check_pool_holds_league(dir: &LeagueDir, store: &Store, has_identity: bool) -> Result<()> {
    let pool = dir.root.display();
    let db = store.url();
    let snapshots: Vec<String> = store
        .players()?
        .into_iter()
        .filter(|p| p.kind == crate::store::Kind::Snapshot && p.quarantined.is_none())
        .filter_map(|p| p.checkpoint.map(|(rel, _)| rel))
        .collect();
    let seen = snapshots
        .iter()
        .filter(|rel| dir.root.join(rel).exists())
        .count();
    let refuse = |what: String| -> LeagueError {
        LeagueError::Pool(format!(
            "{db} holds a league, but the pool folder {pool} is not its pool: {what}. Nothing was changed. \
             Give the pool folder this league was started with (--pool, the folder every host shares)"
        ))
    };
    if !snapshots.is_empty() && seen == 0 {
        return Err(refuse(format!(
            "it holds none of the {} snapshot folders the store names (e.g. {})",
            snapshots.len(),
            snapshots[0]
        )));
    }
    let started = !store.seats()?.is_empty() || store.match_count()? > 0 || !snapshots.is_empty();
    if !has_identity && seen == 0 && started {
        return Err(refuse(format!(
            "{} is missing{}",
            dir.identity_path().display(),
            if dir.root.is_dir() {
                ""
            } else {
                " (the folder does not exist)"
            }
        )));
    }
    Ok(())
}

/// Snapshots name their league: a pool of another league beside this store
/// means the store (or the pool) is not this league's.
fn check_pool_identity(dir: &LeagueDir, league_id: &str, db: &StoreUrl) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir.players_dir()) else {
        return Ok(());
    };
    for e in entries.flatten() {
        if e.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        if let Ok(meta) = t2e_learners::nn::checkpoint::read_meta(&e.path()) {
            if let Ok(Some(m)) = crate::run::folder::pool::PoolMembership::of(&meta) {
                if m.league_id != league_id {
                    refuse!(
                        "{}: belongs to league {}, but {db} is league {league_id}: the store and the pool are from different leagues",
                        e.path().display(),
                        m.league_id,
                    );
                }
            }
        }
    }
    Ok(())
}

/// The store's identity, checked against `league.json`; None for a league
/// from before identities (neither has one).
fn check_identity(dir: &LeagueDir, store: &Store) -> Result<Option<String>> {
    let file = dir.identity()?;
    let stored = store.league_id()?;
    match (stored, file) {
        (Some(s), Some(f)) if s == f.league_id => Ok(Some(s)),
        (Some(s), Some(f)) => refuse!(
            "{}: belongs to another league (id {s}) than {} (id {}, league {})",
            store.url(),
            dir.identity_path().display(),
            f.league_id,
            f.name
        ),
        (None, Some(f)) => refuse!(
            "{}: has no league identity, but {} names league {} (id {}): the store is not this league's",
            store.url(),
            dir.identity_path().display(),
            f.name,
            f.league_id
        ),
        (Some(s), None) => Ok(Some(s)),
        (None, None) => Ok(None),
    }
}
