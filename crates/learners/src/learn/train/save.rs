//! A run's learners to and from disk: a checkpoint of every side and
//! `state.json`, one side as a folder, and a side put back to a checkpoint.

use super::super::persist::{self, RunDir, RunState};
use super::{LearnerSide, Trainer};
use crate::env::Side;
use crate::nn::checkpoint::{checkpoint_name, code_version, CheckpointMeta, FORMAT};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

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
            league: None,
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

    /// Writes `side`'s learner as the checkpoint folder `dir` (the league's
    /// snapshots), atomically.
    pub fn save_side(&self, side: Side, dir: &Path) -> Result<()> {
        let ls = self
            .learners
            .iter()
            .find(|l| l.side == side)
            .with_context(|| format!("no {} learner in this run", side.name()))?;
        persist::save_learner(dir, ls.learner.as_ref(), self.meta(ls))?;
        Ok(())
    }

    /// Writes `side`'s learner as a new league pool member at `dir`, which
    /// must not exist (a recorded member never changes), its sidecar naming
    /// the pool it belongs to.
    pub fn save_pool_member(
        &self,
        side: Side,
        dir: &Path,
        membership: crate::nn::checkpoint::PoolMembership,
    ) -> Result<()> {
        let ls = self
            .learners
            .iter()
            .find(|l| l.side == side)
            .with_context(|| format!("no {} learner in this run", side.name()))?;
        let mut meta = self.meta(ls);
        meta.league = Some(membership);
        persist::save_new_learner(dir, ls.learner.as_ref(), meta)?;
        Ok(())
    }

    /// Puts `side`'s learner back to the checkpoint folder `dir` (weights,
    /// Adam moments, return statistics) and clears its recurrent states; the
    /// run's step and iteration counts go on (a league exploiter's reset).
    pub fn reset_learner(&mut self, side: Side, dir: &Path) -> Result<()> {
        let ls = self
            .learners
            .iter_mut()
            .find(|l| l.side == side)
            .with_context(|| format!("no {} learner in this run", side.name()))?;
        persist::load_learner(dir, ls.learner.as_mut())?;
        ls.actor_h = ls.actor_h.zeros_like();
        ls.critic_h = ls.critic_h.zeros_like();
        Ok(())
    }
}
