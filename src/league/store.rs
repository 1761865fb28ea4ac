//! The league's store: one SQLite database (`league.db` in the league
//! directory) through sqlx. sqlx is async; its runtime lives here, inside
//! `Store`, so the rest of the league stays synchronous.
//!
//! Invariants:
//! - WAL, a busy timeout and short transactions: several processes (the
//!   manager, the learners, `status`) read and write it at once.
//! - The schema comes from `league/migrations/*.sql` (`sqlx::migrate!`); an
//!   older database is migrated, one written by a newer schema is refused.
//! - Queries use only portable SQL (`$N` parameters, `ON CONFLICT DO
//!   NOTHING`, no database-specific functions; times are written by the
//!   program), so a PostgreSQL store can follow for multi-machine leagues.
//! - A match is recorded once: its key names the episode (learner, world,
//!   episode), and recording it again is a no-op. The rating update of a
//!   match is written in the same transaction as the match.

use super::ratings::{self, Rating};
use crate::env::Side;
use sqlx::sqlite::{SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions};
use sqlx::Row;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Duration;

static MIGRATOR: sqlx::migrate::Migrator = sqlx::migrate!("league/migrations");

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{path}: written by a newer t2e-league (schema migration {version} is unknown to this build); use a newer build to open it")]
    NewerSchema { path: PathBuf, version: i64 },
    #[error("{path}: {source}")]
    Database {
        path: PathBuf,
        #[source]
        source: sqlx::Error,
    },
    #[error("{path}: migrating the schema failed: {source}")]
    Migrate {
        path: PathBuf,
        #[source]
        source: sqlx::migrate::MigrateError,
    },
    #[error("{0}")]
    Invalid(String),
}

/// What kind of member a player is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A main learner (its row holds its latest checkpoint).
    Learner,
    /// A frozen checkpoint of a learner, in the pool.
    Snapshot,
    /// A rule-based controller, a permanent pool member.
    Heuristic,
    /// A main exploiter.
    Exploiter,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Learner => "learner",
            Kind::Snapshot => "snapshot",
            Kind::Heuristic => "heuristic",
            Kind::Exploiter => "exploiter",
        }
    }

    fn parse(s: &str) -> Kind {
        match s {
            "learner" => Kind::Learner,
            "snapshot" => Kind::Snapshot,
            "exploiter" => Kind::Exploiter,
            _ => Kind::Heuristic,
        }
    }
}

fn side_name(side: Side) -> &'static str {
    match side {
        Side::Captors => "captors",
        Side::Target => "target",
    }
}

/// A player as written.
#[derive(Clone, Debug, PartialEq)]
pub struct NewPlayer {
    pub name: String,
    pub side: Side,
    pub kind: Kind,
    pub parent: Option<i64>,
    pub env_steps: u64,
    pub curriculum_stage: usize,
    /// Checkpoint folder relative to the league directory, and the SHA-256
    /// of its `meta.json`.
    pub checkpoint: Option<(String, String)>,
}

/// A player as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Player {
    pub id: i64,
    pub name: String,
    pub side: Side,
    pub kind: Kind,
    pub parent: Option<i64>,
    pub created_at_ms: i64,
    pub env_steps: u64,
    pub curriculum_stage: usize,
    pub checkpoint: Option<(String, String)>,
    /// Why it no longer plays (missing or corrupt files), if it does not.
    pub quarantined: Option<String>,
}

/// One finished episode between a captor team and a target.
#[derive(Clone, Debug, PartialEq)]
pub struct MatchRecord {
    /// Names the episode: the same key is recorded once.
    pub key: String,
    pub captor_player: i64,
    pub target_player: i64,
    pub map: String,
    pub num_captors: usize,
    pub speed_ratio: f64,
    pub seed: u64,
    pub captured: bool,
    pub steps: u32,
    pub final_asz_m2: Option<f64>,
    pub recorded_by: String,
}

/// Wins and games of the captor team `captor` against the target `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairResult {
    pub captor: i64,
    pub target: i64,
    pub captor_wins: u64,
    pub games: u64,
}

pub fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// How a process opens the store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Access {
    Create,
    Existing,
    ReadOnly { immutable: bool },
}

/// A `league.db` that is missing or empty is not a store.
fn check_present(path: &Path) -> Result<(), StoreError> {
    match std::fs::metadata(path) {
        Ok(m) if m.len() > 0 => Ok(()),
        Ok(_) => Err(StoreError::Invalid(format!(
            "{}: empty (0 bytes): the league's store was truncated",
            path.display()
        ))),
        Err(_) => Err(StoreError::Invalid(format!(
            "{}: missing: the directory holds no league store",
            path.display()
        ))),
    }
}

/// A learner's (or the evaluator's) latest heartbeat.
#[derive(Clone, Debug, PartialEq)]
pub struct Heartbeat {
    pub learner: String,
    pub pid: i64,
    /// The machine it runs on (its pid means something only there).
    pub host: Option<String>,
    pub state: String,
    pub env_steps: u64,
    pub steps_per_s: f64,
    pub at_ms: i64,
}

/// A learner process that exited unasked.
#[derive(Clone, Debug, PartialEq)]
pub struct Crash {
    pub learner: String,
    pub exit_status: String,
    pub message: String,
    pub at_ms: i64,
}

/// A curriculum stage change.
#[derive(Clone, Debug, PartialEq)]
pub struct StageChange {
    pub stage: usize,
    pub speed_ratio: f64,
    pub reason: String,
    pub at_ms: i64,
}

/// This machine's name, for heartbeats.
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .ok()
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "localhost".into())
}

pub struct Store {
    rt: tokio::runtime::Runtime,
    pool: SqlitePool,
    path: PathBuf,
}

impl Store {
    /// Opens (creating if needed) the store of a league directory and brings
    /// its schema up to date. Only a league being started creates its store;
    /// every other process opens it with `open_existing`.
    pub fn open(league_dir: &Path) -> Result<Store, StoreError> {
        std::fs::create_dir_all(league_dir).map_err(|e| {
            StoreError::Invalid(format!("cannot create {}: {e}", league_dir.display()))
        })?;
        Store::connect(league_dir, Access::Create)
    }

    /// Opens the store a league directory already holds, refusing a missing
    /// or empty `league.db` (SQLite would take either for a new database).
    pub fn open_existing(league_dir: &Path) -> Result<Store, StoreError> {
        let path = league_dir.join("league.db");
        check_present(&path)?;
        Store::connect(league_dir, Access::Existing)
    }

    /// Opens a league's store for reading only (`status`, `export`): nothing
    /// in the league directory is created or changed, so it works on a
    /// read-only copy. The schema is not migrated; an older one is refused
    /// with the command that migrates it.
    pub fn open_read_only(league_dir: &Path) -> Result<Store, StoreError> {
        let store = Store::inspect(league_dir)?;
        let path = store.path.clone();
        let applied: Vec<i64> = store
            .rt
            .block_on(
                sqlx::query("SELECT version FROM _sqlx_migrations WHERE success = TRUE")
                    .fetch_all(&store.pool),
            )
            .map_err(|e| store.db(e))?
            .iter()
            .map(|r| r.get::<i64, _>(0))
            .collect();
        for m in MIGRATOR.iter() {
            if !applied.contains(&m.version) {
                return Err(StoreError::Invalid(format!(
                    "{}: written by an older t2e-league (schema migration {} missing); `t2e-league run --dir {}` migrates it",
                    path.display(),
                    m.version,
                    league_dir.display()
                )));
            }
        }
        if let Some(v) = applied
            .iter()
            .find(|v| !MIGRATOR.iter().any(|m| m.version == **v))
        {
            return Err(StoreError::NewerSchema { path, version: *v });
        }
        Ok(store)
    }

    /// Opens a store read-only whatever its schema version, to check what
    /// it holds before anything is written (a file that is not a league's
    /// store is refused untouched).
    pub fn inspect(league_dir: &Path) -> Result<Store, StoreError> {
        let path = league_dir.join("league.db");
        check_present(&path)?;
        let probe = |store: &Store| {
            store
                .rt
                .block_on(sqlx::query("SELECT COUNT(*) FROM league_config").fetch_one(&store.pool))
                .map(|_| ())
                .map_err(|e| store.db(e))
        };
        let normal = Store::connect(league_dir, Access::ReadOnly { immutable: false })
            .and_then(|s| probe(&s).map(|()| s));
        let store = match normal {
            Ok(s) => s,
            Err(first) => {
                // A WAL database whose -shm file is absent and cannot be
                // created (a read-only directory) opens only as immutable,
                // which ignores the write-ahead log: refuse rather than read
                // a stale store when the log holds changes.
                let wal = league_dir.join("league.db-wal");
                if std::fs::metadata(&wal).is_ok_and(|m| m.len() > 0) {
                    return Err(StoreError::Invalid(format!(
                        "{}: cannot be read here ({first}); its write-ahead log {} holds changes not yet in it, which only a process that can write the directory can read",
                        path.display(),
                        wal.display()
                    )));
                }
                let s = Store::connect(league_dir, Access::ReadOnly { immutable: true })?;
                probe(&s).map_err(|e| {
                    StoreError::Invalid(format!(
                        "{}: not a league store, or not readable as one ({e}); restore it from a backup",
                        path.display()
                    ))
                })?;
                s
            }
        };
        Ok(store)
    }

    fn connect(league_dir: &Path, access: Access) -> Result<Store, StoreError> {
        let path = league_dir.join("league.db");
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .build()
            .map_err(|e| StoreError::Invalid(format!("cannot start the store's runtime: {e}")))?;
        let db = |source| StoreError::Database {
            path: path.clone(),
            source,
        };
        let mut options = SqliteConnectOptions::from_str(&format!("sqlite://{}", path.display()))
            .map_err(db)?
            .busy_timeout(Duration::from_secs(30))
            .foreign_keys(true);
        options = match access {
            Access::Create | Access::Existing => options
                .create_if_missing(access == Access::Create)
                .journal_mode(SqliteJournalMode::Wal),
            Access::ReadOnly { immutable } => options.read_only(true).immutable(immutable),
        };
        let pool = rt
            .block_on(
                SqlitePoolOptions::new()
                    .max_connections(1)
                    .connect_with(options),
            )
            .map_err(db)?;
        if matches!(access, Access::Create | Access::Existing) {
            match rt.block_on(MIGRATOR.run(&pool)) {
                Ok(()) => {}
                Err(sqlx::migrate::MigrateError::VersionMissing(version)) => {
                    return Err(StoreError::NewerSchema { path, version })
                }
                Err(source) => return Err(StoreError::Migrate { path, source }),
            }
        }
        Ok(Store { rt, pool, path })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    fn db(&self, source: sqlx::Error) -> StoreError {
        StoreError::Database {
            path: self.path.clone(),
            source,
        }
    }

    /// Stores the league's config the first time; returns the one stored
    /// (the first), so a resumed league can tell whether it changed.
    pub fn config_once(&self, toml: &str) -> Result<String, StoreError> {
        self.rt.block_on(async {
            sqlx::query(
                "INSERT INTO league_config (id, config_toml, created_at_ms) VALUES (1, $1, $2) ON CONFLICT (id) DO NOTHING",
            )
            .bind(toml)
            .bind(now_ms())
            .execute(&self.pool)
            .await?;
            let row = sqlx::query("SELECT config_toml FROM league_config WHERE id = 1")
                .fetch_one(&self.pool)
                .await?;
            Ok::<_, sqlx::Error>(row.get::<String, _>(0))
        })
        .map_err(|e| self.db(e))
    }

    /// The config the league was started with, if the store holds one (an
    /// empty store does not).
    pub fn stored_config(&self) -> Result<Option<String>, StoreError> {
        self.rt
            .block_on(
                sqlx::query("SELECT config_toml FROM league_config WHERE id = 1")
                    .fetch_optional(&self.pool),
            )
            .map(|r| r.map(|r| r.get::<String, _>(0)))
            .map_err(|e| self.db(e))
    }

    /// The league's identity, if one was written (a store from before
    /// identities has no such column until it is migrated).
    pub fn league_id(&self) -> Result<Option<String>, StoreError> {
        let row = self
            .rt
            .block_on(
                sqlx::query("SELECT * FROM league_config WHERE id = 1").fetch_optional(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(row.and_then(|r| r.try_get::<Option<String>, _>("league_id").ok().flatten()))
    }

    /// Takes a member back into play: its files verify again.
    pub fn reinstate(&self, id: i64) -> Result<(), StoreError> {
        self.rt
            .block_on(
                sqlx::query("UPDATE players SET quarantined = NULL WHERE id = $1")
                    .bind(id)
                    .execute(&self.pool),
            )
            .map(|_| ())
            .map_err(|e| self.db(e))
    }

    /// Writes the league's identity once (the config row must exist);
    /// returns the identity stored, which is `id` unless one was there.
    pub fn set_league_id_once(&self, id: &str) -> Result<String, StoreError> {
        self.rt
            .block_on(
                sqlx::query(
                    "UPDATE league_config SET league_id = $1 WHERE id = 1 AND league_id IS NULL",
                )
                .bind(id)
                .execute(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        self.league_id()?.ok_or_else(|| {
            StoreError::Invalid(format!(
                "{}: holds no league config to attach an identity to",
                self.path.display()
            ))
        })
    }

    /// Matches a recorder (a learner's name, or "evaluator") wrote.
    pub fn matches_recorded_by(&self, recorder: &str) -> Result<u64, StoreError> {
        self.rt
            .block_on(
                sqlx::query("SELECT COUNT(*) FROM matches WHERE recorded_by = $1")
                    .bind(recorder)
                    .fetch_one(&self.pool),
            )
            .map(|r| r.get::<i64, _>(0) as u64)
            .map_err(|e| self.db(e))
    }

    /// Adds a player; a player of the same name already there is returned
    /// as it is (adding is idempotent, so a killed writer cannot duplicate).
    /// A recorded member never changes: adding a name that is recorded with
    /// other checkpoint files is an error, not a silent no-op.
    pub fn add_player(&self, p: &NewPlayer) -> Result<i64, StoreError> {
        let (path, sha) = match &p.checkpoint {
            Some((a, b)) => (Some(a.clone()), Some(b.clone())),
            None => (None, None),
        };
        let (id, stored_path, stored_sha) = self
            .rt
            .block_on(async {
                sqlx::query(
                    "INSERT INTO players (name, side, kind, parent, created_at_ms, env_steps, curriculum_stage, checkpoint_path, checkpoint_sha256) \
                     VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9) ON CONFLICT (name) DO NOTHING",
                )
                .bind(&p.name)
                .bind(side_name(p.side))
                .bind(p.kind.name())
                .bind(p.parent)
                .bind(now_ms())
                .bind(p.env_steps as i64)
                .bind(p.curriculum_stage as i64)
                .bind(&path)
                .bind(&sha)
                .execute(&self.pool)
                .await?;
                let row = sqlx::query(
                    "SELECT id, checkpoint_path, checkpoint_sha256 FROM players WHERE name = $1",
                )
                .bind(&p.name)
                .fetch_one(&self.pool)
                .await?;
                Ok::<_, sqlx::Error>((
                    row.get::<i64, _>("id"),
                    row.get::<Option<String>, _>("checkpoint_path"),
                    row.get::<Option<String>, _>("checkpoint_sha256"),
                ))
            })
            .map_err(|e| self.db(e))?;
        if p.checkpoint.is_some() && (stored_path != path || stored_sha != sha) {
            return Err(StoreError::Invalid(format!(
                "{}: player {} is already recorded with other checkpoint files ({} sha256 {}); a recorded member never changes",
                self.path.display(),
                p.name,
                stored_path.as_deref().unwrap_or("none"),
                stored_sha.as_deref().unwrap_or("none"),
            )));
        }
        Ok(id)
    }

    /// Points a learner's row at its newest checkpoint.
    pub fn update_learner(
        &self,
        id: i64,
        env_steps: u64,
        checkpoint: (&str, &str),
    ) -> Result<(), StoreError> {
        self.rt
            .block_on(
                sqlx::query(
                    "UPDATE players SET env_steps = $1, checkpoint_path = $2, checkpoint_sha256 = $3 WHERE id = $4",
                )
                .bind(env_steps as i64)
                .bind(checkpoint.0)
                .bind(checkpoint.1)
                .bind(id)
                .execute(&self.pool),
            )
            .map(|_| ())
            .map_err(|e| self.db(e))
    }

    /// Takes a member out of play, saying why.
    pub fn quarantine(&self, id: i64, why: &str) -> Result<(), StoreError> {
        self.rt
            .block_on(
                sqlx::query("UPDATE players SET quarantined = $1 WHERE id = $2")
                    .bind(why)
                    .bind(id)
                    .execute(&self.pool),
            )
            .map(|_| ())
            .map_err(|e| self.db(e))
    }

    pub fn players(&self) -> Result<Vec<Player>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(
                    "SELECT id, name, side, kind, parent, created_at_ms, env_steps, curriculum_stage, checkpoint_path, checkpoint_sha256, quarantined \
                     FROM players ORDER BY id",
                )
                .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| {
                let path: Option<String> = r.get("checkpoint_path");
                let sha: Option<String> = r.get("checkpoint_sha256");
                Player {
                    id: r.get("id"),
                    name: r.get("name"),
                    side: if r.get::<String, _>("side") == "captors" {
                        Side::Captors
                    } else {
                        Side::Target
                    },
                    kind: Kind::parse(&r.get::<String, _>("kind")),
                    parent: r.get("parent"),
                    created_at_ms: r.get("created_at_ms"),
                    env_steps: r.get::<i64, _>("env_steps") as u64,
                    curriculum_stage: r.get::<i64, _>("curriculum_stage") as usize,
                    checkpoint: path.zip(sha),
                    quarantined: r.get("quarantined"),
                }
            })
            .collect())
    }

    /// Records a match and updates both players' live ratings, in one
    /// transaction. Returns false (and changes nothing) when a match with
    /// the same key is already recorded.
    pub fn record_match(&self, m: &MatchRecord) -> Result<bool, StoreError> {
        if !m.speed_ratio.is_finite() || m.final_asz_m2.is_some_and(|a| !a.is_finite()) {
            return Err(StoreError::Invalid(format!(
                "match {}: non-finite speed ratio or |ASZ|",
                m.key
            )));
        }
        self.rt
            .block_on(async {
                let mut tx = self.pool.begin().await?;
                let inserted = sqlx::query(
                    "INSERT INTO matches (match_key, captor_player, target_player, map, num_captors, speed_ratio, seed, captured, steps, final_asz_m2, recorded_by, recorded_at_ms) \
                     VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12) ON CONFLICT (match_key) DO NOTHING",
                )
                .bind(&m.key)
                .bind(m.captor_player)
                .bind(m.target_player)
                .bind(&m.map)
                .bind(m.num_captors as i64)
                .bind(m.speed_ratio)
                .bind(m.seed as i64)
                .bind(m.captured as i64)
                .bind(m.steps as i64)
                .bind(m.final_asz_m2)
                .bind(&m.recorded_by)
                .bind(now_ms())
                .execute(&mut *tx)
                .await?
                .rows_affected()
                    == 1;
                if !inserted {
                    tx.rollback().await?;
                    return Ok(false);
                }
                let match_id: i64 = sqlx::query("SELECT id FROM matches WHERE match_key = $1")
                    .bind(&m.key)
                    .fetch_one(&mut *tx)
                    .await?
                    .get(0);
                let mut current = [Rating::default(); 2];
                for (slot, player) in current.iter_mut().zip([m.captor_player, m.target_player]) {
                    if let Some(row) = sqlx::query(
                        "SELECT mu, sigma FROM ratings WHERE player = $1 ORDER BY id DESC LIMIT 1",
                    )
                    .bind(player)
                    .fetch_optional(&mut *tx)
                    .await?
                    {
                        *slot = Rating {
                            mu: row.get(0),
                            sigma: row.get(1),
                        };
                    }
                }
                let (c, t) = ratings::update(current[0], current[1], m.captured);
                for (player, r) in [(m.captor_player, c), (m.target_player, t)] {
                    sqlx::query(
                        "INSERT INTO ratings (player, match_id, mu, sigma, at_ms) VALUES ($1, $2, $3, $4, $5)",
                    )
                    .bind(player)
                    .bind(match_id)
                    .bind(r.mu)
                    .bind(r.sigma)
                    .bind(now_ms())
                    .execute(&mut *tx)
                    .await?;
                }
                tx.commit().await?;
                Ok::<_, sqlx::Error>(true)
            })
            .map_err(|e| self.db(e))
    }

    pub fn has_match(&self, key: &str) -> Result<bool, StoreError> {
        self.rt
            .block_on(
                sqlx::query("SELECT COUNT(*) FROM matches WHERE match_key = $1")
                    .bind(key)
                    .fetch_one(&self.pool),
            )
            .map(|r| r.get::<i64, _>(0) > 0)
            .map_err(|e| self.db(e))
    }

    pub fn match_count(&self) -> Result<u64, StoreError> {
        self.rt
            .block_on(sqlx::query("SELECT COUNT(*) FROM matches").fetch_one(&self.pool))
            .map(|r| r.get::<i64, _>(0) as u64)
            .map_err(|e| self.db(e))
    }

    /// The payoff table: captor wins and games per captor-target pair.
    pub fn payoff(&self) -> Result<Vec<PairResult>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(
                    "SELECT captor_player, target_player, SUM(captured), COUNT(*) FROM matches \
                     GROUP BY captor_player, target_player ORDER BY captor_player, target_player",
                )
                .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| PairResult {
                captor: r.get(0),
                target: r.get(1),
                captor_wins: r.get::<i64, _>(2) as u64,
                games: r.get::<i64, _>(3) as u64,
            })
            .collect())
    }

    /// Each player's latest live rating (players without matches are absent).
    pub fn ratings(&self) -> Result<HashMap<i64, Rating>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(
                    "SELECT r.player, r.mu, r.sigma FROM ratings r \
                     WHERE r.id = (SELECT MAX(q.id) FROM ratings q WHERE q.player = r.player)",
                )
                .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| {
                (
                    r.get::<i64, _>(0),
                    Rating {
                        mu: r.get(1),
                        sigma: r.get(2),
                    },
                )
            })
            .collect())
    }

    /// A player's live ratings, oldest first: (match id, mu, sigma, at ms).
    pub fn rating_history(
        &self,
        player: i64,
    ) -> Result<Vec<(Option<i64>, f64, f64, i64)>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(
                    "SELECT match_id, mu, sigma, at_ms FROM ratings WHERE player = $1 ORDER BY id",
                )
                .bind(player)
                .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| (r.get(0), r.get(1), r.get(2), r.get(3)))
            .collect())
    }

    /// Appends a curriculum stage change.
    pub fn push_curriculum(
        &self,
        stage: usize,
        speed_ratio: f64,
        reason: &str,
    ) -> Result<(), StoreError> {
        self.rt
            .block_on(
                sqlx::query(
                    "INSERT INTO curriculum (stage, speed_ratio, reason, at_ms) VALUES ($1, $2, $3, $4)",
                )
                .bind(stage as i64)
                .bind(speed_ratio)
                .bind(reason)
                .bind(now_ms())
                .execute(&self.pool),
            )
            .map(|_| ())
            .map_err(|e| self.db(e))
    }

    /// Outcomes (captured or not), oldest first, of the last `limit`
    /// matches `captor_player` played at `speed_ratio` since `since_ms`: the
    /// curriculum's window, rebuilt when a learner restarts.
    pub fn recent_outcomes(
        &self,
        captor_player: i64,
        speed_ratio: f64,
        since_ms: i64,
        limit: usize,
    ) -> Result<Vec<bool>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(
                    "SELECT captured FROM matches WHERE captor_player = $1 AND ABS(speed_ratio - $2) < 1e-9 \
                     AND recorded_at_ms >= $3 ORDER BY id DESC LIMIT $4",
                )
                .bind(captor_player)
                .bind(speed_ratio)
                .bind(since_ms)
                .bind(limit as i64)
                .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows.iter().rev().map(|r| r.get::<i64, _>(0) != 0).collect())
    }

    /// Curriculum stage changes, oldest first.
    pub fn curriculum_history(&self) -> Result<Vec<StageChange>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query("SELECT stage, speed_ratio, reason, at_ms FROM curriculum ORDER BY id")
                    .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| StageChange {
                stage: r.get::<i64, _>("stage") as usize,
                speed_ratio: r.get("speed_ratio"),
                reason: r.get("reason"),
                at_ms: r.get("at_ms"),
            })
            .collect())
    }

    /// A learner's latest state and throughput; `steps_per_s` None keeps
    /// the rate last reported (a run that trained no step measured none).
    pub fn heartbeat(
        &self,
        learner: &str,
        state: &str,
        env_steps: u64,
        steps_per_s: Option<f64>,
    ) -> Result<(), StoreError> {
        let rate = steps_per_s.map(|r| if r.is_finite() { r } else { 0.0 });
        self.rt
            .block_on(
                sqlx::query(
                    "INSERT INTO heartbeats (learner, pid, host, state, env_steps, steps_per_s, at_ms) VALUES ($1, $2, $3, $4, $5, COALESCE($6, 0.0), $7) \
                     ON CONFLICT (learner) DO UPDATE SET pid = excluded.pid, host = excluded.host, state = excluded.state, env_steps = excluded.env_steps, \
                     steps_per_s = COALESCE($6, heartbeats.steps_per_s), at_ms = excluded.at_ms",
                )
                .bind(learner)
                .bind(std::process::id() as i64)
                .bind(host_name())
                .bind(state)
                .bind(env_steps as i64)
                .bind(rate)
                .bind(now_ms())
                .execute(&self.pool),
            )
            .map(|_| ())
            .map_err(|e| self.db(e))
    }

    pub fn heartbeats(&self) -> Result<Vec<Heartbeat>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(
                    "SELECT learner, pid, host, state, env_steps, steps_per_s, at_ms FROM heartbeats ORDER BY learner",
                )
                .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| Heartbeat {
                learner: r.get("learner"),
                pid: r.get("pid"),
                host: r.get("host"),
                state: r.get("state"),
                env_steps: r.get::<i64, _>("env_steps") as u64,
                steps_per_s: r.get("steps_per_s"),
                at_ms: r.get("at_ms"),
            })
            .collect())
    }

    pub fn record_crash(
        &self,
        learner: &str,
        exit_status: &str,
        message: &str,
    ) -> Result<(), StoreError> {
        self.rt
            .block_on(
                sqlx::query(
                    "INSERT INTO crashes (learner, exit_status, message, at_ms) VALUES ($1, $2, $3, $4)",
                )
                .bind(learner)
                .bind(exit_status)
                .bind(message)
                .bind(now_ms())
                .execute(&self.pool),
            )
            .map(|_| ())
            .map_err(|e| self.db(e))
    }

    /// Crashes, oldest first.
    pub fn crashes(&self) -> Result<Vec<Crash>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query("SELECT learner, exit_status, message, at_ms FROM crashes ORDER BY id")
                    .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(rows
            .iter()
            .map(|r| Crash {
                learner: r.get("learner"),
                exit_status: r.get("exit_status"),
                message: r.get("message"),
                at_ms: r.get("at_ms"),
            })
            .collect())
    }
}

impl Drop for Store {
    /// Closes the connection, so the last one to close folds the
    /// write-ahead log into league.db and removes it: a league left alone
    /// is a single file that a reader without write access can open.
    fn drop(&mut self) {
        self.rt.block_on(self.pool.close());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn player(name: &str, side: Side, kind: Kind) -> NewPlayer {
        NewPlayer {
            name: name.into(),
            side,
            kind,
            parent: None,
            env_steps: 0,
            curriculum_stage: 0,
            checkpoint: None,
        }
    }

    fn game(key: &str, c: i64, t: i64, captured: bool) -> MatchRecord {
        MatchRecord {
            key: key.into(),
            captor_player: c,
            target_player: t,
            map: "m".into(),
            num_captors: 3,
            speed_ratio: 1.0,
            seed: 7,
            captured,
            steps: 120,
            final_asz_m2: Some(0.2),
            recorded_by: "test".into(),
        }
    }

    #[test]
    fn matches_count_once_and_move_ratings() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let c = store
            .add_player(&player("captors-main", Side::Captors, Kind::Learner))
            .unwrap();
        let t = store
            .add_player(&player("rule-based", Side::Target, Kind::Heuristic))
            .unwrap();
        assert_eq!(
            store
                .add_player(&player("captors-main", Side::Captors, Kind::Learner))
                .unwrap(),
            c,
            "adding twice is a no-op"
        );
        assert!(store.record_match(&game("a/0/0", c, t, true)).unwrap());
        assert!(
            !store.record_match(&game("a/0/0", c, t, true)).unwrap(),
            "same key: no-op"
        );
        assert!(store.record_match(&game("a/0/1", c, t, false)).unwrap());
        assert!(store.record_match(&game("a/1/0", c, t, true)).unwrap());
        assert_eq!(store.match_count().unwrap(), 3);
        assert_eq!(
            store.payoff().unwrap(),
            vec![PairResult {
                captor: c,
                target: t,
                captor_wins: 2,
                games: 3
            }]
        );
        let r = store.ratings().unwrap();
        assert!(r[&c].mu > r[&t].mu, "{r:?}");
        // Reopening keeps everything (and migrates nothing twice).
        drop(store);
        let store = Store::open(dir.path()).unwrap();
        assert_eq!(store.players().unwrap().len(), 2);
        assert_eq!(store.config_once("a = 1").unwrap(), "a = 1");
        assert_eq!(
            store.config_once("a = 2").unwrap(),
            "a = 1",
            "the first config stays"
        );
        store
            .push_curriculum(1, 1.2, "captors won 61% at 1.0")
            .unwrap();
        assert_eq!(store.curriculum_history().unwrap()[0].speed_ratio, 1.2);
        store
            .heartbeat("captors-main", "training", 640, Some(512.0))
            .unwrap();
        store
            .heartbeat("captors-main", "training", 1280, Some(530.0))
            .unwrap();
        assert_eq!(store.heartbeats().unwrap().len(), 1);
        store.heartbeat("captors-main", "done", 1280, None).unwrap();
        let beat = &store.heartbeats().unwrap()[0];
        assert_eq!(
            (beat.state.as_str(), beat.steps_per_s),
            ("done", 530.0),
            "a run that trained nothing keeps the last rate"
        );
        store
            .record_crash("target-main", "signal 9", "killed")
            .unwrap();
        assert_eq!(store.crashes().unwrap().len(), 1);
        store.quarantine(t, "files missing").unwrap();
        assert_eq!(
            store.players().unwrap()[1].quarantined.as_deref(),
            Some("files missing")
        );
    }

    #[test]
    fn the_curriculum_window_comes_back_from_the_store() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let c = store
            .add_player(&player("captors-main", Side::Captors, Kind::Learner))
            .unwrap();
        let t = store
            .add_player(&player("rule-based", Side::Target, Kind::Heuristic))
            .unwrap();
        for (i, won) in [true, false, true, true, false].into_iter().enumerate() {
            store
                .record_match(&game(&format!("k/{i}"), c, t, won))
                .unwrap();
        }
        let faster = MatchRecord {
            speed_ratio: 1.2,
            ..game("k/fast", c, t, true)
        };
        store.record_match(&faster).unwrap();
        assert_eq!(
            store.recent_outcomes(c, 1.0, 0, 3).unwrap(),
            vec![true, true, false],
            "the last 3, oldest first"
        );
        assert_eq!(store.recent_outcomes(c, 1.2, 0, 10).unwrap(), vec![true]);
        assert_eq!(
            store.recent_outcomes(t, 1.0, 0, 10).unwrap(),
            Vec::<bool>::new(),
            "only this captor's"
        );
        assert!(
            store
                .recent_outcomes(c, 1.0, now_ms() + 60_000, 10)
                .unwrap()
                .is_empty(),
            "only since the stage began"
        );
    }

    #[test]
    fn a_newer_schema_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        store
            .rt
            .block_on(
                sqlx::query(
                    "INSERT INTO _sqlx_migrations (version, description, installed_on, success, checksum, execution_time) \
                     VALUES (9999, 'from the future', CURRENT_TIMESTAMP, TRUE, x'00', 0)",
                )
                .execute(&store.pool),
            )
            .unwrap();
        drop(store);
        let err = Store::open(dir.path()).err().unwrap().to_string();
        assert!(err.contains("newer") && err.contains("9999"), "{err}");
    }
}
