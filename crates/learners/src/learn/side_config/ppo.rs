//! PPO's settings table (`[captors.ppo]`, `[target.ppo]`), shared by MAPPO
//! and IPPO, with the paper's defaults and the checks that name each field.

use super::bad_updates::check_max_bad_updates;
use serde::{Deserialize, Serialize};
use t2e_core::error::{in_interval, in_range, ConfigError};

/// Every PPO hyperparameter, with the paper's settings (spec §9) as defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PpoConfig {
    /// Adam learning rate of actor and critic (paper: 3e-5 to 5e-4).
    pub lr: f64,
    /// Adam epsilon.
    pub adam_eps: f64,
    /// Passes over each rollout (paper: 4 to 15).
    pub epochs: usize,
    /// Minibatches per pass; each holds whole recurrent chunks.
    pub minibatches: usize,
    /// Length of the recurrent chunks the GRU is trained on (paper: 10).
    pub chunk_len: usize,
    /// PPO ratio clip (paper: 0.2).
    pub clip: f64,
    /// Entropy bonus (paper: 0.01).
    pub entropy_coef: f64,
    /// Weight of the value loss.
    pub value_coef: f64,
    /// Discount (paper: 0.99).
    pub gamma: f64,
    /// GAE lambda (paper: 0.95).
    pub gae_lambda: f64,
    /// Huber value loss threshold, on normalised returns (paper: 10).
    pub huber_delta: f64,
    /// Learn values in normalised units with running return statistics (paper: on).
    pub value_norm: bool,
    /// Clip each network's gradient to this global norm (paper: 10).
    pub max_grad_norm: f64,
    /// Normalise advantages over each rollout.
    pub normalize_advantages: bool,
    /// An update whose loss or gradient norm is not finite is undone (last
    /// good weights, moments and return statistics restored); training stops
    /// with an error after this many in a row.
    pub max_bad_updates: u32,
    /// Anneal the learning rate linearly over the run: the update after
    /// `d` of the run's `total_env_steps` uses lr x (1 - d / total), so the
    /// first uses `lr` and the last lr / iterations (CleanRL's `anneal_lr`,
    /// the MAPPO code's `use_linear_lr_decay`; the paper does not say; off
    /// by default, as in both). The schedule reads the run's current total:
    /// extending a run with `--total-env-steps` stretches what is left of it
    /// (the rate steps up at the resume). Under `train --for D` it ends at
    /// D of training instead, when that comes first (`Trainer::progress`).
    /// Left out of the stored config, and so of the config hash, while off.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub lr_anneal: bool,
    /// A target's penalty for leaving the rule-based target: this weight
    /// times KL(rule-based || policy) = -log pi(the rule-based action),
    /// averaged over the minibatch (AlphaStar keeps its agents near the
    /// supervised policy with such a KL). `heuristic_prior` moves where
    /// the policy starts; this keeps pulling it back while it learns, so
    /// it leaves the rule-based action only where the advantage outweighs
    /// the penalty. The target only; 0: off (the paper's). Left out of the
    /// stored config while 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub heuristic_kl: f64,
    /// Anneal `heuristic_kl` linearly to 0 over this share of the run (as
    /// `lr_anneal`, by env steps or the `--for` clock): behaviour cloning of
    /// the rule-based target on the learner's own states first, free RL
    /// after. 0: the weight stays (the default). Left out while 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub heuristic_kl_anneal: f64,
    /// The target `heuristic_kl` pulls towards in place of the rule-based
    /// one: a scripted target controller (`robust:H:MODELS`,
    /// `lookahead:H`, `tuned:...`), whose move is computed in every state
    /// of the learner's own play. The KL then distils it on the states the
    /// learner reaches (DAgger's states, the teacher's labels), imitation
    /// first and RL after when `heuristic_kl_anneal` is set. The network's
    /// `heuristic_prior` stays the rule-based target's: it is part of the
    /// network, and a checkpoint plays the same wherever it is loaded,
    /// with no teacher beside it. Needs `heuristic_kl` > 0. Left out of the
    /// stored config while unset.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teacher: Option<String>,
    /// The KL's weight, times this, in the states where the teacher's move
    /// is not the rule-based target's (its departures). A robust teacher
    /// departs in a few percent of states, and there a logit prior of 10
    /// holds the policy to the rule: with the same weight everywhere the
    /// departures are a few percent of the KL and are never learned. 1:
    /// every state alike (the default). Needs `teacher`. Left out while 1.
    #[serde(skip_serializing_if = "is_one")]
    pub teacher_departure_weight: f64,
    /// DAgger in place of PPO (`learn/dagger.rs`): the target keeps the
    /// teacher-labelled states of its last this many rollouts and fits its
    /// actor to the teacher's moves on them by cross-entropy (departures
    /// weighted by `teacher_departure_weight`), `epochs x minibatches`
    /// gradient steps per rollout drawn from all of them. No reward enters
    /// the update and `heuristic_kl` is not read. The aggregate is not
    /// saved: a resumed run starts a new one. Needs `teacher`. 0: off (PPO,
    /// the default); left out of the stored config while 0.
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub dagger_rollouts: usize,
    /// The share of the run (by env steps or the `--for` clock, as
    /// `lr_anneal`) that DAgger takes; PPO after it, from the imitated
    /// actor, with `heuristic_kl` towards the teacher when that is set (its
    /// anneal counted from the run's start, not from the switch). The
    /// teacher's moves imitated first, reward learned from them after:
    /// Expert Iteration's order. 1: DAgger throughout (the default).
    /// Needs `dagger_rollouts`. Left out while 1.
    #[serde(skip_serializing_if = "is_one")]
    pub dagger_share: f64,
}

fn is_zero_usize(x: &usize) -> bool {
    *x == 0
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

impl Default for PpoConfig {
    fn default() -> Self {
        PpoConfig {
            lr: 5e-4,
            adam_eps: 1e-5,
            epochs: 5,
            minibatches: 1,
            chunk_len: 10,
            clip: 0.2,
            entropy_coef: 0.01,
            value_coef: 1.0,
            gamma: 0.99,
            gae_lambda: 0.95,
            huber_delta: 10.0,
            value_norm: true,
            max_grad_norm: 10.0,
            normalize_advantages: true,
            max_bad_updates: 3,
            lr_anneal: false,
            heuristic_kl: 0.0,
            heuristic_kl_anneal: 0.0,
            teacher: None,
            teacher_departure_weight: 1.0,
            dagger_rollouts: 0,
            dagger_share: 1.0,
        }
    }
}

impl PpoConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_interval("gamma", self.gamma, 0.0, 1.0, true)?;
        in_interval("gae_lambda", self.gae_lambda, 0.0, 1.0, true)?;
        in_interval("clip", self.clip, 0.0, 1.0, false)?;
        in_interval("lr", self.lr, 0.0, 0.1, false)?;
        in_interval("adam_eps", self.adam_eps, 0.0, 1.0, false)?;
        in_interval("entropy_coef", self.entropy_coef, 0.0, 10.0, true)?;
        in_interval("value_coef", self.value_coef, 0.0, 100.0, true)?;
        in_interval("huber_delta", self.huber_delta, 0.0, 1e6, false)?;
        in_interval("max_grad_norm", self.max_grad_norm, 0.0, 1e6, false)?;
        in_interval("heuristic_kl", self.heuristic_kl, 0.0, 100.0, true)?;
        in_interval(
            "heuristic_kl_anneal",
            self.heuristic_kl_anneal,
            0.0,
            1.0,
            true,
        )?;
        if self.heuristic_kl_anneal > 0.0 && self.heuristic_kl == 0.0 {
            return Err(ConfigError::new(
                "heuristic_kl_anneal",
                self.heuristic_kl_anneal,
                "anneals heuristic_kl, which is 0 (off): set heuristic_kl too",
            ));
        }
        in_range(
            "dagger_rollouts",
            self.dagger_rollouts,
            0..=100_000,
            "must be in 0..=100000 (0: off)",
        )?;
        if self.dagger_rollouts > 0 && self.teacher.is_none() {
            return Err(ConfigError::new(
                "dagger_rollouts",
                self.dagger_rollouts,
                "keeps the states the teacher labelled, and no teacher is set: set teacher too",
            ));
        }
        in_interval("dagger_share", self.dagger_share, 0.0, 1.0, false)?;
        if self.dagger_share != 1.0 && self.dagger_rollouts == 0 {
            return Err(ConfigError::new(
                "dagger_share",
                self.dagger_share,
                "is the share of the run DAgger takes, and dagger_rollouts is 0 (off): set dagger_rollouts too",
            ));
        }
        if let Some(teacher) = &self.teacher {
            if self.heuristic_kl == 0.0 && self.dagger_rollouts == 0 {
                return Err(ConfigError::new(
                    "teacher",
                    format!("\"{teacher}\""),
                    "is what heuristic_kl pulls towards, and heuristic_kl is 0 (off): set heuristic_kl too (or dagger_rollouts)",
                ));
            }
        }
        in_interval(
            "teacher_departure_weight",
            self.teacher_departure_weight,
            1.0,
            1000.0,
            true,
        )?;
        if self.teacher_departure_weight != 1.0 && self.teacher.is_none() {
            return Err(ConfigError::new(
                "teacher_departure_weight",
                self.teacher_departure_weight,
                "weighs the states where the teacher departs from the rule, and no teacher is set: set teacher too",
            ));
        }
        for (name, v) in [
            ("epochs", self.epochs),
            ("minibatches", self.minibatches),
            ("chunk_len", self.chunk_len),
        ] {
            in_range(name, v, 1..=10_000, "must be in 1..=10000")?;
        }
        check_max_bad_updates(self.max_bad_updates)?;
        Ok(())
    }
}
