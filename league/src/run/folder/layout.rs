//! The league directory: everything a league is, so processes share nothing
//! else.
//!
//! ```text
//! runs/league/NAME/
//!     config.toml          the league's config (as started)
//!     league.json          the league's identity (also in the store and in
//!                          every snapshot's meta.json)
//!     league.db            the store (SQLite, WAL), unless the league's store
//!                          is a PostgreSQL database (`--store postgres://`):
//!                          then this folder is the pool that every host shares
//!     league.lock          held by the live manager (flock)
//!     learners/SIDE-main/  each main learner's run folder (state.json, checkpoints/)
//!     players/NAME/        frozen snapshots in the pool (checkpoint folders)
//!     logs/SIDE-main.log   each learner process's output
//!     exploits/PLAYER-KEY/ `exploit`'s best responses: opponent/ (the
//!                          frozen player), run/ (the best response's run)
//! ```

use crate::error::{IoResultExt, LeagueError, Result};
use crate::rules::config::LeagueConfig;
use crate::store::StoreUrl;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use t2e_core::env::Side;

/// `league.json`: which league a directory holds. The id is random, written
/// once when the league starts; the store and every snapshot carry it too.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeagueIdentity {
    pub league_id: String,
    pub name: String,
}

/// A fresh league id: 16 hex digits from the clock, the pid and a counter,
/// hashed.
pub fn new_league_id() -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let seed = format!(
        "{nanos}/{}/{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::SeqCst)
    );
    t2e_core::util::sha256_hex(seed.as_bytes())[..16].to_string()
}

#[derive(Clone, Debug)]
pub struct LeagueDir {
    pub root: PathBuf,
    /// The league's store: `league.db` in `root` by default.
    pub store: StoreUrl,
}

impl LeagueDir {
    pub fn new(root: impl Into<PathBuf>) -> LeagueDir {
        let root = root.into();
        LeagueDir {
            store: StoreUrl::in_dir(&root),
            root,
        }
    }

    /// A league whose store is elsewhere (a PostgreSQL database): `root` is
    /// the pool folder every host shares.
    pub fn with_store(root: impl Into<PathBuf>, store: StoreUrl) -> LeagueDir {
        LeagueDir {
            root: root.into(),
            store,
        }
    }

    pub fn config_path(&self) -> PathBuf {
        self.root.join("config.toml")
    }

    pub fn config(&self) -> Result<LeagueConfig> {
        Ok(LeagueConfig::load_stored(&self.config_path())?)
    }

    pub fn identity_path(&self) -> PathBuf {
        self.root.join("league.json")
    }

    /// The identity `league.json` holds; None when the file is absent.
    pub fn identity(&self) -> Result<Option<LeagueIdentity>> {
        let path = self.identity_path();
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&path)
            .io_context(|| format!("{}: cannot read", path.display()))?;
        let id: LeagueIdentity =
            serde_json::from_str(&text).map_err(|cause| LeagueError::Json {
                context: format!("{}: not a league identity", path.display()),
                cause,
            })?;
        if id.league_id.is_empty() {
            return Err(LeagueError::Folder(format!(
                "{}: league_id is empty",
                path.display()
            )));
        }
        Ok(Some(id))
    }

    pub fn write_identity(&self, id: &LeagueIdentity) -> Result<()> {
        let path = self.identity_path();
        let text = serde_json::to_string_pretty(id).map_err(|cause| LeagueError::Json {
            context: format!("{}: cannot write the league's identity", path.display()),
            cause,
        })?;
        Ok(t2e_core::fs::write_file_atomically(&path, text.as_bytes())?)
    }

    /// What on disk shows that a league lived here, beside its store: the
    /// identity file, snapshot folders, learners' run states and
    /// checkpoints. Empty for a new (or never started) league.
    pub fn league_files(&self) -> Vec<String> {
        let mut found = Vec::new();
        if self.identity_path().exists() {
            found.push("league.json".to_string());
        }
        let visible = |dir: &Path| -> usize {
            std::fs::read_dir(dir)
                .map(|it| {
                    it.flatten()
                        .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
                        .count()
                })
                .unwrap_or(0)
        };
        let snapshots = visible(&self.players_dir());
        if snapshots > 0 {
            found.push(format!("{snapshots} snapshot folders in players/"));
        }
        if let Ok(it) = std::fs::read_dir(self.root.join("learners")) {
            let mut seats: Vec<_> = it.flatten().filter(|e| e.path().is_dir()).collect();
            seats.sort_by_key(|e| e.file_name());
            for e in seats {
                let path = e.path();
                let run = t2e_learners::learn::persist::RunDir::new(&path);
                let checkpoints = run.checkpoint_names(None).map_or(0, |n| n.len());
                if run.has_state() || checkpoints > 0 {
                    found.push(format!(
                        "learners/{}/ ({checkpoints} checkpoints{})",
                        e.file_name().to_string_lossy(),
                        if run.has_state() { ", state.json" } else { "" }
                    ));
                }
            }
        }
        found
    }

    /// Whether `path` (which need not exist yet) lies inside this league
    /// directory, symbolic links resolved.
    pub fn contains(&self, path: &Path) -> bool {
        let (Some(root), Some(p)) = (resolve(&self.root), resolve(path)) else {
            return false;
        };
        p.starts_with(root)
    }

    pub fn learner_dir(&self, side: Side) -> PathBuf {
        self.seat_dir(crate::rules::players::Seat::main(side))
    }

    /// A learner's run folder (main learner or exploiter).
    pub fn seat_dir(&self, seat: crate::rules::players::Seat) -> PathBuf {
        self.root.join("learners").join(seat.name())
    }

    pub fn players_dir(&self) -> PathBuf {
        self.root.join("players")
    }

    pub fn log_path(&self, side: Side) -> PathBuf {
        self.root
            .join("logs")
            .join(format!("{}.log", crate::rules::players::learner_name(side)))
    }

    /// `path` relative to the league directory, '/'-separated (as stored).
    pub fn relative(&self, path: &Path) -> String {
        path.strip_prefix(&self.root)
            .unwrap_or(path)
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/")
    }

    /// Threads each learner process uses (libtorch intra-op and rayon): the
    /// config's number, or the machine's cores shared between the two
    /// learners.
    pub fn threads_per_learner(&self, cfg: &LeagueConfig) -> usize {
        if cfg.threads_per_learner > 0 {
            return cfg.threads_per_learner;
        }
        let cores = std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1);
        let learners = 2 + [Side::Captors, Side::Target]
            .iter()
            .filter(|s| cfg.exploiters.enabled(**s))
            .count();
        (cores / learners).max(1)
    }
}

/// `path` made absolute, `.` and `..` folded lexically, and symbolic links
/// resolved in the part of it that exists.
fn resolve(path: &Path) -> Option<PathBuf> {
    use std::path::Component;
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir().ok()?.join(path)
    };
    let mut normal = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::ParentDir => {
                normal.pop();
            }
            Component::CurDir => {}
            other => normal.push(other.as_os_str()),
        }
    }
    let mut existing = normal.clone();
    let mut rest = Vec::new();
    loop {
        if let Ok(c) = existing.canonicalize() {
            let mut out = c;
            for part in rest.iter().rev() {
                out.push(part);
            }
            return Some(out);
        }
        rest.push(existing.file_name()?.to_os_string());
        if !existing.pop() {
            return None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_inside_the_league_are_recognised_however_written() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = LeagueDir::new(tmp.path().join("league"));
        std::fs::create_dir_all(dir.players_dir()).unwrap();
        assert!(dir.contains(&dir.players_dir().join("new-export")));
        assert!(dir.contains(&dir.root.join("a/b/../c")));
        assert!(dir.contains(&tmp.path().join("league/./players/x")));
        assert!(!dir.contains(&tmp.path().join("elsewhere/x")));
        assert!(!dir.contains(&tmp.path().join("league/../x")));
        std::os::unix::fs::symlink(dir.players_dir(), tmp.path().join("alias")).unwrap();
        assert!(dir.contains(&tmp.path().join("alias/x")), "through a link");
        assert_ne!(new_league_id(), new_league_id());
    }
}
