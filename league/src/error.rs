//! The league's one error type, `LeagueError`, returned by every public
//! function of the crate that can fail outside the store (which keeps its
//! own `StoreError`): each variant says what a caller can act on (a
//! setting, the store, a learner, a checkpoint, the league folder or its
//! pool, a file, a child process or a lock, a request the league cannot
//! serve), and each message names the setting, the file or the player.
//!
//! The conventions are the learners' (`t2e_learners::error`): a variant
//! that wraps another error either is that error (`transparent`: its
//! message and its causes are the wrapped error's) or holds it as a cause
//! it prints after its own words, `context: cause`, through
//! `t2e_core::error::Chain`, and does not hand it on as `source()`: the
//! command line's `{:#}` then names every part once, in the words the
//! messages always had. `ResultExt::context` adds such words to any error
//! the crate returns.

use crate::rules::selection::NoChoice;
use crate::store::url::StoreUrlError;
use crate::store::StoreError;
use std::path::PathBuf;
use t2e_core::error::{Chain, ConfigError, ConfigFileError, ConfigLoadError, MapsRefused};
use t2e_core::fs::FsError;
use t2e_core::map::catalog::MapLoadError;
use t2e_learners::controllers::ControllerError;
use t2e_learners::error::LearnError;
use t2e_learners::nn::checkpoint::{CheckpointError, DoesNotFit};
use t2e_learners::nn::policy::PolicyError;
use t2e_learners::nn::run_dir::RunDirError;
use t2e_learners::nn::stacked::StackError;

/// A result whose error is, unless said otherwise, a `LeagueError`.
pub type Result<T, E = LeagueError> = std::result::Result<T, E>;

/// Why the league could not do what it was asked.
#[derive(Debug, thiserror::Error)]
pub enum LeagueError {
    /// A setting out of range: a field of the league's config, or an
    /// option of a command.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A league config's text that is not the league's schema.
    #[error(transparent)]
    ConfigFile(#[from] ConfigFileError),
    /// A league config file that cannot be read or used; names the file.
    #[error(transparent)]
    ConfigLoad(#[from] ConfigLoadError),
    /// The store: out of reach, newer than this build, not a store.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A `--store` value that names no store.
    #[error(transparent)]
    StoreUrl(#[from] StoreUrlError),
    /// What the learners report: a trainer that cannot start or go on.
    #[error(transparent)]
    Learn(#[from] LearnError),
    /// A checkpoint folder, its files or its manifest.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// A learner's run folder: its `state.json`, its checkpoints.
    #[error(transparent)]
    RunDir(#[from] RunDirError),
    /// A checkpoint that does not fit where it was asked to play; the
    /// checkpoint's folder first.
    #[error("{}: {cause}", .checkpoint.display())]
    DoesNotFit {
        checkpoint: PathBuf,
        cause: DoesNotFit,
    },
    /// Opponent networks that cannot be stacked for one forward pass.
    #[error(transparent)]
    Stack(#[from] StackError),
    /// Maps that cannot be found or loaded.
    #[error(transparent)]
    Maps(#[from] MapLoadError),
    /// Training maps that do not fit the league's protocol.
    #[error(transparent)]
    MapsRefused(#[from] MapsRefused),
    /// A heuristic member's controller that cannot be built.
    #[error(transparent)]
    Controller(#[from] ControllerError),
    /// No validation-best snapshot to choose (`export --best`).
    #[error(transparent)]
    NoChoice(#[from] NoChoice),
    /// A file or folder that could not be written whole.
    #[error(transparent)]
    Fs(#[from] FsError),
    /// File I/O; `context` names the file.
    #[error("{context}: {}", Chain(.cause))]
    Io {
        context: String,
        cause: std::io::Error,
    },
    /// A JSON file (an identity, a pool label); `context` names it.
    #[error("{context}: {}", Chain(.cause))]
    Json {
        context: String,
        cause: serde_json::Error,
    },
    /// A TOML file this program writes (a config); `context` names it.
    #[error("{context}: {}", Chain(.cause))]
    Toml {
        context: String,
        cause: toml::ser::Error,
    },
    /// A child process, a pipe, a lock file or a thread pool that could not
    /// be made, started or waited for.
    #[error("{what}: {}", Chain(.cause))]
    Process { what: String, cause: std::io::Error },
    /// A thread pool of the asked size that could not be started.
    #[error("cannot start the thread pool: {0}")]
    ThreadPool(rayon::ThreadPoolBuildError),
    /// Another process holds what this one needs: the league's manager
    /// lock or lease, an exploit's lock.
    #[error("{0}")]
    Busy(String),
    /// The league folder (or the store beside it) does not hold the league
    /// it should: missing, another league's, a config that differs.
    #[error("{0}")]
    Folder(String),
    /// The snapshot pool: a member that cannot be adopted, imported or
    /// found, a pool folder that is not the league's.
    #[error("{0}")]
    Pool(String),
    /// A checkpoint whose files are not the ones the store recorded.
    #[error("{0}")]
    Corrupt(String),
    /// A player the league does not have; `league` says where it looked.
    #[error("no player '{player}' in {league} (players: {players})")]
    UnknownPlayer {
        player: String,
        league: String,
        players: String,
    },
    /// A heuristic member asked for weights it does not have (to export, to
    /// verify a folder against).
    #[error("{0}")]
    NoWeights(String),
    /// A heuristic member of the store that the league's config does not
    /// name (`[members]`), so nothing can play it.
    #[error("{0} is a heuristic member the league's config does not name ([members])")]
    UnnamedHeuristic(String),
    /// The key an older build gave an exploit (its text form) that cannot
    /// be made from the best response's config; what is missing.
    #[error("{0}")]
    ExploitKey(String),
    /// A request the league cannot serve as given: an option that does not
    /// fit the player, a folder of another league, an output in the way.
    #[error("{0}")]
    Refused(String),
    /// A learner or the evaluator that failed before its first iteration:
    /// restarting it would fail the same way (`supervision::EXIT_CANNOT_START`).
    #[error("{}", Chain(&**.0))]
    CannotStart(Box<LeagueError>),
    /// A seat of the league failed and the league stopped; why.
    #[error("{0}")]
    Failed(String),
    /// Another of these errors, with what was being done.
    #[error("{context}: {}", Chain(&**.cause))]
    Context {
        context: String,
        cause: Box<LeagueError>,
    },
}

impl From<PolicyError> for LeagueError {
    fn from(e: PolicyError) -> LeagueError {
        match e {
            PolicyError::Checkpoint(e) => LeagueError::Checkpoint(e),
            PolicyError::RunDir(e) => LeagueError::RunDir(e),
        }
    }
}

impl LeagueError {
    /// File I/O on the file `context` names.
    pub fn io(context: impl Into<String>, cause: std::io::Error) -> LeagueError {
        LeagueError::Io {
            context: context.into(),
            cause,
        }
    }

    /// A child process, pipe or lock: `what` was being done.
    pub fn process(what: impl Into<String>, cause: std::io::Error) -> LeagueError {
        LeagueError::Process {
            what: what.into(),
            cause,
        }
    }

    /// An error before a learner's (or the evaluator's) first iteration.
    pub fn cannot_start(e: impl Into<LeagueError>) -> LeagueError {
        match e.into() {
            e @ LeagueError::CannotStart(_) => e,
            e => LeagueError::CannotStart(Box::new(e)),
        }
    }

    /// Whether restarting the process would fail the same way.
    pub fn is_cannot_start(&self) -> bool {
        matches!(self, LeagueError::CannotStart(_))
    }

    /// The error and its causes, as the command line prints them (`{:#}`):
    /// for a reason kept in the store or a log line.
    pub fn chain(&self) -> String {
        Chain(self).to_string()
    }

    /// This error with what was being done before it: `context: self`.
    pub fn context(self, context: impl Into<String>) -> LeagueError {
        LeagueError::Context {
            context: context.into(),
            cause: Box::new(self),
        }
    }
}

t2e_core::result_ext!(LeagueError);

/// `.io_context(...)` on a result of file I/O: the error names the file.
pub trait IoResultExt<T> {
    fn io_context<C: Into<String>>(self, context: impl FnOnce() -> C) -> Result<T>;
}

impl<T> IoResultExt<T> for std::io::Result<T> {
    fn io_context<C: Into<String>>(self, context: impl FnOnce() -> C) -> Result<T> {
        self.map_err(|e| LeagueError::io(context(), e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_context_prints_before_its_cause_and_a_chain_names_each_part_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let e: Result<()> = Err(LeagueError::io("cannot read a.json", io)).context("resuming");
        let e = e.unwrap_err();
        assert_eq!(e.to_string(), "resuming: cannot read a.json: gone");
        assert!(std::error::Error::source(&e).is_none());
        let e = LeagueError::Config(ConfigError::new("num_envs", 0, "must be at least 1"))
            .context("a config");
        assert_eq!(e.to_string(), "a config: num_envs = 0: must be at least 1");
    }

    #[test]
    fn cannot_start_prints_its_cause_alone_and_is_not_wrapped_twice() {
        let e = LeagueError::cannot_start(LeagueError::Folder("no league".into()));
        assert_eq!(e.to_string(), "no league");
        assert!(e.is_cannot_start());
        let twice = LeagueError::cannot_start(e);
        assert!(matches!(&twice, LeagueError::CannotStart(inner) if !inner.is_cannot_start()));
    }

    #[test]
    fn it_is_an_error_a_learner_hook_can_return() {
        let e = LearnError::hooks(LeagueError::Refused("outer".into()));
        assert_eq!(e.to_string(), "outer");
    }
}
