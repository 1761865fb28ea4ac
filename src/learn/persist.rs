//! Persistence of training: a learning side's checkpoint folder (weights,
//! Adam moments, return statistics; see `nn::checkpoint` for the layout and
//! its integrity checks) and a run's `state.json`. Kept apart from the
//! training loop so the league's learners write and read the same folders.

use super::ppo::{PpoLearner, ValueNorm};
use crate::env::Side;
use crate::nn::checkpoint::{
    load_into, named_cpu_tensors, read_checked, read_meta, write_checkpoint, write_file_atomically,
    CheckpointMeta, Written,
};
use anyhow::{anyhow, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

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
    pub fn read(run_dir: &Path) -> Result<RunState> {
        let path = run_dir.join("state.json");
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{}: cannot read (nothing to resume)", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{}: not a run state", path.display()))
    }

    pub fn write(&self, run_dir: &Path) -> Result<()> {
        write_file_atomically(
            &run_dir.join("state.json"),
            serde_json::to_string_pretty(self)?.as_bytes(),
        )
    }
}

/// A learner's state that is not a tensor, kept in `meta.json`.
#[derive(Serialize, Deserialize)]
struct LearnerState {
    value_norm: ValueNorm,
    actor_adam_steps: u64,
    critic_adam_steps: u64,
}

/// The `learner_state` of a sidecar for `learner` as it is now.
pub fn learner_state(learner: &PpoLearner) -> serde_json::Value {
    serde_json::to_value(LearnerState {
        value_norm: learner.value_norm.clone(),
        actor_adam_steps: learner.actor_adam.steps,
        critic_adam_steps: learner.critic_adam.steps,
    })
    .expect("serialisable")
}

/// Writes `learner` as the checkpoint folder `dir` with sidecar `meta`.
pub fn save_learner(dir: &Path, learner: &PpoLearner, meta: CheckpointMeta) -> Result<Written> {
    let mut optimizer = Vec::new();
    for (prefix, adam) in [
        ("actor.", &learner.actor_adam),
        ("critic.", &learner.critic_adam),
    ] {
        optimizer.extend(
            adam.state_tensors()
                .into_iter()
                .map(|(n, t)| (format!("{prefix}{n}"), t)),
        );
    }
    write_checkpoint(
        dir,
        meta,
        &[
            ("actor.safetensors", named_cpu_tensors(&learner.actor_vs)),
            ("critic.safetensors", named_cpu_tensors(&learner.critic_vs)),
            ("optimizer.safetensors", optimizer),
        ],
    )
}

/// Loads the checkpoint folder `dir` into `learner`: weights, Adam moments
/// and return statistics, every file checked against its recorded hash.
pub fn load_learner(dir: &Path, learner: &mut PpoLearner) -> Result<CheckpointMeta> {
    let meta = read_meta(dir)?;
    let actor = read_checked(dir, &meta, "actor.safetensors")?;
    let critic = read_checked(dir, &meta, "critic.safetensors")?;
    let optimizer = read_checked(dir, &meta, "optimizer.safetensors")?;
    load_into(
        &mut learner.actor_vs,
        &actor,
        &dir.join("actor.safetensors"),
    )?;
    load_into(
        &mut learner.critic_vs,
        &critic,
        &dir.join("critic.safetensors"),
    )?;
    let st: LearnerState = serde_json::from_value(
        meta.learner_state
            .clone()
            .with_context(|| format!("{}: meta.json has no learner_state", dir.display()))?,
    )
    .with_context(|| format!("{}: learner_state", dir.display()))?;
    let split = |prefix: &str| -> Vec<(String, tch::Tensor)> {
        optimizer
            .iter()
            .filter_map(|(n, t)| {
                n.strip_prefix(prefix)
                    .map(|n| (n.to_string(), t.shallow_clone()))
            })
            .collect()
    };
    learner
        .actor_adam
        .load_state(&split("actor."), st.actor_adam_steps)
        .map_err(|e| anyhow!("{}: {e}", dir.display()))?;
    learner
        .critic_adam
        .load_state(&split("critic."), st.critic_adam_steps)
        .map_err(|e| anyhow!("{}: {e}", dir.display()))?;
    learner.value_norm = st.value_norm;
    Ok(meta)
}
