//! A run's learners to and from disk: a checkpoint of every side and
//! `state.json`; and through one side's handle (`Trainer::side`), that side
//! as a folder, as a new labelled folder, or put back to a checkpoint.

use super::super::persist::{self, RunDir, RunState};
use super::trainer::{LearnerSide, Trainer};
use crate::error::{LearnError, Result};
use crate::nn::checkpoint::{checkpoint_name, code_version, CheckpointMeta, FORMAT};
use std::path::{Path, PathBuf};
use t2e_core::env::Side;

impl Trainer {
    /// The sidecar of `side`'s checkpoint as of now.
    fn meta(&self, ls: &LearnerSide) -> CheckpointMeta {
        CheckpointMeta {
            format: FORMAT,
            side: ls.side,
            algorithm: ls.learner.algorithm(),
            net: ls.learner.net().clone(),
            num_captors: self.cfg.env.num_captors,
            critic_agents: ls.learner.critic_agents(),
            speed_ratio: self.cfg.env.speed_ratio(),
            env_steps: self.env_steps,
            iteration: self.iteration,
            config_hash: self.config_hash.clone(),
            protocol: self.cfg.protocol,
            code_version: code_version(),
            learner_state: None,
            files: Default::default(),
            pool_label: None,
            wall_ray_range_m: None,
        }
    }

    /// Writes a checkpoint of every learning side, then `state.json`.
    pub fn save(&self, run_dir: &Path) -> Result<Vec<PathBuf>> {
        let run = RunDir::new(run_dir);
        let mut written = Vec::new();
        let mut names = Vec::new();
        for ls in &self.learners {
            let name = checkpoint_name(ls.side, self.env_steps);
            let dir = run.checkpoint(&name);
            persist::save_learner(&dir, ls.learner.as_ref(), self.meta(ls))?;
            written.push(dir);
            names.push((ls.side, name));
        }
        run.write_state(&RunState {
            iteration: self.iteration,
            env_steps: self.env_steps,
            wall_s: self.wall_s,
            config_hash: self.config_hash.clone(),
            checkpoints: names,
        })?;
        Ok(written)
    }

    /// One learning side of this run, to save or reset on its own (a
    /// league's snapshots and exploiter resets).
    pub fn side(&mut self, side: Side) -> Result<SideHandle<'_>> {
        let index = self
            .learners
            .iter()
            .position(|l| l.side == side)
            .ok_or(LearnError::NoLearner(side))?;
        Ok(SideHandle {
            trainer: self,
            index,
        })
    }
}

/// One learning side of a `Trainer` (`Trainer::side`).
pub struct SideHandle<'a> {
    trainer: &'a mut Trainer,
    index: usize,
}

impl SideHandle<'_> {
    fn learner(&self) -> &LearnerSide {
        &self.trainer.learners[self.index]
    }

    /// Writes the side's learner as the checkpoint folder `dir`, atomically.
    pub fn save(&self, dir: &Path) -> Result<()> {
        let ls = self.learner();
        persist::save_learner(dir, ls.learner.as_ref(), self.trainer.meta(ls))?;
        Ok(())
    }

    /// Writes the side's learner as a new checkpoint folder `dir`, which
    /// must not exist (what is recorded never changes), its sidecar
    /// carrying `label`: the caller's own record of what the folder is (a
    /// league's pool membership), stored as given and never read here.
    pub fn save_new(&self, dir: &Path, label: serde_json::Value) -> Result<()> {
        let ls = self.learner();
        let mut meta = self.trainer.meta(ls);
        meta.pool_label = Some(label);
        persist::save_new_learner(dir, ls.learner.as_ref(), meta)?;
        Ok(())
    }

    /// Puts the side's learner back to the checkpoint folder `dir`
    /// (weights, Adam moments, return statistics) and clears its recurrent
    /// states; the run's step and iteration counts go on.
    pub fn reset_to(&mut self, dir: &Path) -> Result<()> {
        let ls = &mut self.trainer.learners[self.index];
        persist::load_learner(dir, ls.learner.as_mut())?;
        ls.actor_h = ls.actor_h.zeros_like();
        ls.critic_h = ls.critic_h.zeros_like();
        Ok(())
    }
}
