//! A training run's folder, and the one place that knows its layout:
//!
//! ```text
//! RUN/
//!   config.toml                 the run's config, as `train` was given it
//!   state.json                  where the run stands (`RunState`)
//!   checkpoints/SIDE-ENVSTEPS/  one checkpoint folder per save (nn::checkpoint)
//!   metrics.csv, curves.png     one row per iteration, and its curves (`train`)
//!   teacher.csv                 a target with `ppo.teacher`: one row per
//!                               iteration, how its moves match the teacher's
//!   evals/SIDE-ENVSTEPS/        `train --eval-every`'s evaluations, gathered
//!                               in eval.csv, eval.png and departure.png
//! ```
//!
//! `train`, the league's learners and `exploit`'s best responses all keep
//! their runs this way, so every question about a run folder (is there a
//! run, which checkpoints does it hold, which one does it resume from) is
//! answered here. Checkpoint names sort by age (the env steps are
//! zero-padded); a folder whose name starts with a dot is a write in
//! progress and never counts.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use t2e_core::env::Side;
use t2e_core::fs::{clean_stale_temporaries, write_file_atomically, FsError};

/// What went wrong with a run folder; each message names the file.
#[derive(Debug, thiserror::Error)]
pub enum RunDirError {
    #[error("{}: cannot read (nothing to resume): {cause}", .path.display())]
    Unreadable {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: not a run state: {cause}", .path.display())]
    NotAState {
        path: PathBuf,
        cause: serde_json::Error,
    },
    #[error("{}: names the {side} checkpoint {}, which is missing or incomplete; refusing to fall back to an older one", .state.display(), .checkpoint.display())]
    NamedCheckpointGone {
        state: PathBuf,
        side: &'static str,
        checkpoint: PathBuf,
    },
    #[error("cannot read {}: {cause}", .dir.display())]
    Unlistable { dir: PathBuf, cause: std::io::Error },
    #[error("cannot remove the old checkpoint {}: {cause}", .path.display())]
    Unremovable {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// `state.json` that the run resumed from it cannot follow: another
    /// configuration, a checkpoint it does not name, one that is missing or
    /// holds other counts; `what` says which.
    #[error("{}: {what}", .state.display())]
    StateDisagrees { state: PathBuf, what: String },
    /// A new run asked for in a folder that holds one.
    #[error("{} already holds a run: add --resume to continue it, or pick another --out or name", .0.display())]
    HoldsARun(PathBuf),
    #[error(transparent)]
    Write(#[from] FsError),
}

/// `state.json`: where a run stands, written after every checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunState {
    pub iteration: u64,
    pub env_steps: u64,
    pub wall_s: f64,
    pub config_hash: String,
    /// Checkpoint folder names (under `checkpoints/`) per learning side.
    pub checkpoints: Vec<(Side, String)>,
}

impl RunState {
    /// The checkpoint folder name this state names for `side`.
    pub fn checkpoint_of(&self, side: Side) -> Option<&str> {
        self.checkpoints
            .iter()
            .find(|(s, _)| *s == side)
            .map(|(_, n)| n.as_str())
    }
}

/// Where a run folder stands for a learner about to resume
/// (`RunDir::recover`).
#[derive(Clone, Debug, PartialEq)]
pub enum Recovery {
    /// `state.json` is there, as read.
    Kept { env_steps: u64 },
    /// `state.json` was missing and is rebuilt from this checkpoint, the
    /// newest that verifies, was written under the run's config and is not
    /// behind what the run is known to have played.
    Rebuilt { checkpoint: PathBuf, env_steps: u64 },
    /// No `state.json` and no checkpoint: nothing was ever saved.
    Empty,
    /// No `state.json`, and every checkpoint was refused: `name: why`.
    Unusable(Vec<String>),
}

/// A run folder (it need not exist yet).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunDir {
    root: PathBuf,
}

impl RunDir {
    pub fn new(root: impl Into<PathBuf>) -> RunDir {
        RunDir { root: root.into() }
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    pub fn state_path(&self) -> PathBuf {
        self.root.join("state.json")
    }

    pub fn config_path(&self) -> PathBuf {
        self.root.join("config.toml")
    }

    pub fn metrics_path(&self) -> PathBuf {
        self.root.join("metrics.csv")
    }

    pub fn teacher_path(&self) -> PathBuf {
        self.root.join("teacher.csv")
    }

    /// A DAgger target's agreement with its teacher on the states it was
    /// fitted on (`teacher.csv` holds it on each new rollout).
    pub fn dagger_path(&self) -> PathBuf {
        self.root.join("dagger.csv")
    }

    pub fn curves_path(&self) -> PathBuf {
        self.root.join("curves.png")
    }

    /// The folder of the periodic evaluation of `side`'s checkpoint at
    /// `env_steps`.
    pub fn eval_dir(&self, side: Side, env_steps: u64) -> PathBuf {
        self.root
            .join("evals")
            .join(format!("{}-{env_steps:012}", side.name()))
    }

    /// The periodic evaluations' table and plots.
    pub fn eval_csv_path(&self) -> PathBuf {
        self.root.join("eval.csv")
    }

    pub fn eval_png_path(&self) -> PathBuf {
        self.root.join("eval.png")
    }

    pub fn departure_png_path(&self) -> PathBuf {
        self.root.join("departure.png")
    }

    /// Whether a run was saved here (its `state.json` exists).
    pub fn has_state(&self) -> bool {
        self.state_path().is_file()
    }

    pub fn read_state(&self) -> Result<RunState, RunDirError> {
        let path = self.state_path();
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(cause) => return Err(RunDirError::Unreadable { path, cause }),
        };
        serde_json::from_str(&text).map_err(|cause| RunDirError::NotAState { path, cause })
    }

    pub fn write_state(&self, state: &RunState) -> Result<(), RunDirError> {
        let text = serde_json::to_string_pretty(state).expect("a run state serialises");
        write_file_atomically(&self.state_path(), text.as_bytes())?;
        Ok(())
    }

    /// Removes what killed writes left behind (dot temporaries) in the run
    /// folder and in its checkpoints; returns what it removed.
    pub fn clean_stale_temporaries(&self) -> Result<Vec<PathBuf>, FsError> {
        let mut removed = clean_stale_temporaries(&self.root)?;
        removed.extend(clean_stale_temporaries(&self.checkpoints_dir())?);
        Ok(removed)
    }

    pub fn checkpoints_dir(&self) -> PathBuf {
        self.root.join("checkpoints")
    }

    /// The folder of the checkpoint called `name`.
    pub fn checkpoint(&self, name: &str) -> PathBuf {
        self.checkpoints_dir().join(name)
    }

    /// The checkpoint folders' names, oldest first, of `side` alone when
    /// given; writes in progress (dot folders) left out. Complete or not:
    /// a caller that resumes checks each. A missing `checkpoints/` holds
    /// none.
    pub fn checkpoint_names(&self, side: Option<Side>) -> Result<Vec<String>, RunDirError> {
        names_in(&self.checkpoints_dir(), side)
    }

    /// The newest complete checkpoint (with its `meta.json`) of `side`.
    pub fn latest_checkpoint(&self, side: Side) -> Option<PathBuf> {
        latest_in(&self.checkpoints_dir(), side)
    }

    /// Where the run stands for `side`'s learner, written under the config
    /// of hash `config_hash`, known elsewhere (a league's store) to have
    /// played `played` env steps. A missing `state.json` (lost, or a first
    /// save killed between its checkpoint and its state) is rebuilt from
    /// the newest of the side's checkpoints that verifies file by file,
    /// carries `config_hash` and is not behind `played`; never from one
    /// that does not.
    pub fn recover(
        &self,
        side: Side,
        config_hash: &str,
        played: u64,
    ) -> Result<Recovery, RunDirError> {
        use crate::nn::checkpoint::{read_meta, verify_file};
        if self.has_state() {
            let state = self.read_state()?;
            return Ok(Recovery::Kept {
                env_steps: state.env_steps,
            });
        }
        let names = self.checkpoint_names(Some(side)).unwrap_or_default();
        let mut rejected = Vec::new();
        for name in names.iter().rev() {
            let ckpt = self.checkpoint(name);
            let usable = (|| -> Result<crate::nn::checkpoint::CheckpointMeta, String> {
                let meta = read_meta(&ckpt).map_err(|e| format!("{e:#}"))?;
                for file in meta.files.keys() {
                    verify_file(&ckpt, &meta, file).map_err(|e| format!("{e:#}"))?;
                }
                if meta.config_hash != config_hash {
                    return Err(format!(
                        "written under another config (hash {})",
                        meta.config_hash
                    ));
                }
                if meta.env_steps < played {
                    return Err(format!(
                        "at {} env steps, behind the store's {played}",
                        meta.env_steps
                    ));
                }
                Ok(meta)
            })();
            match usable {
                Ok(meta) => {
                    self.write_state(&RunState {
                        iteration: meta.iteration,
                        env_steps: meta.env_steps,
                        wall_s: 0.0,
                        config_hash: meta.config_hash.clone(),
                        checkpoints: vec![(side, name.clone())],
                    })?;
                    return Ok(Recovery::Rebuilt {
                        checkpoint: ckpt,
                        env_steps: meta.env_steps,
                    });
                }
                Err(why) => rejected.push(format!("{name}: {why}")),
            }
        }
        Ok(if rejected.is_empty() {
            Recovery::Empty
        } else {
            Recovery::Unusable(rejected)
        })
    }

    /// Removes all but the newest `keep` checkpoints, never one that
    /// `state.json` names (the run resumes from it) and never a write in
    /// progress.
    pub fn prune_checkpoints(&self, keep: usize) -> Result<(), RunDirError> {
        let named: Vec<String> = self
            .read_state()
            .map(|s| s.checkpoints.into_iter().map(|(_, name)| name).collect())
            .unwrap_or_default();
        let names = self.checkpoint_names(None)?;
        let old = names.len().saturating_sub(keep);
        for name in &names[..old] {
            if named.contains(name) {
                continue;
            }
            let path = self.checkpoint(name);
            std::fs::remove_dir_all(&path)
                .map_err(|cause| RunDirError::Unremovable { path, cause })?;
        }
        Ok(())
    }

    /// The checkpoint of `side` that `state.json` names, if there is a
    /// `state.json` naming one; an error if that checkpoint is gone (never
    /// an older one in its place: that would play the wrong weights).
    pub fn named_checkpoint(&self, side: Side) -> Result<Option<PathBuf>, RunDirError> {
        if !self.has_state() {
            return Ok(None);
        }
        let state = self.read_state()?;
        let Some(name) = state.checkpoint_of(side) else {
            return Ok(None);
        };
        let dir = self.checkpoint(name);
        if !dir.join("meta.json").is_file() {
            return Err(RunDirError::NamedCheckpointGone {
                state: self.state_path(),
                side: side.name(),
                checkpoint: dir,
            });
        }
        Ok(Some(dir))
    }
}

/// Checkpoint folder names in `dir` (see `RunDir::checkpoint_names`).
fn names_in(dir: &Path, side: Option<Side>) -> Result<Vec<String>, RunDirError> {
    let prefix = side.map(|s| format!("{}-", s.name()));
    let mut names: Vec<String> = match std::fs::read_dir(dir) {
        Ok(it) => it
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.'))
            .filter(|n| prefix.as_ref().is_none_or(|p| n.starts_with(p)))
            .collect(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(cause) => {
            return Err(RunDirError::Unlistable {
                dir: dir.to_path_buf(),
                cause,
            })
        }
    };
    names.sort();
    Ok(names)
}

/// The newest complete checkpoint of `side` in a `checkpoints` folder.
fn latest_in(dir: &Path, side: Side) -> Option<PathBuf> {
    names_in(dir, Some(side))
        .ok()?
        .into_iter()
        .rev()
        .map(|n| dir.join(n))
        .find(|p| p.join("meta.json").is_file())
}

/// The newest complete checkpoint of `side` in a run folder, or in a
/// `checkpoints` folder given directly.
pub fn latest_checkpoint(run_or_checkpoints: &Path, side: Side) -> Option<PathBuf> {
    let run = RunDir::new(run_or_checkpoints);
    if run.checkpoints_dir().is_dir() {
        run.latest_checkpoint(side)
    } else {
        latest_in(run_or_checkpoints, side)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without state.json a run is empty, or its checkpoints are refused
    /// one by one with the reason; with it, it is kept as read, and no
    /// checkpoint is pruned that it names.
    #[test]
    fn recovery_and_pruning_follow_the_state_and_never_guess() {
        let tmp = tempfile::tempdir().unwrap();
        let run = RunDir::new(tmp.path().join("run"));
        assert_eq!(
            run.recover(Side::Target, "abc", 0).unwrap(),
            Recovery::Empty
        );
        let broken = run.checkpoint("target-000000009600");
        std::fs::create_dir_all(&broken).unwrap();
        std::fs::write(broken.join("meta.json"), "{").unwrap();
        match run.recover(Side::Target, "abc", 0).unwrap() {
            Recovery::Unusable(why) => {
                assert_eq!(why.len(), 1);
                assert!(why[0].starts_with("target-000000009600: "), "{why:?}");
            }
            other => panic!("a broken checkpoint recovered as {other:?}"),
        }
        // The captors' checkpoints are not the target's to stand in.
        assert!(matches!(
            run.recover(Side::Captors, "abc", 0).unwrap(),
            Recovery::Empty
        ));
        for steps in [3200, 6400, 12800] {
            std::fs::create_dir_all(run.checkpoint(&format!("target-{steps:012}"))).unwrap();
        }
        run.write_state(&state(vec![(Side::Target, "target-000000003200".into())]))
            .unwrap();
        assert_eq!(
            run.recover(Side::Target, "abc", 0).unwrap(),
            Recovery::Kept { env_steps: 9600 }
        );
        run.prune_checkpoints(1).unwrap();
        assert_eq!(
            run.checkpoint_names(None).unwrap(),
            ["target-000000003200", "target-000000012800"],
            "the named checkpoint and the newest stay"
        );
    }

    fn state(checkpoints: Vec<(Side, String)>) -> RunState {
        RunState {
            iteration: 3,
            env_steps: 9600,
            wall_s: 1.5,
            config_hash: "abc".into(),
            checkpoints,
        }
    }

    #[test]
    fn checkpoints_are_listed_oldest_first_without_writes_in_progress() {
        let run = tempfile::tempdir().unwrap();
        let run = RunDir::new(run.path());
        assert!(run.checkpoint_names(None).unwrap().is_empty());
        for name in [
            "target-000000006400",
            "captors-000000012800",
            "captors-000000003200",
            ".captors-000000016000.tmp-1",
        ] {
            std::fs::create_dir_all(run.checkpoint(name)).unwrap();
        }
        assert_eq!(
            run.checkpoint_names(Some(Side::Captors)).unwrap(),
            ["captors-000000003200", "captors-000000012800"]
        );
        assert_eq!(run.checkpoint_names(None).unwrap().len(), 3);
        // Only complete ones (with meta.json) are the latest.
        assert_eq!(run.latest_checkpoint(Side::Captors), None);
        std::fs::write(
            run.checkpoint("captors-000000003200").join("meta.json"),
            "{}",
        )
        .unwrap();
        assert_eq!(
            run.latest_checkpoint(Side::Captors),
            Some(run.checkpoint("captors-000000003200"))
        );
        assert_eq!(
            latest_checkpoint(&run.checkpoints_dir(), Side::Captors),
            Some(run.checkpoint("captors-000000003200"))
        );
        assert_eq!(latest_checkpoint(run.root(), Side::Target), None);
    }

    #[test]
    fn the_state_names_its_checkpoint_and_a_missing_one_is_an_error_not_an_older_one() {
        let dir = tempfile::tempdir().unwrap();
        let run = RunDir::new(dir.path());
        assert!(!run.has_state());
        assert_eq!(run.named_checkpoint(Side::Captors).unwrap(), None);
        let name = "captors-000000009600".to_string();
        run.write_state(&state(vec![(Side::Captors, name.clone())]))
            .unwrap();
        let read = run.read_state().unwrap();
        assert_eq!((read.iteration, read.env_steps), (3, 9600));
        assert_eq!(read.checkpoint_of(Side::Captors), Some(name.as_str()));
        assert_eq!(run.named_checkpoint(Side::Target).unwrap(), None);
        std::fs::create_dir_all(run.checkpoint("captors-000000003200")).unwrap();
        std::fs::write(
            run.checkpoint("captors-000000003200").join("meta.json"),
            "{}",
        )
        .unwrap();
        let err = run.named_checkpoint(Side::Captors).unwrap_err().to_string();
        assert!(err.contains("refusing to fall back"), "{err}");
        std::fs::create_dir_all(run.checkpoint(&name)).unwrap();
        std::fs::write(run.checkpoint(&name).join("meta.json"), "{}").unwrap();
        assert_eq!(
            run.named_checkpoint(Side::Captors).unwrap(),
            Some(run.checkpoint(&name))
        );
    }
}
