//! Persistence of training: a learning side's checkpoint folder (weights,
//! Adam moments, return statistics; see `nn::checkpoint` for the layout and
//! its integrity checks). The run folder around the checkpoints, and its
//! `state.json`, belong to `nn::run_dir`. Kept apart from the training loop
//! so the league's learners write and read the same folders.

use super::learner::Learner;
use crate::error::LearnError;
use crate::nn::checkpoint::{
    read_checked, read_meta, write_checkpoint, write_new_checkpoint, CheckpointError,
    CheckpointMeta,
};
pub use crate::nn::run_dir::{Recovery, RunDir, RunState};
use std::path::Path;
use t2e_core::fs::Written;

/// Writes `learner` as the checkpoint folder `dir` with sidecar `meta`
/// (its `learner_state` filled in here).
pub fn save_learner(
    dir: &Path,
    learner: &dyn Learner,
    mut meta: CheckpointMeta,
) -> Result<Written, CheckpointError> {
    meta.learner_state = Some(learner.learner_state());
    write_checkpoint(dir, meta, &learner.checkpoint_files())
}

/// As `save_learner`, into a folder that must not exist yet.
pub fn save_new_learner(
    dir: &Path,
    learner: &dyn Learner,
    mut meta: CheckpointMeta,
) -> Result<Written, CheckpointError> {
    meta.learner_state = Some(learner.learner_state());
    write_new_checkpoint(dir, meta, &learner.checkpoint_files())
}

/// Loads the checkpoint folder `dir` into `learner`: every file the learner
/// keeps (weights, optimizer moments, target networks), each checked
/// against its recorded hash, and its state. A checkpoint of another
/// algorithm is refused before anything is loaded.
pub fn load_learner(dir: &Path, learner: &mut dyn Learner) -> Result<CheckpointMeta, LearnError> {
    // A run's own checkpoint, named by its state.json; one written before
    // checkpoints carried a manifest resumes, and the next one has it.
    if std::fs::symlink_metadata(dir.join("SHA256SUMS")).is_ok() {
        crate::nn::checkpoint::verify_manifest(dir)?;
    }
    let meta = read_meta(dir)?;
    let algorithm = learner.algorithm();
    if meta.algorithm != algorithm {
        return Err(CheckpointError::Invalid {
            path: dir.join("meta.json"),
            what: format!(
                "a {} checkpoint, but this learner is {algorithm}",
                meta.algorithm
            ),
        }
        .into());
    }
    let mut files = Vec::new();
    for (name, _) in learner.checkpoint_files() {
        files.push((name, read_checked(dir, &meta, name)?));
    }
    let state = meta
        .learner_state
        .clone()
        .ok_or_else(|| CheckpointError::Invalid {
            path: dir.to_path_buf(),
            what: "meta.json has no learner_state".into(),
        })?;
    learner.restore(&files, state, dir)?;
    Ok(meta)
}
