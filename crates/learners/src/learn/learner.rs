//! What the training loop needs of a learning side, whatever its algorithm:
//! the actor it acts with, the critic pass it makes while acting (PPO keeps
//! the values for GAE; the off-policy learners only carry the critic's
//! recurrent state, which their replay stores), the update on a rollout, and
//! the tensors and state a checkpoint holds. The algorithms themselves read
//! top to bottom in their own files (`ppo.rs`, `maddpg.rs`, `maac.rs`).
//!
//! `LearnerKind` is what a training run asks of an algorithm beyond the
//! `Learner` it builds: the table of a side's config its settings live in,
//! their chunk length, discount and checks, the replay it would hold, the
//! cost of its update, and the learner itself.

use super::adam::Adam;
use super::rollout::{BadUpdate, Rollout, UpdateStats};
use super::side_config::SideConfig;
use crate::error::LearnError;
use crate::nn::checkpoint::CheckpointError;
use crate::nn::{Actor, NetConfig};
use rand_chacha::ChaCha8Rng;
use std::path::Path;
use t2e_core::algorithm::Algorithm;
use t2e_core::error::ConfigError;
use tch::{Device, Tensor};

pub trait LearnerKind: Sync {
    /// The table of a side's config its settings are read from (MAPPO and
    /// IPPO share `ppo`).
    fn settings_table(&self) -> &'static str;
    /// Whether it learns from a replay of past experience (and so cannot
    /// take a KL pull towards a prior, nor values states while acting).
    fn off_policy(&self) -> bool {
        false
    }
    /// Steps per recurrent chunk it trains on.
    fn chunk_len(&self, side: &SideConfig) -> usize;
    /// The discount it learns with.
    fn gamma(&self, side: &SideConfig) -> f64;
    /// Checks its settings; the error names the field within its table.
    fn validate(&self, side: &SideConfig) -> Result<(), ConfigError>;
    /// (world-steps, chunk length) of its replay, if it keeps one.
    fn replay(&self, _side: &SideConfig) -> Option<(usize, usize)> {
        None
    }
    /// FLOPs of its update per rollout row, from the FLOPs of one forward
    /// pass of actor and critic; NaN where they follow replay settings.
    fn update_flops(&self, _side: &SideConfig, _actor: f64, _critic: f64) -> f64 {
        f64::NAN
    }
    /// A fresh learner for a team of `team` robots.
    fn build(
        &self,
        side: &SideConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> Box<dyn Learner>;
}

/// Named tensors of one checkpoint file.
pub type NamedTensors = Vec<(String, Tensor)>;

pub trait Learner {
    fn algorithm(&self) -> Algorithm;
    fn net(&self) -> &NetConfig;
    /// Whether the rollout must hold the rule-based target's action for
    /// each row (`Rollout::hints`): a target with a heuristic prior or a
    /// KL towards the rule-based target.
    fn wants_hints(&self) -> bool {
        false
    }
    /// The teacher whose moves the rollout must hold for each row
    /// (`Rollout::teacher_hints`), where the KL pulls towards one.
    fn teacher(&self) -> Option<&str> {
        None
    }
    /// The policy every robot of the side acts with (and that eval, render
    /// and the league's pools load from `actor.safetensors`).
    fn actor(&self) -> &Actor;
    /// Robots per world on this side.
    fn team(&self) -> usize;
    /// Observations the critic's encoder reads per row (the sidecar records it).
    fn critic_agents(&self) -> usize;
    /// Recurrent chunk length of the rollout this learner trains on.
    fn chunk_len(&self) -> usize;
    /// Whether the rollout must hold critic values (`values`, `final_values`,
    /// `last_values`): PPO bootstraps GAE from them; off-policy learners
    /// compute their targets at update time.
    fn needs_values(&self) -> bool;
    /// The critic's acting-time pass over rows of whole teams (a world's
    /// robots adjacent), patches [rows, 1, S, S] and vectors [rows, V]: the
    /// values where `needs_values`, and the critic's next recurrent state.
    fn critic_step(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h: &Tensor,
    ) -> (Option<Tensor>, Tensor);
    /// Whether the critic values a rollout after it is collected
    /// (`value_rollout`) instead of stepping beside the actor while acting:
    /// the same values, with the encoder run once over every step.
    fn values_after_rollout(&self) -> bool {
        false
    }
    /// Fills the rollout's `values`, `critic_h` (chunk starts),
    /// `final_values` and `last_values` from its observations, masks and
    /// final and last observations, the critic starting from `h0`; returns
    /// the critic's state after the last step. Only where
    /// `values_after_rollout`.
    fn value_rollout(&self, _ro: &mut Rollout, _h0: &Tensor) -> Tensor {
        unreachable!("values_after_rollout is false")
    }
    /// Learns from one rollout. A non-finite loss or gradient undoes
    /// everything the update changed.
    fn update(&mut self, ro: &Rollout, rng: &mut ChaCha8Rng) -> Result<UpdateStats, BadUpdate>;
    /// Share of actions drawn uniformly instead of from the policy while
    /// training (MADDPG's epsilon-greedy exploration; 0 for the others).
    fn exploration(&self) -> f64 {
        0.0
    }
    /// Share of the run's env-step budget done before the coming update, in
    /// [0, 1]; learners with a learning-rate schedule follow it.
    fn set_progress(&mut self, _done: f64) {}
    /// The actor's learning rate, for the metrics (None: not reported).
    fn learning_rate(&self) -> Option<f64> {
        None
    }
    /// Updates undone in a row before training stops.
    fn max_bad_updates(&self) -> u32;
    /// The files of a checkpoint (`actor.safetensors` first) and their tensors on the CPU.
    fn checkpoint_files(&self) -> Vec<(&'static str, NamedTensors)>;
    /// What is not a tensor (optimizer step counts, return statistics), for `meta.json`.
    fn learner_state(&self) -> serde_json::Value;
    /// Puts the learner back to a checkpoint's files (as `checkpoint_files`
    /// names them, hashes already checked) and state; `dir` names errors.
    fn restore(
        &mut self,
        files: &[(&'static str, NamedTensors)],
        state: serde_json::Value,
        dir: &Path,
    ) -> Result<(), LearnError>;
}

/// The tensors of `name` among a checkpoint's files.
pub fn file<'a>(files: &'a [(&'static str, NamedTensors)], name: &str) -> &'a NamedTensors {
    &files
        .iter()
        .find(|(n, _)| *n == name)
        .expect("restore gets every file checkpoint_files names")
        .1
}

/// The tensors of `files` whose names start with `prefix`, prefix removed.
pub fn with_prefix(tensors: &NamedTensors, prefix: &str) -> NamedTensors {
    tensors
        .iter()
        .filter_map(|(n, t)| {
            n.strip_prefix(prefix)
                .map(|n| (n.to_string(), t.shallow_clone()))
        })
        .collect()
}

/// Both Adams' moments in one `optimizer.safetensors`, prefixed `actor.`
/// and `critic.`: the layout every learner's checkpoint uses.
pub fn optimizer_file(actor: &Adam, critic: &Adam) -> NamedTensors {
    let mut optimizer = Vec::new();
    for (prefix, adam) in [("actor.", actor), ("critic.", critic)] {
        optimizer.extend(
            adam.state_tensors()
                .into_iter()
                .map(|(n, t)| (format!("{prefix}{n}"), t)),
        );
    }
    optimizer
}

/// The inverse of `optimizer_file`, with each Adam's step count from the
/// learner's state.
pub fn restore_optimizers(
    files: &[(&'static str, NamedTensors)],
    (actor, actor_steps): (&mut Adam, u64),
    (critic, critic_steps): (&mut Adam, u64),
    dir: &Path,
) -> Result<(), CheckpointError> {
    let optimizer = file(files, "optimizer.safetensors");
    let invalid = |e: super::adam::OptimizerStateError| CheckpointError::Invalid {
        path: dir.to_path_buf(),
        what: e.to_string(),
    };
    actor
        .load_state(&with_prefix(optimizer, "actor."), actor_steps)
        .map_err(invalid)?;
    critic
        .load_state(&with_prefix(optimizer, "critic."), critic_steps)
        .map_err(invalid)?;
    Ok(())
}
