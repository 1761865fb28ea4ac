//! MAAC's settings table (`[captors.maac]`, `[target.maac]`), with
//! its defaults and the checks that name each field.

use super::bad_updates::check_max_bad_updates;
use super::replay::{check_replay, ReplayConfig, ReplaySettings};
use crate::nn::NetConfig;
use serde::{Deserialize, Serialize};
use t2e_core::error::{in_interval, ConfigError};

/// Every MAAC hyperparameter. The paper gives none beyond the shared ones
/// (gamma 0.99, chunks of 10, hidden 128); the rest are the original MAAC's
/// (Iqbal and Sha 2019: Adam at 1e-3 for actor and critic, tau 1e-3,
/// reward scale 100, i.e. entropy weight 0.01, 4 attention heads,
/// attention and logit penalties 1e-3, critic gradient clip 10 per robot,
/// actor clip 0.5, a buffer of 10^6 transitions).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaacConfig {
    pub actor_lr: f64,
    pub critic_lr: f64,
    pub adam_eps: f64,
    /// Discount (paper: 0.99).
    pub gamma: f64,
    /// Soft target update rate (original: 1e-3).
    pub tau: f64,
    /// Entropy weight alpha (original: 1 / reward scale 100).
    pub entropy_coef: f64,
    /// Attention heads; they split the hidden width (original: 4).
    pub attention_heads: i64,
    /// Penalty on the squared attention logits (original: 1e-3).
    pub attention_reg: f64,
    /// Penalty on the squared policy logits (original: 1e-3).
    pub logit_reg: f64,
    /// Steps per replayed sequence, the GRU's training window (paper: 10).
    pub chunk_len: usize,
    /// Sequences per gradient step.
    pub batch_size: usize,
    /// Replay capacity in world-steps.
    pub buffer_steps: usize,
    /// World-steps in the replay before the first update.
    pub learning_starts: usize,
    /// World-steps sampled for learning per world-step collected.
    /// Default 1 (each step replayed once on average), a CPU budget: the
    /// original replayed about 3.4 (4 x 1024 transitions every 100 steps
    /// of 12 worlds).
    pub replay_ratio: f64,
    /// Critic gradient clip per robot of the team (original: 10 x robots).
    pub critic_max_grad_norm: f64,
    /// Actor gradient clip (original: 0.5).
    pub actor_max_grad_norm: f64,
    /// Update phases undone in a row (non-finite loss) before training stops.
    pub max_bad_updates: u32,
}

impl Default for MaacConfig {
    fn default() -> Self {
        MaacConfig {
            actor_lr: 1e-3,
            critic_lr: 1e-3,
            adam_eps: 1e-5,
            gamma: 0.99,
            tau: 1e-3,
            entropy_coef: 0.01,
            attention_heads: 4,
            attention_reg: 1e-3,
            logit_reg: 1e-3,
            chunk_len: 10,
            batch_size: 32,
            buffer_steps: 200_000,
            learning_starts: 5_000,
            replay_ratio: 1.0,
            critic_max_grad_norm: 10.0,
            actor_max_grad_norm: 0.5,
            max_bad_updates: 3,
        }
    }
}

impl ReplayConfig for MaacConfig {
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
    fn check(&self, net: &NetConfig) -> Result<(), ConfigError> {
        self.validate(net)
    }
}

impl MaacConfig {
    pub fn validate(&self, net: &NetConfig) -> Result<(), ConfigError> {
        in_interval("actor_lr", self.actor_lr, 0.0, 0.1, false)?;
        in_interval("critic_lr", self.critic_lr, 0.0, 0.1, false)?;
        in_interval("adam_eps", self.adam_eps, 0.0, 1.0, false)?;
        in_interval("gamma", self.gamma, 0.0, 1.0, true)?;
        in_interval("tau", self.tau, 0.0, 1.0, false)?;
        in_interval("entropy_coef", self.entropy_coef, 0.0, 10.0, true)?;
        in_interval("attention_reg", self.attention_reg, 0.0, 10.0, true)?;
        in_interval("logit_reg", self.logit_reg, 0.0, 10.0, true)?;
        in_interval("replay_ratio", self.replay_ratio, 0.0, 1000.0, false)?;
        in_interval(
            "critic_max_grad_norm",
            self.critic_max_grad_norm,
            0.0,
            1e6,
            false,
        )?;
        in_interval(
            "actor_max_grad_norm",
            self.actor_max_grad_norm,
            0.0,
            1e6,
            false,
        )?;
        if self.attention_heads < 1 || net.hidden % self.attention_heads != 0 {
            return Err(ConfigError::new(
                "attention_heads",
                self.attention_heads,
                format!("must be at least 1 and divide net.hidden = {}", net.hidden),
            ));
        }
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
