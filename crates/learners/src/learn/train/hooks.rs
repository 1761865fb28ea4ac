//! What a caller adds to the training loop's rollout (the league's
//! network opponents), and the empty hooks of a plain run.

use crate::error::Result;
use t2e_core::env::{Action, VecEnv};

/// What a caller adds to a rollout: actions for robots that neither a
/// learner of the trainer nor a controller inside the vector env plays (the
/// league's network opponents, batched per opponent), and a look at every
/// step (finished episodes, opponents for the worlds that restarted). An
/// error of the caller's own comes back as `LearnError::Hooks`.
pub trait RolloutHooks {
    /// Before each step: write the actions of the robots the hooks play.
    fn before_step(&mut self, venv: &mut VecEnv, actions: &mut [Action]) -> Result<()>;
    /// After each step (`venv.finished` lists the episodes that ended).
    fn after_step(&mut self, venv: &mut VecEnv) -> Result<()>;
}

/// No hooks: every robot is a learner's or a scripted controller's.
pub struct NoHooks;

impl RolloutHooks for NoHooks {
    fn before_step(&mut self, _venv: &mut VecEnv, _actions: &mut [Action]) -> Result<()> {
        Ok(())
    }
    fn after_step(&mut self, _venv: &mut VecEnv) -> Result<()> {
        Ok(())
    }
}
