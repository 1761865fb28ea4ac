//! The league directory: everything a league is, so processes share nothing
//! else.
//!
//! ```text
//! runs/league/NAME/
//!     config.toml          the league's config (as started)
//!     league.db            the store (SQLite, WAL)
//!     league.lock          held by the live manager (flock)
//!     learners/SIDE-main/  each main learner's run folder (state.json, checkpoints/)
//!     players/NAME/        frozen snapshots in the pool (checkpoint folders)
//!     logs/SIDE-main.log   each learner process's output
//! ```

use super::config::LeagueConfig;
use crate::env::Side;
use anyhow::Result;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub struct LeagueDir {
    pub root: PathBuf,
}

impl LeagueDir {
    pub fn new(root: impl Into<PathBuf>) -> LeagueDir {
        LeagueDir { root: root.into() }
    }

    pub fn config_path(&self) -> PathBuf {
        self.root.join("config.toml")
    }

    pub fn config(&self) -> Result<LeagueConfig> {
        LeagueConfig::load_stored(&self.config_path())
    }

    pub fn learner_dir(&self, side: Side) -> PathBuf {
        self.seat_dir(super::learner::Seat::main(side))
    }

    /// A learner's run folder (main learner or exploiter).
    pub fn seat_dir(&self, seat: super::learner::Seat) -> PathBuf {
        self.root.join("learners").join(seat.name())
    }

    pub fn players_dir(&self) -> PathBuf {
        self.root.join("players")
    }

    pub fn log_path(&self, side: Side) -> PathBuf {
        self.root
            .join("logs")
            .join(format!("{}.log", super::learner::learner_name(side)))
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
