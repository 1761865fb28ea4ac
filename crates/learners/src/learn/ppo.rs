//! Recurrent PPO, the part MAPPO and IPPO share: hyperparameters, GAE, value
//! normalisation, the clipped objective, the Huber value loss, and the
//! update that ties them together, top to bottom (the rollout buffer and
//! Adam, which every learner uses, are in `rollout.rs` and `adam.rs`).
//! MAPPO and IPPO differ only in what the critic reads (`mappo.rs`, `ippo.rs`).

use super::adam::{backward_clipped, Adam};
use super::dagger::{Aggregate, Imitator};
use super::learner::{
    file, optimizer_file, restore_optimizers, Learner, LearnerKind, NamedTensors,
};
use super::rollout::{BadUpdate, Rollout, UpdateStats};
pub use super::side_config::ppo::PpoConfig;
use super::side_config::SideConfig;
use super::teacher::TeacherAgreement;
use super::undo::UndoPoint;
use crate::error::LearnError;
use crate::nn::checkpoint::{load_into, named_cpu_tensors, CheckpointError};
use crate::nn::prior::add_prior;
use crate::nn::{Actor, Critic, NetConfig};
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::Path;
use t2e_core::algorithm::Algorithm;
use t2e_core::error::ConfigError;
use tch::{nn, Device, Kind, Tensor};

/// Generalised advantage estimation over a rollout of `steps` x `rows`
/// (time major). `dones[t]` marks an episode that ended with step t, so
/// nothing flows across it into the next episode. An episode that ended by
/// capture is worth nothing afterwards; one cut off by the step limit
/// (`truncated[t]` = 1, with `dones[t]` = 1) is not over for the robots, so
/// its last step bootstraps from the value of the state it reached,
/// `final_values[t]` (ignored elsewhere). `last_values` are the values of the
/// states after the rollout's last step. Returns (advantages, returns).
#[allow(clippy::too_many_arguments)]
pub fn gae(
    rewards: &[f32],
    values: &[f32],
    dones: &[f32],
    truncated: &[f32],
    final_values: &[f32],
    last_values: &[f32],
    rows: usize,
    gamma: f64,
    lambda: f64,
) -> (Vec<f32>, Vec<f32>) {
    let steps = rewards.len() / rows;
    let mut adv = vec![0f32; rewards.len()];
    let mut running = vec![0f64; rows];
    for t in (0..steps).rev() {
        for r in 0..rows {
            let i = t * rows + r;
            let next_value = if t + 1 < steps {
                values[i + rows]
            } else {
                last_values[r]
            } as f64;
            let live = 1.0 - dones[i] as f64;
            let after = next_value * live + final_values[i] as f64 * truncated[i] as f64;
            let delta = rewards[i] as f64 + gamma * after - values[i] as f64;
            running[r] = delta + gamma * lambda * live * running[r];
            adv[i] = running[r] as f32;
        }
    }
    let returns = adv.iter().zip(values).map(|(a, v)| a + v).collect();
    (adv, returns)
}

/// Running statistics of the returns; the critic predicts normalised values
/// (MAPPO's ValueNorm: exponential averages with a debiasing term).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ValueNorm {
    pub beta: f64,
    pub running_mean: f64,
    pub running_mean_sq: f64,
    pub debias: f64,
}

impl Default for ValueNorm {
    fn default() -> Self {
        ValueNorm {
            beta: 0.99999,
            running_mean: 0.0,
            running_mean_sq: 0.0,
            debias: 0.0,
        }
    }
}

impl ValueNorm {
    pub fn update(&mut self, x: &[f32]) {
        let n = x.len().max(1) as f64;
        let mean = x.iter().map(|&v| v as f64).sum::<f64>() / n;
        let mean_sq = x.iter().map(|&v| (v as f64).powi(2)).sum::<f64>() / n;
        let b = self.beta;
        self.running_mean = b * self.running_mean + (1.0 - b) * mean;
        self.running_mean_sq = b * self.running_mean_sq + (1.0 - b) * mean_sq;
        self.debias = b * self.debias + (1.0 - b);
    }

    /// (mean, variance) of the returns seen so far.
    pub fn stats(&self) -> (f64, f64) {
        let d = self.debias.max(1e-5);
        let mean = self.running_mean / d;
        let var = (self.running_mean_sq / d - mean * mean).max(1e-2);
        (mean, var)
    }

    pub fn normalize(&self, x: f32) -> f32 {
        let (m, v) = self.stats();
        ((x as f64 - m) / v.sqrt()) as f32
    }

    pub fn denormalize(&self, x: f32) -> f32 {
        let (m, v) = self.stats();
        (x as f64 * v.sqrt() + m) as f32
    }
}

/// PPO's clipped surrogate, to minimise: -mean(min(r A, clip(r) A)) with
/// r = exp(new - old). Also returns the share of clipped ratios.
pub fn clipped_surrogate(
    new_logp: &Tensor,
    old_logp: &Tensor,
    adv: &Tensor,
    clip: f64,
) -> (Tensor, f64) {
    let ratio = (new_logp - old_logp).exp();
    let unclipped = &ratio * adv;
    let clipped = ratio.clamp(1.0 - clip, 1.0 + clip) * adv;
    let loss = -unclipped.minimum(&clipped).mean(Kind::Float);
    let frac = (ratio - 1.0)
        .abs()
        .gt(clip)
        .to_kind(Kind::Float)
        .mean(Kind::Float)
        .double_value(&[]);
    (loss, frac)
}

/// Mean Huber loss: quadratic within `delta` of the target, linear beyond.
pub fn huber(pred: &Tensor, target: &Tensor, delta: f64) -> Tensor {
    let err = (target - pred).abs();
    let quad = err.clamp_max(delta);
    let lin = &err - &quad;
    (quad.square() * 0.5 + lin * delta).mean(Kind::Float)
}

/// How the critic's inputs are made from the actors' (the one thing MAPPO
/// and IPPO do differently).
pub trait CriticView {
    /// Observations each critic input holds, for a side of `team` robots.
    fn critic_agents(&self, team: usize) -> usize;
    /// From patches [rows, 1, 48, 48] and vectors [rows, V] of rows ordered
    /// (..., world, robot) with `team` robots per world, the critic inputs
    /// [rows, C, 48, 48] and [rows, C V].
    fn critic_inputs(&self, patches: &Tensor, vectors: &Tensor, team: usize) -> (Tensor, Tensor);
}

/// One side's learning state: networks, optimisers, return statistics.
pub struct PpoLearner {
    /// MAPPO or IPPO: which critic view.
    pub algorithm: Algorithm,
    pub cfg: PpoConfig,
    pub net: NetConfig,
    pub device: Device,
    pub actor_vs: nn::VarStore,
    pub actor: Actor,
    pub critic_vs: nn::VarStore,
    pub critic: Critic,
    pub actor_adam: Adam,
    pub critic_adam: Adam,
    pub value_norm: ValueNorm,
    /// Robots per world on this side.
    pub team: usize,
    pub view: Box<dyn CriticView>,
    /// The KL weight of the coming update: `cfg.heuristic_kl`, annealed by
    /// `set_progress` when `cfg.heuristic_kl_anneal` says so.
    pub kl_weight: f64,
    /// The labelled states a DAgger target is fitted on
    /// (`cfg.dagger_rollouts`; empty otherwise).
    pub aggregate: Aggregate,
    /// Whether the coming update is DAgger's: `cfg.dagger_rollouts` is set
    /// and the run is within `cfg.dagger_share` (`set_progress`).
    pub imitating: bool,
}

/// MAPPO's and IPPO's kind: PPO over the `ppo` settings, with the critic
/// view that tells them apart.
pub struct PpoKind {
    pub algorithm: Algorithm,
    pub view: fn() -> Box<dyn CriticView>,
}

impl LearnerKind for PpoKind {
    fn settings_table(&self) -> &'static str {
        "ppo"
    }
    fn chunk_len(&self, side: &SideConfig) -> usize {
        side.ppo.chunk_len
    }
    fn gamma(&self, side: &SideConfig) -> f64 {
        side.ppo.gamma
    }
    fn validate(&self, side: &SideConfig) -> Result<(), ConfigError> {
        side.ppo.validate()
    }
    /// Each epoch a forward and a backward (about three forwards) of actor
    /// and critic over every row.
    fn update_flops(&self, side: &SideConfig, actor: f64, critic: f64) -> f64 {
        3.0 * side.ppo.epochs as f64 * (actor + critic)
    }
    fn build(
        &self,
        side: &SideConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> Box<dyn Learner> {
        let (cfg, net) = (side.ppo.clone(), side.net.clone());
        Box::new(PpoLearner::new(self, cfg, net, vector_len, team, device))
    }
}

impl PpoLearner {
    pub fn new(
        kind: &PpoKind,
        cfg: PpoConfig,
        net: NetConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> PpoLearner {
        let (algorithm, view) = (kind.algorithm, (kind.view)());
        let actor_vs = nn::VarStore::new(device);
        let actor = Actor::new(&actor_vs.root(), &net, vector_len);
        let critic_vs = nn::VarStore::new(device);
        let critic = Critic::new(
            &critic_vs.root(),
            &net,
            vector_len,
            view.critic_agents(team),
        );
        let actor_adam = Adam::new(&actor_vs, cfg.lr, cfg.adam_eps);
        let critic_adam = Adam::new(&critic_vs, cfg.lr, cfg.adam_eps);
        PpoLearner {
            algorithm,
            net,
            device,
            actor_vs,
            actor,
            critic_vs,
            critic,
            actor_adam,
            critic_adam,
            value_norm: ValueNorm::default(),
            team,
            view,
            kl_weight: cfg.heuristic_kl,
            aggregate: Aggregate::new(cfg.dagger_rollouts.max(1)),
            imitating: cfg.dagger_rollouts > 0,
            cfg,
        }
    }

    /// Copies of everything an update changes, to undo a bad one.
    fn snapshot(&self) -> LearnerSnapshot {
        LearnerSnapshot {
            point: UndoPoint::take(
                &[&self.actor_vs, &self.critic_vs],
                &[&self.actor_adam, &self.critic_adam],
            ),
            value_norm: self.value_norm.clone(),
        }
    }

    fn restore(&mut self, snap: LearnerSnapshot) {
        snap.point.restore(
            &[&self.actor_vs, &self.critic_vs],
            &mut [&mut self.actor_adam, &mut self.critic_adam],
        );
        self.value_norm = snap.value_norm;
    }

    /// The critic's values of a whole rollout, after it: what stepping the
    /// critic beside the actor gave, step for step, with its encoder run
    /// once over all steps instead of once per step (see
    /// `Learner::value_rollout`). GAE needs the value of every step, of the
    /// state each truncated episode reached (continuing that row's
    /// recurrent state) and of the states after the last step.
    pub fn value_rollout(&self, ro: &mut Rollout, h0: &Tensor) -> Tensor {
        let dev = self.device;
        let (steps, rows, l, hd) = (ro.steps, ro.rows, ro.chunk_len, ro.hidden);
        let (pl, vl) = (ro.patch_side * ro.patch_side, ro.vector_len);
        let n = steps * rows;
        tch::no_grad(|| {
            let (p, v) = crate::nn::obs_tensors(&ro.patches, &ro.vectors, n, 1, ro.patch_side, dev);
            let (cp, cv) = self.view.critic_inputs(&p, &v, self.team);
            let x = self
                .critic
                .encode(&cp, &cv)
                .view([steps as i64, rows as i64, -1]);
            let masks =
                Tensor::from_slice(&ro.masks)
                    .to_device(dev)
                    .view([steps as i64, rows as i64, 1]);
            let mut h = h0.shallow_clone();
            let mut states = Vec::with_capacity(steps);
            let hsz = rows * hd;
            for t in 0..steps {
                if t % l == 0 {
                    let c = t / l;
                    h.to_device(Device::Cpu)
                        .copy_data(&mut ro.critic_h[c * hsz..(c + 1) * hsz], hsz);
                }
                h = self
                    .critic
                    .gru_step(&x.get(t as i64), &(&h * masks.get(t as i64)));
                states.push(h.shallow_clone());
            }
            let states = Tensor::stack(&states, 0).view([n as i64, hd as i64]);
            self.critic
                .values(&states)
                .to_device(Device::Cpu)
                .copy_data(&mut ro.values, n);

            // Truncated rows come in whole teams (a world ends for all its
            // robots), in row order, as the critic's team view needs.
            let cut: Vec<usize> = (0..n).filter(|&i| ro.truncated[i] > 0.5).collect();
            if !cut.is_empty() {
                let m = cut.len();
                let mut fp = vec![0u8; m * pl];
                let mut fv = vec![0f32; m * vl];
                for (k, &i) in cut.iter().enumerate() {
                    fp[k * pl..(k + 1) * pl]
                        .copy_from_slice(&ro.final_patches[i * pl..(i + 1) * pl]);
                    fv[k * vl..(k + 1) * vl]
                        .copy_from_slice(&ro.final_vectors[i * vl..(i + 1) * vl]);
                }
                let (p, v) = crate::nn::obs_tensors(&fp, &fv, m, 1, ro.patch_side, dev);
                let (cp, cv) = self.view.critic_inputs(&p, &v, self.team);
                let at: Vec<i64> = cut.iter().map(|&i| i as i64).collect();
                let hs = states.index_select(0, &Tensor::from_slice(&at).to_device(dev));
                let (values, _) = self.critic.step(&cp, &cv, &hs);
                let mut out = vec![0f32; m];
                values.to_device(Device::Cpu).copy_data(&mut out, m);
                for (&i, value) in cut.iter().zip(out) {
                    ro.final_values[i] = value;
                }
            }

            let (p, v) = crate::nn::obs_tensors(
                &ro.last_patches,
                &ro.last_vectors,
                rows,
                1,
                ro.patch_side,
                dev,
            );
            let (cp, cv) = self.view.critic_inputs(&p, &v, self.team);
            let last_masks = Tensor::from_slice(&ro.last_masks)
                .to_device(dev)
                .unsqueeze(1);
            let (values, _) = self.critic.step(&cp, &cv, &(&h * last_masks));
            values
                .to_device(Device::Cpu)
                .copy_data(&mut ro.last_values, rows);
            h
        })
    }

    /// The PPO update on one rollout. A non-finite loss or gradient norm
    /// undoes the whole update (weights, moments and return statistics as
    /// they were before it) and says what went wrong.
    pub fn update(&mut self, ro: &Rollout, rng: &mut ChaCha8Rng) -> Result<UpdateStats, BadUpdate> {
        let before = self.snapshot();
        match self.update_unguarded(ro, rng) {
            Ok(stats) => Ok(stats),
            Err(bad) => {
                self.restore(before);
                Err(bad)
            }
        }
    }

    // Long on purpose: the learners read like CleanRL, one algorithm top to
    // bottom (advantages, epochs, minibatches, losses, step); split, the
    // update would be read across helpers that each hold half a loss.
    fn update_unguarded(
        &mut self,
        ro: &Rollout,
        rng: &mut ChaCha8Rng,
    ) -> Result<UpdateStats, BadUpdate> {
        if self.imitating {
            return Imitator {
                actor: &self.actor,
                adam: &mut self.actor_adam,
                aggregate: &mut self.aggregate,
                cfg: &self.cfg,
                prior: self.net.heuristic_prior,
                device: self.device,
            }
            .imitate(ro, rng);
        }
        let cfg = self.cfg.clone();
        let dev = self.device;
        let (steps, rows, l, hdim) = (ro.steps, ro.rows, ro.chunk_len, ro.hidden as i64);
        let n = steps * rows;

        // 1. Advantages and returns in real units, then the value targets.
        let denorm = |v: &[f32]| -> Vec<f32> {
            if cfg.value_norm {
                v.iter().map(|&x| self.value_norm.denormalize(x)).collect()
            } else {
                v.to_vec()
            }
        };
        let values = denorm(&ro.values);
        let last_values = denorm(&ro.last_values);
        let final_values = denorm(&ro.final_values);
        let (mut adv, returns) = gae(
            &ro.rewards,
            &values,
            &ro.dones,
            &ro.truncated,
            &final_values,
            &last_values,
            rows,
            cfg.gamma,
            cfg.gae_lambda,
        );
        if cfg.value_norm {
            self.value_norm.update(&returns);
        }
        let targets: Vec<f32> = if cfg.value_norm {
            returns
                .iter()
                .map(|&r| self.value_norm.normalize(r))
                .collect()
        } else {
            returns
        };
        if cfg.normalize_advantages {
            let mean = adv.iter().map(|&a| a as f64).sum::<f64>() / n as f64;
            let var = adv.iter().map(|&a| (a as f64 - mean).powi(2)).sum::<f64>() / n as f64;
            let std = var.sqrt() + 1e-5;
            adv.iter_mut()
                .for_each(|a| *a = ((*a as f64 - mean) / std) as f32);
        }

        // 2. The rollout as tensors on the device; critic inputs built once.
        let (patches, vectors) =
            crate::nn::obs_tensors(&ro.patches, &ro.vectors, n, 1, ro.patch_side, dev);
        let (c_patches, c_vectors) = self.view.critic_inputs(&patches, &vectors, self.team);
        let t = |v: &[f32]| Tensor::from_slice(v).to_device(dev);
        let actions = Tensor::from_slice(&ro.actions).to_device(dev);
        // Only a target that leans on the rule-based one stored hints.
        let prior = self.net.heuristic_prior;
        let hints = self
            .wants_hints()
            .then(|| Tensor::from_slice(&ro.hints).to_device(dev));
        // The KL's anchor: the teacher's moves where one is set, else the
        // rule-based target's (the prior's hints).
        let teacher_hints = self
            .cfg
            .teacher
            .is_some()
            .then(|| Tensor::from_slice(&ro.teacher_hints).to_device(dev));
        let old_logp = t(&ro.logp);
        let adv = t(&adv);
        let targets = t(&targets);
        let masks = t(&ro.masks);
        let actor_h = t(&ro.actor_h).view([-1, hdim]);
        let critic_h = t(&ro.critic_h).view([-1, hdim]);

        // 3. Epochs over minibatches of whole chunks: sequence s = (chunk c, row r).
        let chunks = steps / l;
        let sequences = chunks * rows;
        let per_batch = sequences.div_ceil(cfg.minibatches);
        let mut order: Vec<usize> = (0..sequences).collect();
        let mut stats = UpdateStats::default();
        let mut agreement = teacher_hints.as_ref().map(|_| TeacherAgreement::default());
        for epoch in 0..cfg.epochs {
            order.shuffle(rng);
            for mb in order.chunks(per_batch) {
                // Time-major rows of the minibatch: [l, mb] flattened.
                let mut idx = Vec::with_capacity(l * mb.len());
                for step in 0..l {
                    for &s in mb {
                        let (c, r) = (s / rows, s % rows);
                        idx.push(((c * l + step) * rows + r) as i64);
                    }
                }
                let idx = Tensor::from_slice(&idx).to_device(dev);
                let seq = Tensor::from_slice(&mb.iter().map(|&s| s as i64).collect::<Vec<_>>())
                    .to_device(dev);
                let m = masks
                    .index_select(0, &idx)
                    .view([l as i64, mb.len() as i64]);

                let logits = self.actor.unroll(
                    &patches.index_select(0, &idx),
                    &vectors.index_select(0, &idx),
                    &actor_h.index_select(0, &seq),
                    &m,
                );
                let mb_hints = hints.as_ref().map(|h| h.index_select(0, &idx));
                let mb_anchor = teacher_hints.as_ref().map(|h| h.index_select(0, &idx));
                let logits = match &mb_hints {
                    Some(hints) => add_prior(logits, hints, prior),
                    None => logits,
                };
                let logp_all = logits.log_softmax(-1, Kind::Float);
                // The first pass sees every decision once, before this
                // update has changed the policy.
                if let (0, Some(agreement), Some(anchor), Some(rule)) =
                    (epoch, agreement.as_mut(), &mb_anchor, &mb_hints)
                {
                    let moves = |t: &Tensor| Vec::<i64>::try_from(t).expect("action indices");
                    agreement.add(TeacherAgreement::count(
                        &moves(&logp_all.argmax(-1, false)),
                        &moves(anchor),
                        &moves(rule),
                    ));
                }
                let a = actions.index_select(0, &idx);
                let new_logp = logp_all.gather(1, &a.unsqueeze(1), false).squeeze_dim(1);
                let entropy = -(logp_all.exp() * &logp_all)
                    .sum_dim_intlist(-1, false, Kind::Float)
                    .mean(Kind::Float);
                let old = old_logp.index_select(0, &idx);
                let (policy_loss, clip_frac) =
                    clipped_surrogate(&new_logp, &old, &adv.index_select(0, &idx), cfg.clip);

                let v = self.critic.unroll(
                    &c_patches.index_select(0, &idx),
                    &c_vectors.index_select(0, &idx),
                    &critic_h.index_select(0, &seq),
                    &m,
                );
                let value_loss = huber(&v, &targets.index_select(0, &idx), cfg.huber_delta);

                let mut loss =
                    &policy_loss - cfg.entropy_coef * &entropy + cfg.value_coef * &value_loss;
                if self.kl_weight > 0.0 {
                    let anchor = mb_anchor
                        .as_ref()
                        .or(mb_hints.as_ref())
                        .expect("wants_hints covers heuristic_kl");
                    let log_anchor = logp_all
                        .gather(1, &anchor.unsqueeze(1), false)
                        .squeeze_dim(1);
                    let kl = match (&mb_anchor, &mb_hints) {
                        (Some(teacher), Some(rule)) => {
                            let departs = teacher.ne_tensor(rule).to_kind(Kind::Float);
                            let weight = departs * (cfg.teacher_departure_weight - 1.0) + 1.0;
                            -(log_anchor * weight).mean(Kind::Float)
                        }
                        _ => -log_anchor.mean(Kind::Float),
                    };
                    loss += self.kl_weight * kl;
                }
                let loss_value = loss.double_value(&[]);
                if !loss_value.is_finite() {
                    return Err(BadUpdate(format!(
                        "loss = {loss_value} (policy {}, value {}, entropy {})",
                        policy_loss.double_value(&[]),
                        value_loss.double_value(&[]),
                        entropy.double_value(&[])
                    )));
                }
                let norms = backward_clipped(
                    &loss,
                    &mut [
                        (&mut self.actor_adam, cfg.max_grad_norm),
                        (&mut self.critic_adam, cfg.max_grad_norm),
                    ],
                );
                let (actor_norm, critic_norm) = (norms[0], norms[1]);
                if !(actor_norm.is_finite() && critic_norm.is_finite()) {
                    return Err(BadUpdate(format!(
                        "gradient norm not finite (actor {actor_norm}, critic {critic_norm})"
                    )));
                }
                stats.actor_grad_norm += actor_norm;
                stats.critic_grad_norm += critic_norm;
                self.actor_adam.step();
                self.critic_adam.step();

                stats.policy_loss += policy_loss.double_value(&[]);
                stats.value_loss += value_loss.double_value(&[]);
                stats.entropy += entropy.double_value(&[]);
                stats.approx_kl +=
                    tch::no_grad(|| (&old - &new_logp).mean(Kind::Float).double_value(&[]));
                stats.clip_frac += clip_frac;
                stats.gradient_steps += 1;
            }
        }
        stats.average();
        stats.teacher = agreement;
        Ok(stats)
    }
}

/// A PPO learner's state that is not a tensor, kept in `meta.json`.
#[derive(Serialize, Deserialize)]
struct PpoState {
    value_norm: ValueNorm,
    actor_adam_steps: u64,
    critic_adam_steps: u64,
}

/// The KL weight after `done` of the run: `heuristic_kl`, falling
/// linearly to 0 at `heuristic_kl_anneal` of the run when that is set.
pub fn kl_weight_at(cfg: &PpoConfig, done: f64) -> f64 {
    if cfg.heuristic_kl_anneal > 0.0 {
        cfg.heuristic_kl * (1.0 - done / cfg.heuristic_kl_anneal).max(0.0)
    } else {
        cfg.heuristic_kl
    }
}

impl Learner for PpoLearner {
    fn algorithm(&self) -> Algorithm {
        self.algorithm
    }
    fn net(&self) -> &NetConfig {
        &self.net
    }
    fn wants_hints(&self) -> bool {
        self.net.heuristic_prior > 0.0
            || self.cfg.heuristic_kl > 0.0
            || self.cfg.dagger_rollouts > 0
    }
    fn teacher(&self) -> Option<&str> {
        self.cfg.teacher.as_deref()
    }
    fn actor(&self) -> &Actor {
        &self.actor
    }
    fn team(&self) -> usize {
        self.team
    }
    fn critic_agents(&self) -> usize {
        self.view.critic_agents(self.team)
    }
    fn chunk_len(&self) -> usize {
        self.cfg.chunk_len
    }
    fn needs_values(&self) -> bool {
        true
    }
    fn critic_step(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h: &Tensor,
    ) -> (Option<Tensor>, Tensor) {
        let (cp, cv) = self.view.critic_inputs(patches, vectors, self.team);
        let (values, h) = self.critic.step(&cp, &cv, h);
        (Some(values), h)
    }
    fn values_after_rollout(&self) -> bool {
        true
    }
    fn value_rollout(&self, ro: &mut Rollout, h0: &Tensor) -> Tensor {
        self.value_rollout(ro, h0)
    }
    fn update(&mut self, ro: &Rollout, rng: &mut ChaCha8Rng) -> Result<UpdateStats, BadUpdate> {
        PpoLearner::update(self, ro, rng)
    }
    fn set_progress(&mut self, done: f64) {
        self.kl_weight = kl_weight_at(&self.cfg, done);
        self.imitating = self.cfg.dagger_rollouts > 0 && done < self.cfg.dagger_share;
        if self.cfg.lr_anneal {
            let lr = self.cfg.lr * (1.0 - done.clamp(0.0, 1.0));
            self.actor_adam.lr = lr;
            self.critic_adam.lr = lr;
        }
    }
    fn learning_rate(&self) -> Option<f64> {
        Some(self.actor_adam.lr)
    }
    fn max_bad_updates(&self) -> u32 {
        self.cfg.max_bad_updates
    }
    fn checkpoint_files(&self) -> Vec<(&'static str, NamedTensors)> {
        vec![
            ("actor.safetensors", named_cpu_tensors(&self.actor_vs)),
            ("critic.safetensors", named_cpu_tensors(&self.critic_vs)),
            (
                "optimizer.safetensors",
                optimizer_file(&self.actor_adam, &self.critic_adam),
            ),
        ]
    }
    fn learner_state(&self) -> serde_json::Value {
        serde_json::to_value(PpoState {
            value_norm: self.value_norm.clone(),
            actor_adam_steps: self.actor_adam.steps,
            critic_adam_steps: self.critic_adam.steps,
        })
        .expect("serialisable")
    }
    fn restore(
        &mut self,
        files: &[(&'static str, NamedTensors)],
        state: serde_json::Value,
        dir: &Path,
    ) -> Result<(), LearnError> {
        let st: PpoState = serde_json::from_value(state).map_err(|e| CheckpointError::Invalid {
            path: dir.to_path_buf(),
            what: format!("learner_state: {e}"),
        })?;
        load_into(
            &mut self.actor_vs,
            file(files, "actor.safetensors"),
            &dir.join("actor.safetensors"),
        )?;
        load_into(
            &mut self.critic_vs,
            file(files, "critic.safetensors"),
            &dir.join("critic.safetensors"),
        )?;
        restore_optimizers(
            files,
            (&mut self.actor_adam, st.actor_adam_steps),
            (&mut self.critic_adam, st.critic_adam_steps),
            dir,
        )?;
        self.value_norm = st.value_norm;
        // As the off-policy learners' replays: the labelled states are not
        // saved (hundreds of MB at every checkpoint); a resumed DAgger
        // target fits on what it plays from then on.
        self.aggregate.clear();
        Ok(())
    }
}

/// Everything an update changes, copied before it.
struct LearnerSnapshot {
    point: UndoPoint,
    value_norm: ValueNorm,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kl_weight_falls_linearly_to_zero_over_its_share_of_the_run() {
        let cfg = PpoConfig {
            heuristic_kl: 2.0,
            heuristic_kl_anneal: 0.4,
            ..PpoConfig::default()
        };
        // 2 x (1 - done / 0.4): 2 at the start, 1 at 0.2, 0 from 0.4 on.
        for (done, want) in [(0.0, 2.0), (0.1, 1.5), (0.2, 1.0), (0.4, 0.0), (0.9, 0.0)] {
            assert!((kl_weight_at(&cfg, done) - want).abs() < 1e-12, "{done}");
        }
        let constant = PpoConfig {
            heuristic_kl_anneal: 0.0,
            ..cfg.clone()
        };
        assert_eq!(kl_weight_at(&constant, 0.9), 2.0);
        let err = PpoConfig {
            heuristic_kl: 0.0,
            ..cfg
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(err.contains("heuristic_kl_anneal"), "{err}");
    }

    #[test]
    fn gae_matches_hand_computed_values() {
        // One row, three steps, episode ends after step 1; gamma 0.5, lambda 0.5.
        let rewards = [1.0, 2.0, 3.0];
        let values = [0.5, 1.0, 2.0];
        let dones = [0.0, 1.0, 0.0];
        let last = [4.0];
        let zeros = [0.0; 3];
        let (adv, ret) = gae(
            &rewards, &values, &dones, &zeros, &zeros, &last, 1, 0.5, 0.5,
        );
        // t=2: delta = 3 + 0.5*4 - 2 = 3; A = 3.
        // t=1: delta = 2 + 0 - 1 = 1 (done: no bootstrap); A = 1.
        // t=0: delta = 1 + 0.5*1 - 0.5 = 1; A = 1 + 0.25*1 = 1.25.
        assert_eq!(adv, vec![1.25, 1.0, 3.0]);
        assert_eq!(ret, vec![1.75, 2.0, 5.0]);
        // Two interleaved rows stay independent.
        let (adv2, _) = gae(
            &[1.0, 0.0, 2.0, 0.0, 3.0, 0.0],
            &[0.5, 0.0, 1.0, 0.0, 2.0, 0.0],
            &[0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            &[0.0; 6],
            &[0.0; 6],
            &[4.0, 0.0],
            2,
            0.5,
            0.5,
        );
        assert_eq!([adv2[0], adv2[2], adv2[4]], [1.25, 1.0, 3.0]);
        assert_eq!([adv2[1], adv2[3], adv2[5]], [0.0, 0.0, 0.0]);
    }

    #[test]
    fn truncation_bootstraps_from_the_state_reached_and_capture_does_not() {
        // The same three steps; the episode that ends after step 1 is now
        // cut off by the step limit, in a state whose value is 6.
        let rewards = [1.0, 2.0, 3.0];
        let values = [0.5, 1.0, 2.0];
        let dones = [0.0, 1.0, 0.0];
        let truncated = [0.0, 1.0, 0.0];
        // Stale numbers where `truncated` is 0 must not count.
        let final_values = [100.0, 6.0, 100.0];
        let (adv, ret) = gae(
            &rewards,
            &values,
            &dones,
            &truncated,
            &final_values,
            &[4.0],
            1,
            0.5,
            0.5,
        );
        // t=2: delta = 3 + 0.5*4 - 2 = 3; A = 3 (the next episode, as before).
        // t=1: delta = 2 + 0.5*6 - 1 = 4; A = 4 (bootstrapped, and the
        //      advantage of t=2 still does not flow back across the boundary).
        // t=0: delta = 1 + 0.5*1 - 0.5 = 1; A = 1 + 0.25*4 = 2.
        assert_eq!(adv, vec![2.0, 4.0, 3.0]);
        assert_eq!(ret, vec![2.5, 5.0, 5.0]);
        // Ended by capture instead: no bootstrap (A = 1 at t=1, as in the test above).
        let (adv, _) = gae(
            &rewards,
            &values,
            &dones,
            &[0.0; 3],
            &final_values,
            &[4.0],
            1,
            0.5,
            0.5,
        );
        assert_eq!(adv, vec![1.25, 1.0, 3.0]);
    }

    #[test]
    fn value_norm_tracks_mean_and_variance_and_round_trips() {
        let mut vn = ValueNorm::default();
        vn.update(&[1.0, 2.0, 3.0]);
        let (m, v) = vn.stats();
        // After one batch the debiased averages are the batch's: mean 2, var 2/3.
        assert!((m - 2.0).abs() < 1e-6, "{m}");
        assert!((v - 2.0 / 3.0).abs() < 1e-6, "{v}");
        assert!((vn.normalize(3.0) - (1.0 / (2.0f64 / 3.0).sqrt()) as f32).abs() < 1e-5);
        assert!((vn.denormalize(vn.normalize(7.5)) - 7.5).abs() < 1e-4);
        // A second batch weighs in almost equally while beta is near 1.
        vn.update(&[10.0, 10.0, 10.0]);
        let (m, _) = vn.stats();
        assert!((m - 6.0).abs() < 1e-3, "{m}");
        // Constant returns keep a variance floor instead of dividing by zero.
        let mut flat = ValueNorm::default();
        flat.update(&[5.0; 4]);
        assert!((flat.stats().1 - 1e-2).abs() < 1e-9);
    }

    #[test]
    fn clipped_surrogate_matches_hand_computed_values() {
        let old = Tensor::from_slice(&[0f32, 0.0, 0.0, 0.0]);
        // Ratios 1.5, 0.5, 1.1, 0.5 against advantages 1, 1, -1, -1.
        let new = Tensor::from_slice(&[1.5f32.ln(), 0.5f32.ln(), 1.1f32.ln(), 0.5f32.ln()]);
        let adv = Tensor::from_slice(&[1f32, 1.0, -1.0, -1.0]);
        let (loss, frac) = clipped_surrogate(&new, &old, &adv, 0.2);
        // min(r A, clip(r) A): 1.2, 0.5, -1.1, -0.8 -> mean -0.2 ... loss = -mean.
        let expected = -(1.2 + 0.5 - 1.1 - 0.8) / 4.0;
        assert!(
            (loss.double_value(&[]) - expected).abs() < 1e-6,
            "{}",
            loss.double_value(&[])
        );
        assert_eq!(frac, 0.75);
    }

    #[test]
    fn huber_is_quadratic_then_linear() {
        let pred = Tensor::from_slice(&[0f32, 0.0]);
        let target = Tensor::from_slice(&[1f32, 20.0]);
        // 0.5 * 1^2 = 0.5; 0.5 * 10^2 + 10 * (20 - 10) = 150.
        let l = huber(&pred, &target, 10.0).double_value(&[]);
        assert!((l - (0.5 + 150.0) / 2.0).abs() < 1e-5, "{l}");
    }

    #[test]
    fn adam_first_step_moves_each_weight_by_lr_against_its_gradient() {
        let vs = nn::VarStore::new(Device::Cpu);
        let w = vs.root().var("w", &[3], nn::Init::Const(1.0));
        let mut adam = Adam::new(&vs, 0.1, 1e-8);
        adam.zero_grad();
        (&w * Tensor::from_slice(&[2f32, -3.0, 0.5]))
            .sum(Kind::Float)
            .backward();
        let norm = adam.clip_grad_norm(1.0);
        assert!((norm - (4.0f64 + 9.0 + 0.25).sqrt()).abs() < 1e-5);
        adam.step();
        let mut out = [0f32; 3];
        w.copy_data(&mut out, 3);
        // Adam's first step is lr * sign(g) whatever the gradient's scale.
        for (o, e) in out.iter().zip([0.9, 1.1, 0.9]) {
            assert!((o - e).abs() < 1e-5, "{out:?}");
        }
    }

    #[test]
    fn values_after_the_rollout_equal_the_critic_stepped_while_acting() {
        use rand::{Rng, SeedableRng};
        let net = NetConfig {
            hidden: 16,
            conv_channels: [2, 4],
            patch_pool: 4,
            ..Default::default()
        };
        let (steps, worlds, team, vl) = (6usize, 2usize, 3usize, 20usize);
        let rows = worlds * team;
        let learner = crate::nn::seeded(5, || {
            PpoLearner::new(
                &super::super::mappo::KIND,
                PpoConfig {
                    chunk_len: 3,
                    ..PpoConfig::default()
                },
                net.clone(),
                vl,
                team,
                Device::Cpu,
            )
        });
        let mut ro = Rollout::new(steps, rows, vl, &net, 3);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        ro.patches.iter_mut().for_each(|x| *x = rng.gen_range(0..2));
        ro.final_patches
            .iter_mut()
            .for_each(|x| *x = rng.gen_range(0..2));
        ro.last_patches
            .iter_mut()
            .for_each(|x| *x = rng.gen_range(0..2));
        for v in [&mut ro.vectors, &mut ro.final_vectors, &mut ro.last_vectors] {
            v.iter_mut().for_each(|x| *x = rng.gen_range(-1.0..1.0));
        }
        // World 1 is cut off after step 2 and starts again at step 3; world 0
        // restarts at step 4 after a capture.
        for j in 0..team {
            ro.truncated[2 * rows + team + j] = 1.0;
            ro.masks[3 * rows + team + j] = 0.0;
            ro.masks[4 * rows + j] = 0.0;
        }
        ro.last_masks[0] = 0.0;
        let h0 = Tensor::randn([rows as i64, 16], (Kind::Float, Device::Cpu));

        // By stepping, as the trainer does while acting.
        let step_rows = |patches: &[u8], vectors: &[f32], h: &Tensor| {
            let (p, v) = crate::nn::obs_tensors(patches, vectors, rows, 1, 12, Device::Cpu);
            let (values, h) = tch::no_grad(|| learner.critic_step(&p, &v, h));
            let mut out = vec![0f32; rows];
            values.unwrap().copy_data(&mut out, rows);
            (out, h)
        };
        let (pl, n) = (144, steps * rows);
        let mut h = h0.shallow_clone();
        let mut values = vec![0f32; n];
        let mut chunk_h = Vec::new();
        let mut final_values = vec![0f32; n];
        for t in 0..steps {
            if t % 3 == 0 {
                chunk_h.push(h.shallow_clone());
            }
            let m = Tensor::from_slice(&ro.masks[t * rows..(t + 1) * rows]).unsqueeze(1);
            let (v, h2) = step_rows(
                &ro.patches[t * rows * pl..(t + 1) * rows * pl],
                &ro.vectors[t * rows * vl..(t + 1) * rows * vl],
                &(&h * m),
            );
            values[t * rows..(t + 1) * rows].copy_from_slice(&v);
            h = h2;
            if t == 2 {
                let (v, _) = step_rows(
                    &ro.final_patches[t * rows * pl..(t + 1) * rows * pl],
                    &ro.final_vectors[t * rows * vl..(t + 1) * rows * vl],
                    &h,
                );
                final_values[t * rows + team..(t + 1) * rows].copy_from_slice(&v[team..]);
            }
        }
        let m = Tensor::from_slice(&ro.last_masks).unsqueeze(1);
        let (last, _) = step_rows(&ro.last_patches, &ro.last_vectors, &(&h * m));

        let h_after = learner.value_rollout(&mut ro, &h0);
        let close = |a: &[f32], b: &[f32], what: &str| {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                assert!((x - y).abs() < 1e-4, "{what}[{i}]: {x} vs {y}");
            }
        };
        close(&ro.values, &values, "values");
        close(&ro.last_values, &last, "last_values");
        let cut: Vec<f32> = (0..n)
            .filter(|&i| ro.truncated[i] > 0.5)
            .map(|i| ro.final_values[i])
            .collect();
        let want: Vec<f32> = (0..n)
            .filter(|&i| ro.truncated[i] > 0.5)
            .map(|i| final_values[i])
            .collect();
        assert_eq!(cut.len(), team);
        close(&cut, &want, "final_values");
        let mut stored = vec![0f32; chunk_h.len() * rows * 16];
        let len = stored.len();
        Tensor::cat(&chunk_h, 0).copy_data(&mut stored, len);
        close(&ro.critic_h, &stored, "chunk starts");
        assert!(f64::try_from((&h_after - &h).abs().max()).unwrap() < 1e-4);
    }
}
