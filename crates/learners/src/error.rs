//! The learners' one error type, `LearnError`, returned by every public
//! function of the crate that can fail: each variant says what a caller
//! can act on (a setting, the maps, a checkpoint or run folder, a file, a
//! child process, a run that diverged), and each message names the
//! setting or the file.
//!
//! A variant that wraps another error either is that error (`transparent`:
//! its message and its causes are the wrapped error's) or holds it as a
//! cause it prints after its own words, `context: cause`, through
//! `t2e_core::error::Chain`, and does not hand it on as `source()`: a
//! chain printed whole (`{:#}`) then names every part once, in the words
//! the messages always had. `ResultExt::context` adds such words to any
//! error the crate returns.

use crate::controllers::ControllerError;
use crate::nn::checkpoint::CheckpointError;
use crate::nn::run_dir::RunDirError;
use t2e_core::env::{PlacementError, Side};
use t2e_core::error::{Chain, ConfigError, EnvError, MapsRefused};
use t2e_core::fs::FsError;
use t2e_core::map::catalog::MapLoadError;

/// A result whose error is, unless said otherwise, a `LearnError`.
pub type Result<T, E = LearnError> = std::result::Result<T, E>;

/// Why the learners could not do what they were asked.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    /// A setting out of range: a config file's field or a flag's value.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// `device = "cuda"` on a machine where tch sees no CUDA device.
    #[error("device = \"cuda\" but tch sees no CUDA device; use \"auto\" or \"cpu\"")]
    NoCuda,
    /// Maps that cannot be found or loaded.
    #[error(transparent)]
    Maps(#[from] MapLoadError),
    /// Training maps that do not fit the run's protocol.
    #[error(transparent)]
    MapsRefused(#[from] MapsRefused),
    /// `[extra_maps]` that are test maps or copies of them.
    #[error("extra_maps.{0}")]
    ExtraMapsRefused(MapsRefused),
    /// An environment that cannot be built as configured.
    #[error(transparent)]
    Env(#[from] EnvError),
    /// Robots that cannot be placed on a map.
    #[error(transparent)]
    Placement(#[from] PlacementError),
    /// A controller that cannot be named, built or play where it was asked.
    #[error(transparent)]
    Controller(#[from] ControllerError),
    /// A checkpoint folder, its files or its manifest.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// A run folder: its `state.json`, its checkpoints, a run already there.
    #[error(transparent)]
    RunDir(#[from] RunDirError),
    /// A file or folder that could not be written whole.
    #[error(transparent)]
    Fs(#[from] FsError),
    /// File I/O; `context` names the file.
    #[error("{context}: {}", Chain(.cause))]
    Io {
        context: String,
        cause: std::io::Error,
    },
    /// A CSV file this program writes and reads back; `context` names it.
    #[error("{context}: {}", Chain(.cause))]
    Csv { context: String, cause: csv::Error },
    /// A JSON file a child process wrote; `context` names it.
    #[error("{context}: {}", Chain(.cause))]
    Json {
        context: String,
        cause: serde_json::Error,
    },
    /// A TOML file this program writes; `context` names it.
    #[error("{context}: {}", Chain(.cause))]
    Toml {
        context: String,
        cause: toml::ser::Error,
    },
    /// An image (a plot) that could not be written; `context` names it.
    #[error("{context}: {}", Chain(.cause))]
    Image {
        context: String,
        cause: image::ImageError,
    },
    /// `max_bad_updates` updates of one side in a row were not finite.
    #[error("{} learner: {in_a_row} updates in a row had a non-finite loss or gradient (last: {last}); stopping with the last good weights (max_bad_updates = {limit})", .side.name())]
    Diverged {
        side: Side,
        in_a_row: u32,
        last: String,
        limit: u32,
    },
    /// A child process (a periodic evaluation) that could not be started
    /// or waited for.
    #[error("{what}: {}", Chain(.cause))]
    Process { what: String, cause: std::io::Error },
    /// A side asked for that does not learn in this run.
    #[error("no {} learner in this run", .0.name())]
    NoLearner(Side),
    /// What a caller's `RolloutHooks` reported, with its causes.
    #[error("{}", Chain(&**.0))]
    Hooks(Box<dyn std::error::Error + Send + Sync + 'static>),
    /// Another of these errors, with what was being done.
    #[error("{context}: {}", Chain(&**.cause))]
    Context {
        context: String,
        cause: Box<LearnError>,
    },
}

impl LearnError {
    /// File I/O on the file `context` names.
    pub fn io(context: impl Into<String>, cause: std::io::Error) -> LearnError {
        LearnError::Io {
            context: context.into(),
            cause,
        }
    }

    /// An error of a caller's `RolloutHooks` (any error type, its causes
    /// kept).
    pub fn hooks(e: impl Into<Box<dyn std::error::Error + Send + Sync + 'static>>) -> LearnError {
        LearnError::Hooks(e.into())
    }

    /// This error with what was being done before it: `context: self`.
    pub fn context(self, context: impl Into<String>) -> LearnError {
        LearnError::Context {
            context: context.into(),
            cause: Box::new(self),
        }
    }
}

t2e_core::result_ext!(LearnError);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_context_prints_before_its_cause_and_a_chain_names_each_part_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let e: Result<()> = Err(LearnError::io("cannot read a.csv", io)).context("resuming");
        let e = e.unwrap_err();
        assert_eq!(e.to_string(), "resuming: cannot read a.csv: gone");
        assert!(std::error::Error::source(&e).is_none());
        let e = LearnError::Config(ConfigError::new("num_envs", 0, "must be at least 1"))
            .context("a config");
        assert_eq!(e.to_string(), "a config: num_envs = 0: must be at least 1");
    }

    #[test]
    fn a_hooks_error_prints_its_whole_chain() {
        #[derive(Debug, thiserror::Error)]
        #[error("outer")]
        struct Outer(#[source] std::io::Error);
        let e = LearnError::hooks(Outer(std::io::Error::other("inner")));
        assert_eq!(e.to_string(), "outer: inner");
        assert!(std::error::Error::source(&e).is_none());
    }
}
