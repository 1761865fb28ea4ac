//! MADDPG (Lowe et al. 2017) for discrete actions, recurrent, as the paper
//! benchmarks it: off-policy; a deterministic-gradient actor made
//! differentiable through the Gumbel-softmax straight-through estimator; a
//! centralised Q critic that reads every teammate's observation and action
//! (the robot's own first); target networks with soft updates; a replay of
//! 10-step sequences with stored recurrent states (`offpolicy.rs`).
//! Teammates share one actor and one critic, as with MAPPO.
//!
//! One update phase, after each rollout:
//! 1. the rollout's chunks go into the replay;
//! 2. once it holds `learning_starts` steps, `replay_ratio` x (new steps) /
//!    (batch_size x chunk_len) gradient steps, each on `batch_size` sampled
//!    sequences:
//!    - critic: y = r + gamma Q'(o', a'), a' the target actor's greedy
//!      actions (one-hot), bootstrapped at truncations from the state
//!      reached, not at captures; loss (Q(o, a) - y)^2;
//!    - actor: a robot's action replaced by a Gumbel-softmax sample of its
//!      policy (teammates keep the replayed ones); loss -Q(o, a) plus a
//!      small penalty on the logits (the original's regulariser);
//!    - targets: theta' <- tau theta + (1 - tau) theta'.

use super::adam::minimize;
use super::mappo::{mates_index, Mappo};
use super::offpolicy::{
    batch_td_targets, gumbel_noise, gumbel_softmax_st, mean_entropy, one_hot, Batch, CriticTrunk,
    OffPolicy, ReplayCore, ReplayKind,
};
use super::ppo::CriticView;
use super::rollout::{BadUpdate, UpdateStats};
pub use super::side_config::maddpg::MaddpgConfig;
use super::side_config::replay::ReplayConfig;
use crate::nn::{Actor, NetConfig, Trunk};
use rand_chacha::ChaCha8Rng;
use t2e_core::algorithm::Algorithm;
use t2e_core::env::Action;
use tch::{nn, Device, Kind, Tensor};

/// The centralised Q function: the trunk over the team's observations (own
/// first, as MAPPO's critic reads them), then the team's one-hot actions
/// (own first) joined after the GRU, so the recurrent state depends on
/// observations only and the replay's stored state stays valid.
pub struct QCritic {
    trunk: Trunk,
    fc: nn::Linear,
    out: nn::Linear,
    team: usize,
}

impl CriticTrunk for QCritic {
    /// Recurrent states of a chunk over rows of whole teams.
    fn unroll(&self, patches: &Tensor, vectors: &Tensor, h0: &Tensor, masks: &Tensor) -> Tensor {
        let (cp, cv) = Mappo.critic_inputs(patches, vectors, self.team);
        self.trunk.unroll(&cp, &cv, h0, masks)
    }

    fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> Tensor {
        let (cp, cv) = Mappo.critic_inputs(patches, vectors, self.team);
        self.trunk.step(&cp, &cv, h).1
    }
}

impl QCritic {
    pub fn new(p: &nn::Path, net: &NetConfig, vector_len: usize, team: usize) -> QCritic {
        let h = net.hidden;
        let actions = (team * Action::COUNT) as i64;
        QCritic {
            trunk: Trunk::new(p, net, team as i64, (vector_len * team) as i64),
            fc: nn::linear(p / "q_fc", h + actions, h, Default::default()),
            out: nn::linear(p / "q_out", h, 1, Default::default()),
            team,
        }
    }

    /// Q [N] from states [N, hidden] and the team's actions [N, team * 5].
    pub fn q(&self, states: &Tensor, team_actions: &Tensor) -> Tensor {
        Tensor::cat(&[states, team_actions], 1)
            .apply(&self.fc)
            .relu()
            .apply(&self.out)
            .squeeze_dim(1)
    }
}

/// Each row's action first, then its teammates' (from `all`): [N, team * 5].
pub fn team_actions(own: &Tensor, all: &Tensor, team: usize) -> Tensor {
    if team == 1 {
        return own.shallow_clone();
    }
    let n = own.size()[0];
    let mates = all
        .index_select(0, &mates_index(n as usize, team, own.device()))
        .view([n, -1]);
    Tensor::cat(&[own, &mates], 1)
}

/// MADDPG's kind: its settings are the side's `maddpg` table.
pub const KIND: ReplayKind<MaddpgConfig> = ReplayKind {
    table: "maddpg",
    settings: |side| &side.maddpg,
    build: |cfg, net, vector_len, team, device| {
        Box::new(MaddpgLearner::new(cfg, net, vector_len, team, device))
    },
};

pub struct MaddpgLearner {
    pub cfg: MaddpgConfig,
    /// Shape, team, variables and optimisers, replay.
    pub core: ReplayCore,
    pub actor: Actor,
    pub critic: QCritic,
    pub target_actor: Actor,
    pub target_critic: QCritic,
}

impl MaddpgLearner {
    pub fn new(
        cfg: MaddpgConfig,
        net: NetConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> MaddpgLearner {
        let critic_net = net.clone();
        let (core, (actor, critic, target_actor, target_critic)) = ReplayCore::new(
            cfg.replay_settings(),
            net,
            vector_len,
            team,
            team,
            device,
            |p| QCritic::new(p, &critic_net, vector_len, team),
        );
        MaddpgLearner {
            cfg,
            core,
            actor,
            critic,
            target_actor,
            target_critic,
        }
    }

    /// The TD targets of a batch, [len * rows]: the target critic's Q of
    /// the target actor's greedy actions.
    fn targets(&self, b: &Batch) -> Tensor {
        let (actor, critic, team) = (&self.target_actor, &self.target_critic, self.core.team);
        batch_td_targets(b, actor, critic, self.cfg.gamma, |ha, hc| {
            let a = one_hot(&actor.logits(ha).argmax(-1, false), Action::COUNT as i64);
            critic.q(hc, &team_actions(&a, &a, team))
        })
    }
}

impl OffPolicy for MaddpgLearner {
    const ALGORITHM: Algorithm = Algorithm::Maddpg;
    fn core(&self) -> &ReplayCore {
        &self.core
    }
    fn core_mut(&mut self) -> &mut ReplayCore {
        &mut self.core
    }
    fn policy(&self) -> &Actor {
        &self.actor
    }
    /// One gradient step of critic, actor and targets on a batch.
    fn gradient_step(
        &mut self,
        b: &Batch,
        stats: &mut UpdateStats,
        rng: &mut ChaCha8Rng,
    ) -> Result<(), BadUpdate> {
        let cfg = self.cfg.clone();
        let y = self.targets(b);
        let (p, v, m) = b.now();
        let buffer_actions = one_hot(&b.actions, Action::COUNT as i64);

        // Critic first, stepped before the actor's loss is built: that loss
        // runs through the critic, and its gradient must not move it.
        let hc = self.critic.unroll(&p, &v, &b.critic_h0, &m);
        let q = self.critic.q(
            &hc,
            &team_actions(&buffer_actions, &buffer_actions, self.core.team),
        );
        let critic_loss = (&q - &y).square().mean(Kind::Float);
        let cl = critic_loss.double_value(&[]);
        if !cl.is_finite() {
            return Err(BadUpdate(format!("critic loss {cl}")));
        }
        let params = &mut self.core.params;
        let critic_norm = minimize(
            &critic_loss,
            &mut params.critic_adam,
            cfg.max_grad_norm,
            "critic",
        )?;

        let ha = self.actor.unroll_states(&p, &v, &b.actor_h0, &m);
        let logits = self.actor.logits(&ha);
        let sampled =
            gumbel_softmax_st(&logits, &gumbel_noise(&logits, rng), cfg.gumbel_temperature);
        let q_pi = self.critic.q(
            &hc.detach(),
            &team_actions(&sampled, &buffer_actions, self.core.team),
        );
        let actor_loss =
            -q_pi.mean(Kind::Float) + cfg.logit_reg * logits.square().mean(Kind::Float);
        let al = actor_loss.double_value(&[]);
        if !al.is_finite() {
            return Err(BadUpdate(format!("actor loss {al}")));
        }
        let params = &mut self.core.params;
        let actor_norm = minimize(
            &actor_loss,
            &mut params.actor_adam,
            cfg.max_grad_norm,
            "actor",
        )?;
        params.finish_step(cfg.tau);

        let entropy = mean_entropy(&logits.log_softmax(-1, Kind::Float));
        stats.add_step(al, cl, entropy, (actor_norm, critic_norm));
        Ok(())
    }
    fn critic_h(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> Tensor {
        self.critic.step(patches, vectors, h)
    }
    /// Epsilon-greedy, annealed over the world-steps collected.
    fn explore(&self) -> f64 {
        let c = &self.cfg;
        let done =
            (self.core.params.collected_steps as f64 / c.epsilon_anneal_steps as f64).min(1.0);
        c.epsilon_start + (c.epsilon_finish - c.epsilon_start) * done
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_row_reads_its_own_action_first_then_its_teammates() {
        let own = Tensor::from_slice(&[10f32, 11., 12., 13.]).view([4, 1]);
        let all = Tensor::from_slice(&[0f32, 1., 2., 3.]).view([4, 1]);
        let ta = team_actions(&own, &all, 2);
        let mut v = [0f32; 8];
        ta.copy_data(&mut v, 8);
        assert_eq!(v, [10., 1., 11., 0., 12., 3., 13., 2.]);
    }
}
