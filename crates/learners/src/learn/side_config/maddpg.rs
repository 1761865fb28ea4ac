//! MADDPG's settings table (`[captors.maddpg]`, `[target.maddpg]`), with
//! its defaults and the checks that name each field.

use super::bad_updates::check_max_bad_updates;
use super::replay::{check_replay, ReplayConfig, ReplaySettings};
use crate::nn::NetConfig;
use serde::{Deserialize, Serialize};
use t2e_core::error::{in_interval, ConfigError};

/// Every MADDPG hyperparameter. The paper gives none for its off-policy
/// learners beyond the shared ones (gamma 0.99, chunks of 10, hidden 128);
/// the rest are the original MADDPG's (Lowe et al. 2017: Adam, tau 0.01,
/// logit penalty 1e-3, Gumbel temperature 1, a buffer of 10^6 transitions),
/// except the learning rate (the original's 1e-2 suits its two-layer MLPs,
/// not a CNN and GRU; here the upper end of the paper's PPO range) and the
/// gradient clip (the paper's 10, spec §9: the original's 0.5 held learning
/// on the chase task of tests/integration/learn.rs to half the return in the same
/// steps, 48 vs 106 after 200 iterations at lr 1e-3, at this game's
/// reward scale). A rate of 3e-3 learns that task faster but did not get
/// MADDPG to a capture on the 3:1, 1.0 grid cell in 150 k steps (docs/algorithms/maddpg.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaddpgConfig {
    /// Adam learning rate of the actor.
    pub actor_lr: f64,
    /// Adam learning rate of the critic.
    pub critic_lr: f64,
    pub adam_eps: f64,
    /// Discount (paper: 0.99).
    pub gamma: f64,
    /// Soft target update rate (original: 0.01).
    pub tau: f64,
    /// Steps per replayed sequence, the GRU's training window (paper: 10).
    pub chunk_len: usize,
    /// Sequences per gradient step (32 x 10 steps; the original's batch was
    /// 1024 transitions of one robot, this is 320 world-steps of a team).
    pub batch_size: usize,
    /// Replay capacity in world-steps (original: 10^6 transitions; 200,000
    /// world-steps of a 3-captor team is about 0.4 GB with the default net).
    pub buffer_steps: usize,
    /// World-steps in the replay before the first update.
    pub learning_starts: usize,
    /// World-steps sampled for learning per world-step collected.
    /// Default 1 (each step replayed once on average), a CPU budget: the
    /// original replayed about 10 (1024 transitions every 100). On the
    /// 3:1, 1.0 grid cell, 4 did not help within 117 k steps, and 10 got
    /// the captors moving but to 1 capture in 150 k steps (docs/algorithms/maddpg.md).
    pub replay_ratio: f64,
    /// Exploration while acting: this share of actions is uniform instead of
    /// the policy's, annealed linearly from `epsilon_start` to
    /// `epsilon_finish` over `epsilon_anneal_steps` world-steps. The
    /// original MADDPG explores through its sampled policy alone; with
    /// discrete actions the straight-through actor turns near-deterministic
    /// within a few hundred updates, so discrete-action MADDPGs (the
    /// off-policy MARL benchmark's, 1.0 to 0.05 over 50,000 steps) add this.
    pub epsilon_start: f64,
    pub epsilon_finish: f64,
    pub epsilon_anneal_steps: u64,
    /// Temperature of the Gumbel-softmax relaxation (original: 1).
    pub gumbel_temperature: f64,
    /// Penalty on the squared logits in the actor loss (original: 1e-3).
    pub logit_reg: f64,
    /// Gradient clip, global norm per network (paper: 10; original: 0.5).
    pub max_grad_norm: f64,
    /// Update phases undone in a row (non-finite loss) before training stops.
    pub max_bad_updates: u32,
}

impl Default for MaddpgConfig {
    fn default() -> Self {
        MaddpgConfig {
            actor_lr: 5e-4,
            critic_lr: 5e-4,
            adam_eps: 1e-5,
            gamma: 0.99,
            tau: 0.01,
            chunk_len: 10,
            batch_size: 32,
            buffer_steps: 200_000,
            learning_starts: 5_000,
            replay_ratio: 1.0,
            epsilon_start: 1.0,
            epsilon_finish: 0.05,
            epsilon_anneal_steps: 50_000,
            gumbel_temperature: 1.0,
            logit_reg: 1e-3,
            max_grad_norm: 10.0,
            max_bad_updates: 3,
        }
    }
}

impl ReplayConfig for MaddpgConfig {
    /// The settings its replay and optimisers are built with.
    fn replay_settings(&self) -> ReplaySettings {
        ReplaySettings {
            actor_lr: self.actor_lr,
            critic_lr: self.critic_lr,
            adam_eps: self.adam_eps,
            buffer_steps: self.buffer_steps,
            chunk_len: self.chunk_len,
            batch_size: self.batch_size,
            replay_ratio: self.replay_ratio,
            learning_starts: self.learning_starts,
            max_bad_updates: self.max_bad_updates,
        }
    }
    fn gamma(&self) -> f64 {
        self.gamma
    }
    fn check(&self, _net: &NetConfig) -> Result<(), ConfigError> {
        self.validate()
    }
}

impl MaddpgConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_interval("actor_lr", self.actor_lr, 0.0, 0.1, false)?;
        in_interval("critic_lr", self.critic_lr, 0.0, 0.1, false)?;
        in_interval("adam_eps", self.adam_eps, 0.0, 1.0, false)?;
        in_interval("gamma", self.gamma, 0.0, 1.0, true)?;
        in_interval("tau", self.tau, 0.0, 1.0, false)?;
        in_interval("replay_ratio", self.replay_ratio, 0.0, 1000.0, false)?;
        in_interval(
            "gumbel_temperature",
            self.gumbel_temperature,
            0.0,
            100.0,
            false,
        )?;
        in_interval("logit_reg", self.logit_reg, 0.0, 10.0, true)?;
        in_interval("max_grad_norm", self.max_grad_norm, 0.0, 1e6, false)?;
        check_replay(
            self.chunk_len,
            self.batch_size,
            self.buffer_steps,
            self.learning_starts,
        )?;
        check_max_bad_updates(self.max_bad_updates)?;
        Ok(())
    }
}
