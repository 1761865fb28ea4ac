//! MAAC, Multi-Actor-Attention-Critic (Iqbal and Sha 2019), recurrent, as
//! the paper benchmarks it: off-policy soft actor-critic with a centralised
//! critic that attends to teammates. Teammates share one actor and one
//! critic; the replay of 10-step sequences with stored recurrent states,
//! the TD target and the soft target updates are `offpolicy.rs`.
//!
//! The critic, for robot i of a team:
//! - s_i = the trunk (CNN + MLP + GRU, spec §9) over i's own observation;
//! - e_j = MLP(s_j, one-hot a_j) for every teammate j;
//! - per head: query W_q s_i, keys W_k e_j, values leaky_relu(W_v e_j) of the
//!   teammates j != i; weights softmax_j(q . k_j / sqrt(d)); x_i their
//!   weighted values, the heads concatenated;
//! - Q_i(o, a_-i, .) = MLP(s_i, x_i): one value per own action.
//!
//! One update phase, after each rollout:
//! 1. the rollout's chunks go into the replay;
//! 2. once it holds `learning_starts` steps, `replay_ratio` x (new steps) /
//!    (batch_size x chunk_len) gradient steps, each on `batch_size` sequences:
//!    - critic: y = r + gamma (Q'(o', a') - alpha log pi'(a'_i | o'_i)), a'
//!      sampled from the target policies, bootstrapped at truncations from
//!      the state reached, not at captures; loss (Q_i(o, a) - y)^2 plus a
//!      small penalty on the attention logits (the original's);
//!    - actor: actions sampled from the current policies; the advantage
//!      Q_i(a_i) - sum_a pi(a) Q_i(a) (a counterfactual baseline: the other
//!      robots' actions fixed); loss log pi(a_i) (alpha log pi(a_i) - A),
//!      the factor held constant, plus a penalty on the logits;
//!    - targets: theta' <- tau theta + (1 - tau) theta'.

use super::adam::minimize;
use super::offpolicy::{
    batch_td_targets, gumbel_noise, mean_entropy, one_hot, Batch, CriticTrunk, OffPolicy,
    ReplayCore, ReplayKind,
};
use super::rollout::{BadUpdate, UpdateStats};
pub use super::side_config::maac::MaacConfig;
use super::side_config::replay::ReplayConfig;
use crate::nn::{Actor, NetConfig, Trunk};
use rand_chacha::ChaCha8Rng;
use t2e_core::algorithm::Algorithm;
use t2e_core::env::Action;
use tch::{nn, Device, Kind, Tensor};

/// Scaled dot-product attention of every robot over its teammates.
/// `q`, `k`, `v`: [worlds, heads, team, d]. Returns the attended values
/// [worlds, heads, team, d], the weights [worlds, heads, team, team] (zero
/// on the diagonal: a robot attends only to the others) and the logits.
pub fn attend(q: &Tensor, k: &Tensor, v: &Tensor) -> (Tensor, Tensor, Tensor) {
    let (team, d) = (q.size()[2], q.size()[3]);
    let logits = q.matmul(&k.transpose(-1, -2)) / (d as f64).sqrt();
    let own = Tensor::eye(team, (Kind::Bool, q.device()));
    let weights = logits
        .masked_fill(&own, f64::NEG_INFINITY)
        .softmax(-1, Kind::Float);
    (weights.matmul(v), weights, logits)
}

/// The attention critic (see the module's notes).
pub struct AttentionCritic {
    trunk: Trunk,
    state_action: nn::Linear,
    query: nn::Linear,
    key: nn::Linear,
    value: nn::Linear,
    q_fc: nn::Linear,
    q_out: nn::Linear,
    heads: i64,
    team: i64,
}

impl CriticTrunk for AttentionCritic {
    /// Recurrent states of a chunk, each robot's own observation.
    fn unroll(&self, patches: &Tensor, vectors: &Tensor, h0: &Tensor, masks: &Tensor) -> Tensor {
        self.trunk.unroll(patches, vectors, h0, masks)
    }

    fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> Tensor {
        self.trunk.step(patches, vectors, h).1
    }
}

impl AttentionCritic {
    pub fn new(
        p: &nn::Path,
        net: &NetConfig,
        vector_len: usize,
        team: usize,
        heads: i64,
    ) -> AttentionCritic {
        let h = net.hidden;
        let no_bias = nn::LinearConfig {
            bias: false,
            ..Default::default()
        };
        AttentionCritic {
            trunk: Trunk::new(p, net, 1, vector_len as i64),
            state_action: nn::linear(
                p / "state_action",
                h + Action::COUNT as i64,
                h,
                Default::default(),
            ),
            query: nn::linear(p / "query", h, h, no_bias),
            key: nn::linear(p / "key", h, h, no_bias),
            value: nn::linear(p / "value", h, h, Default::default()),
            q_fc: nn::linear(p / "q_fc", 2 * h, h, Default::default()),
            q_out: nn::linear(p / "q_out", h, Action::COUNT as i64, Default::default()),
            heads,
            team: team as i64,
        }
    }

    /// From states [N, hidden] and one-hot actions [N, 5] of rows of whole
    /// teams: Q of every own action [N, 5], and the attention logits
    /// between teammates (for their penalty; empty for a team of one).
    pub fn q_all(&self, states: &Tensor, actions: &Tensor) -> (Tensor, Tensor) {
        let (n, h) = (states.size()[0], states.size()[1]);
        let (team, heads) = (self.team, self.heads);
        let attended;
        let logits;
        if team == 1 {
            attended = states.zeros_like();
            logits = Tensor::zeros([0], (Kind::Float, states.device()));
        } else {
            let e = Tensor::cat(&[states, actions], 1)
                .apply(&self.state_action)
                .leaky_relu();
            let split = |x: Tensor| {
                x.view([n / team, team, heads, h / heads])
                    .permute([0, 2, 1, 3])
            };
            let (x, _, l) = attend(
                &split(states.apply(&self.query)),
                &split(e.apply(&self.key)),
                &split(e.apply(&self.value).leaky_relu()),
            );
            attended = x.permute([0, 2, 1, 3]).reshape([n, h]);
            let off = Tensor::eye(team, (Kind::Bool, states.device())).logical_not();
            logits = l.masked_select(&off);
        }
        let q = Tensor::cat(&[states, &attended], 1)
            .apply(&self.q_fc)
            .leaky_relu()
            .apply(&self.q_out);
        (q, logits)
    }
}

/// MAAC's kind: its settings are the side's `maac` table.
pub const KIND: ReplayKind<MaacConfig> = ReplayKind {
    table: "maac",
    settings: |side| &side.maac,
    build: |cfg, net, vector_len, team, device| {
        Box::new(MaacLearner::new(cfg, net, vector_len, team, device))
    },
};

pub struct MaacLearner {
    pub cfg: MaacConfig,
    /// Shape, team, variables and optimisers, replay.
    pub core: ReplayCore,
    pub actor: Actor,
    pub critic: AttentionCritic,
    pub target_actor: Actor,
    pub target_critic: AttentionCritic,
}

/// (sampled actions [N], their log-probabilities [N]) of logits [N, 5]:
/// the Gumbel-max trick, argmax(log p + Gumbel noise), with the noise from
/// the trainer's generator.
fn sample_actions(logits: &Tensor, rng: &mut ChaCha8Rng) -> (Tensor, Tensor) {
    let logp = logits.log_softmax(-1, Kind::Float);
    let a = (&logp + gumbel_noise(&logp, rng)).argmax(1, true);
    (a.squeeze_dim(1), logp.gather(1, &a, false).squeeze_dim(1))
}

impl MaacLearner {
    pub fn new(
        cfg: MaacConfig,
        net: NetConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> MaacLearner {
        let heads = cfg.attention_heads;
        let critic_net = net.clone();
        let (core, (actor, critic, target_actor, target_critic)) = ReplayCore::new(
            cfg.replay_settings(),
            net,
            vector_len,
            team,
            1,
            device,
            |p| AttentionCritic::new(p, &critic_net, vector_len, team, heads),
        );
        MaacLearner {
            cfg,
            core,
            actor,
            critic,
            target_actor,
            target_critic,
        }
    }

    /// The soft TD targets of a batch, [len * rows]: the target critic's Q
    /// of an action the target actor samples, less alpha times its
    /// log-probability.
    fn targets(&self, b: &Batch, rng: &mut ChaCha8Rng) -> Tensor {
        let (actor, critic, alpha) = (
            &self.target_actor,
            &self.target_critic,
            self.cfg.entropy_coef,
        );
        batch_td_targets(b, actor, critic, self.cfg.gamma, |ha, hc| {
            let (a, logp) = sample_actions(&actor.logits(ha), rng);
            let (q, _) = critic.q_all(hc, &one_hot(&a, Action::COUNT as i64));
            q.gather(1, &a.unsqueeze(1), false).squeeze_dim(1) - logp * alpha
        })
    }
}

impl OffPolicy for MaacLearner {
    const ALGORITHM: Algorithm = Algorithm::Maac;
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
        let y = self.targets(b, rng);
        let (p, v, m) = b.now();

        let hc = self.critic.unroll(&p, &v, &b.critic_h0, &m);
        let (q_all, attention_logits) = self
            .critic
            .q_all(&hc, &one_hot(&b.actions, Action::COUNT as i64));
        let q = q_all
            .gather(1, &b.actions.unsqueeze(1), false)
            .squeeze_dim(1);
        let mut critic_loss = (&q - &y).square().mean(Kind::Float);
        if attention_logits.numel() > 0 {
            critic_loss += cfg.attention_reg * attention_logits.square().mean(Kind::Float);
        }

        let ha = self.actor.unroll_states(&p, &v, &b.actor_h0, &m);
        let logits = self.actor.logits(&ha);
        let logp_all = logits.log_softmax(-1, Kind::Float);
        let (a, _) = tch::no_grad(|| sample_actions(&logits, rng));
        let advantage = tch::no_grad(|| {
            let (q_pi, _) = self.critic.q_all(&hc, &one_hot(&a, Action::COUNT as i64));
            let baseline = (logp_all.exp() * &q_pi).sum_dim_intlist(-1, false, Kind::Float);
            q_pi.gather(1, &a.unsqueeze(1), false).squeeze_dim(1) - baseline
        });
        let logp = logp_all.gather(1, &a.unsqueeze(1), false).squeeze_dim(1);
        let factor = (cfg.entropy_coef * &logp - advantage).detach();
        let actor_loss =
            (&logp * factor).mean(Kind::Float) + cfg.logit_reg * logits.square().mean(Kind::Float);

        let (cl, al) = (critic_loss.double_value(&[]), actor_loss.double_value(&[]));
        if !(cl.is_finite() && al.is_finite()) {
            return Err(BadUpdate(format!("critic loss {cl}, actor loss {al}")));
        }
        // The actor's loss reads the critic only through the detached
        // advantage, so stepping the critic first changes nothing for it.
        let critic_max = cfg.critic_max_grad_norm * self.core.team as f64;
        let params = &mut self.core.params;
        let critic_norm = minimize(&critic_loss, &mut params.critic_adam, critic_max, "critic")?;
        let actor_max = cfg.actor_max_grad_norm;
        let actor_norm = minimize(&actor_loss, &mut params.actor_adam, actor_max, "actor")?;
        params.finish_step(cfg.tau);

        let entropy = mean_entropy(&logp_all);
        stats.add_step(al, cl, entropy, (actor_norm, critic_norm));
        Ok(())
    }
    fn critic_h(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> Tensor {
        self.critic.step(patches, vectors, h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(t: &Tensor) -> Vec<f32> {
        let n = t.numel();
        let mut v = vec![0f32; n];
        t.contiguous().copy_data(&mut v, n);
        v
    }

    #[test]
    fn attention_weights_on_a_tiny_team_match_hand_computation() {
        // One world, one head, three robots, d = 4 (scores divide by 2).
        let t = |v: &[f32]| Tensor::from_slice(v).view([1, 1, 3, 4]);
        let q = t(&[2., 0., 0., 0., 0., 0., 0., 0., 0., 0., 0., 4.]);
        let k = t(&[9., 9., 9., 9., 1., 0., 0., 0., 0., 1., 0., 1.]);
        let v = t(&[7., 7., 7., 7., 1., 0., 0., 0., 0., 0., 0., 1.]);
        let (x, w, _) = attend(&q, &k, &v);
        let w = values(&w);
        let e = std::f32::consts::E;
        // Robot 0: scores to robots 1 and 2 are 2/2 = 1 and 0 (its own, 9 x 2 / 2,
        // is masked): weights e/(e+1) and 1/(e+1).
        let expected0 = [0.0, e / (e + 1.0), 1.0 / (e + 1.0)];
        // Robot 1: a zero query weighs robots 0 and 2 equally.
        let expected1 = [0.5, 0.0, 0.5];
        // Robot 2: scores 4 x 9 / 2 = 18 to robot 0 and 4 x 0 / 2 = 0 to robot 1.
        let expected2 = [
            1.0 / (1.0 + (-18f32).exp()),
            (-18f32).exp() / (1.0 + (-18f32).exp()),
            0.0,
        ];
        for (got, want) in w
            .iter()
            .zip(expected0.iter().chain(&expected1).chain(&expected2))
        {
            assert!((got - want).abs() < 1e-6, "{w:?}");
        }
        // Robot 0 attends e/(e+1) to value (1,0,0,0) and 1/(e+1) to (0,0,0,1).
        let x = values(&x);
        let want = [e / (e + 1.0), 0.0, 0.0, 1.0 / (e + 1.0)];
        for (got, want) in x[..4].iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{x:?}");
        }
    }

    #[test]
    fn q_values_do_not_depend_on_the_robots_own_replayed_action() {
        // Q_i(o, a_-i, .) reads the others' actions only: changing robot 0's
        // action changes its teammates' Q, not its own.
        let _seed = crate::nn::seed_torch(0);
        let vs = nn::VarStore::new(Device::Cpu);
        let net = NetConfig {
            hidden: 16,
            ..NetConfig::default()
        };
        let critic = AttentionCritic::new(&vs.root(), &net, 10, 3, 2);
        let states = Tensor::randn([3, 16], (Kind::Float, Device::Cpu));
        let a1 = one_hot(&Tensor::from_slice(&[0i64, 1, 2]), 5);
        let a2 = one_hot(&Tensor::from_slice(&[4i64, 1, 2]), 5);
        let (q1, logits) = critic.q_all(&states, &a1);
        let (q2, _) = critic.q_all(&states, &a2);
        assert_eq!(logits.size(), vec![2 * 3 * 2]);
        let diff = (&q1 - &q2).abs().sum_dim_intlist(-1, false, Kind::Float);
        let d = values(&diff);
        assert!(d[0] < 1e-6, "{d:?}");
        assert!(d[1] > 1e-6 && d[2] > 1e-6, "{d:?}");
    }
}
