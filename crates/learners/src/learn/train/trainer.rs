//! The `Trainer`'s state: its worlds, its learning sides and where the run
//! stands. Its work is in mod.rs (start, resume, iterate), collect.rs and
//! save.rs.

use super::super::learner::Learner;
use super::super::rollout::Rollout;
use super::super::run_config::TrainConfig;
use rand_chacha::ChaCha8Rng;
use t2e_core::env::{Action, Side, VecEnv};
use tch::{Device, Tensor};

/// One learning side during training.
pub(crate) struct LearnerSide {
    pub(super) side: Side,
    pub(super) learner: Box<dyn Learner>,
    pub(super) rollout: Rollout,
    pub(super) team: usize,
    pub(super) rows: usize,
    pub(super) actor_h: Tensor,
    pub(super) critic_h: Tensor,
    /// 0 for rows whose world just started an episode.
    pub(super) next_mask: Vec<f32>,
    /// Updates undone in a row because they were not finite.
    pub(super) bad_updates: u32,
    /// (phi's signed weight for this side, the side's gamma) when it shapes.
    pub(super) shaping: Option<(f32, f64)>,
    /// One per world where the KL pulls towards a teacher; empty elsewhere.
    pub(super) teachers: Vec<crate::learn::teacher::Teacher>,
    /// One per world where the prior leans on a planner
    /// (`NetConfig::prior_teacher`); empty where it is the rule-based target.
    pub(super) prior_teachers: Vec<crate::learn::teacher::Teacher>,
}

pub struct Trainer {
    pub cfg: TrainConfig,
    pub device: Device,
    pub(super) venv: VecEnv,
    pub(super) learners: Vec<LearnerSide>,
    pub(super) rng: ChaCha8Rng,
    pub(super) actions: Vec<Action>,
    pub iteration: u64,
    pub env_steps: u64,
    /// Training time of earlier segments of a resumed run.
    pub wall_s: f64,
    /// A wall-clock budget for this invocation (`train --for`): from
    /// `wall_s` = .0, .1 seconds of training. Schedules (`lr_anneal`) then
    /// end with whichever budget runs out first, steps or seconds.
    pub(super) clock_budget: Option<(f64, f64)>,
    pub(super) config_hash: String,
}
