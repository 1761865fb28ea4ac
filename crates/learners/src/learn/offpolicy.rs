//! What MADDPG and MAAC share, as `ppo.rs` is to MAPPO and IPPO: the replay
//! buffer of recurrent sequences, the TD target with termination and
//! truncation, the Gumbel-softmax straight-through estimator, soft target
//! updates, and the parameters both keep (`Params`: online and target
//! networks, optimisers, undo, checkpoint files). The algorithms read top to
//! bottom in `maddpg.rs` and `maac.rs`.
//!
//! The replay holds 10-step sequences of whole teams (a centralised critic
//! reads every teammate's observation and action at once), each with the
//! observation after its last step, the recurrent states of actor and critic
//! at its first step as they were while acting (R2D2's "stored state"), and
//! the observation a truncated episode reached: the step limit is not the
//! end of the game, so the target bootstraps from that state, not from the
//! next episode's first one.

use super::adam::Adam;
use super::learner::{
    file, optimizer_file, restore_optimizers, Learner, LearnerKind, NamedTensors,
};
use super::rollout::{BadUpdate, Rollout, UpdateStats};
use super::side_config::replay::{ReplayConfig, ReplaySettings};
use super::side_config::SideConfig;
use super::undo::UndoPoint;
use crate::error::LearnError;
use crate::nn::checkpoint::{load_into, named_cpu_tensors, CheckpointError};
use crate::nn::{obs_tensors, Actor, NetConfig};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::Path;
use t2e_core::algorithm::Algorithm;
use t2e_core::error::ConfigError;
use tch::{nn, Device, Kind, Tensor};

/// Sequences of `len` steps of `team` robots, in a ring of `capacity`.
pub struct SequenceReplay {
    pub len: usize,
    pub team: usize,
    pub capacity: usize,
    /// Sequences held.
    pub filled: usize,
    next: usize,
    patch_len: usize,
    patch_side: usize,
    vector_len: usize,
    hidden: usize,
    /// [seq][step 0..=len][robot][...]
    patches: Vec<u8>,
    vectors: Vec<f32>,
    /// [seq][step 0..=len]: 0 where the step starts an episode.
    masks: Vec<f32>,
    /// [seq][step 0..len][robot]
    actions: Vec<i64>,
    rewards: Vec<f32>,
    /// [seq][step 0..len], the same for every robot of a world.
    dones: Vec<f32>,
    truncated: Vec<f32>,
    /// [seq][robot][...]: the state a truncation within the sequence reached.
    final_patches: Vec<u8>,
    final_vectors: Vec<f32>,
    /// [seq][robot][hidden]
    actor_h: Vec<f32>,
    critic_h: Vec<f32>,
}

/// Bytes one sequence takes in the replay.
pub fn sequence_bytes(
    len: usize,
    team: usize,
    patch_len: usize,
    vector_len: usize,
    hidden: usize,
) -> usize {
    let obs = patch_len + 4 * vector_len;
    (len + 1) * team * obs
        + 4 * (len + 1)
        + len * team * 12
        + 8 * len
        + team * obs
        + 8 * team * hidden
}

impl SequenceReplay {
    pub fn new(
        capacity: usize,
        len: usize,
        team: usize,
        patch_side: usize,
        vector_len: usize,
        hidden: usize,
    ) -> SequenceReplay {
        let pl = patch_side * patch_side;
        let steps = len + 1;
        SequenceReplay {
            len,
            team,
            capacity,
            filled: 0,
            next: 0,
            patch_len: pl,
            patch_side,
            vector_len,
            hidden,
            patches: vec![0; capacity * steps * team * pl],
            vectors: vec![0.0; capacity * steps * team * vector_len],
            masks: vec![0.0; capacity * steps],
            actions: vec![0; capacity * len * team],
            rewards: vec![0.0; capacity * len * team],
            dones: vec![0.0; capacity * len],
            truncated: vec![0.0; capacity * len],
            final_patches: vec![0; capacity * team * pl],
            final_vectors: vec![0.0; capacity * team * vector_len],
            actor_h: vec![0.0; capacity * team * hidden],
            critic_h: vec![0.0; capacity * team * hidden],
        }
    }

    /// Forgets every sequence (a restored learner refills it).
    pub fn clear(&mut self) {
        self.filled = 0;
        self.next = 0;
    }

    /// Adds every chunk of every world of a rollout (chunks of `len` steps).
    pub fn push_rollout(&mut self, ro: &Rollout) {
        let (l, team, pl, vl, hd) = (
            self.len,
            self.team,
            self.patch_len,
            self.vector_len,
            self.hidden,
        );
        assert_eq!(ro.chunk_len, l, "rollout chunks are replay sequences");
        let rows = ro.rows;
        let worlds = rows / team;
        for c in 0..ro.steps / l {
            for w in 0..worlds {
                let i = self.next;
                for s in 0..=l {
                    let t = c * l + s;
                    let in_rollout = t < ro.steps;
                    let mask_row = w * team;
                    self.masks[i * (l + 1) + s] = if in_rollout {
                        ro.masks[t * rows + mask_row]
                    } else {
                        ro.last_masks[mask_row]
                    };
                    for j in 0..team {
                        let r = w * team + j;
                        let dst = (i * (l + 1) + s) * team + j;
                        let (p_src, v_src) = if in_rollout {
                            (
                                &ro.patches[(t * rows + r) * pl..(t * rows + r + 1) * pl],
                                &ro.vectors[(t * rows + r) * vl..(t * rows + r + 1) * vl],
                            )
                        } else {
                            (
                                &ro.last_patches[r * pl..(r + 1) * pl],
                                &ro.last_vectors[r * vl..(r + 1) * vl],
                            )
                        };
                        self.patches[dst * pl..(dst + 1) * pl].copy_from_slice(p_src);
                        self.vectors[dst * vl..(dst + 1) * vl].copy_from_slice(v_src);
                        if s < l {
                            let d = (i * l + s) * team + j;
                            self.actions[d] = ro.actions[t * rows + r];
                            self.rewards[d] = ro.rewards[t * rows + r];
                        }
                    }
                    if s < l {
                        let src = t * rows + mask_row;
                        self.dones[i * l + s] = ro.dones[src];
                        self.truncated[i * l + s] = ro.truncated[src];
                        if ro.truncated[src] > 0.5 {
                            for j in 0..team {
                                let r = w * team + j;
                                let d = i * team + j;
                                let src = t * rows + r;
                                self.final_patches[d * pl..(d + 1) * pl]
                                    .copy_from_slice(&ro.final_patches[src * pl..(src + 1) * pl]);
                                self.final_vectors[d * vl..(d + 1) * vl]
                                    .copy_from_slice(&ro.final_vectors[src * vl..(src + 1) * vl]);
                            }
                        }
                    }
                }
                for j in 0..team {
                    let r = w * team + j;
                    let src = (c * rows + r) * hd;
                    let d = (i * team + j) * hd;
                    self.actor_h[d..d + hd].copy_from_slice(&ro.actor_h[src..src + hd]);
                    self.critic_h[d..d + hd].copy_from_slice(&ro.critic_h[src..src + hd]);
                }
                self.next = (self.next + 1) % self.capacity;
                self.filled = (self.filled + 1).min(self.capacity);
            }
        }
    }

    /// `batch` sequences drawn uniformly (with replacement), as tensors on
    /// `device`, rows time major: step s, sequence b, robot j is row
    /// s * (batch * team) + b * team + j, so each step's rows are whole teams.
    pub fn sample(&self, batch: usize, rng: &mut ChaCha8Rng, device: Device) -> Batch {
        let picks: Vec<usize> = (0..batch).map(|_| rng.gen_range(0..self.filled)).collect();
        self.batch_of(&picks, device)
    }

    /// The sequences `picks` as a batch (see `sample`).
    pub fn batch_of(&self, picks: &[usize], device: Device) -> Batch {
        let (l, team, pl, vl, hd) = (
            self.len,
            self.team,
            self.patch_len,
            self.vector_len,
            self.hidden,
        );
        let b = picks.len();
        let n = b * team;
        let mut patches = Vec::with_capacity((l + 1) * n * pl);
        let mut vectors = Vec::with_capacity((l + 1) * n * vl);
        let mut masks = Vec::with_capacity((l + 1) * n);
        for s in 0..=l {
            for &i in picks {
                let src = (i * (l + 1) + s) * team;
                patches.extend_from_slice(&self.patches[src * pl..(src + team) * pl]);
                vectors.extend_from_slice(&self.vectors[src * vl..(src + team) * vl]);
                masks.extend(std::iter::repeat_n(self.masks[i * (l + 1) + s], team));
            }
        }
        let (mut actions, mut rewards, mut dones, mut truncated) = (
            Vec::with_capacity(l * n),
            Vec::with_capacity(l * n),
            Vec::with_capacity(l * n),
            Vec::with_capacity(l * n),
        );
        let mut truncations = Vec::new();
        for s in 0..l {
            for (bi, &i) in picks.iter().enumerate() {
                let src = (i * l + s) * team;
                actions.extend_from_slice(&self.actions[src..src + team]);
                rewards.extend_from_slice(&self.rewards[src..src + team]);
                dones.extend(std::iter::repeat_n(self.dones[i * l + s], team));
                let tr = self.truncated[i * l + s];
                truncated.extend(std::iter::repeat_n(tr, team));
                if tr > 0.5 {
                    truncations.push((bi, s));
                }
            }
        }
        let (mut final_patches, mut final_vectors, mut actor_h, mut critic_h) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for &i in picks {
            final_patches
                .extend_from_slice(&self.final_patches[i * team * pl..(i + 1) * team * pl]);
            final_vectors
                .extend_from_slice(&self.final_vectors[i * team * vl..(i + 1) * team * vl]);
            actor_h.extend_from_slice(&self.actor_h[i * team * hd..(i + 1) * team * hd]);
            critic_h.extend_from_slice(&self.critic_h[i * team * hd..(i + 1) * team * hd]);
        }
        let side = self.patch_side;
        let (patches, vectors) = obs_tensors(&patches, &vectors, (l + 1) * n, 1, side, device);
        let (final_patches, final_vectors) =
            obs_tensors(&final_patches, &final_vectors, n, 1, side, device);
        let f = |v: &[f32]| Tensor::from_slice(v).to_device(device);
        Batch {
            len: l,
            rows: n,
            team,
            patches,
            vectors,
            masks: f(&masks).view([(l + 1) as i64, n as i64]),
            actions: Tensor::from_slice(&actions).to_device(device),
            rewards: f(&rewards),
            dones: f(&dones),
            truncated: f(&truncated),
            final_patches,
            final_vectors,
            actor_h0: f(&actor_h).view([n as i64, hd as i64]),
            critic_h0: f(&critic_h).view([n as i64, hd as i64]),
            truncations,
        }
    }
}

/// Sampled sequences as tensors (see `SequenceReplay::sample`); `rows` = sequences x team.
pub struct Batch {
    pub len: usize,
    pub rows: usize,
    pub team: usize,
    /// Steps 0..=len: [(len + 1) * rows, 1, S, S] u8 and [(len + 1) * rows, V].
    pub patches: Tensor,
    pub vectors: Tensor,
    /// [len + 1, rows]
    pub masks: Tensor,
    /// Steps 0..len: [len * rows].
    pub actions: Tensor,
    pub rewards: Tensor,
    pub dones: Tensor,
    pub truncated: Tensor,
    /// [rows, ...]: where a sequence was truncated, the state it reached.
    pub final_patches: Tensor,
    pub final_vectors: Tensor,
    /// Recurrent states at step 0 while acting, [rows, hidden].
    pub actor_h0: Tensor,
    pub critic_h0: Tensor,
    /// (sequence, step) of every truncation.
    pub truncations: Vec<(usize, usize)>,
}

impl Batch {
    /// Steps 0..len of the observations (what the online networks learn on).
    pub fn now(&self) -> (Tensor, Tensor, Tensor) {
        let n = (self.len * self.rows) as i64;
        (
            self.patches.narrow(0, 0, n),
            self.vectors.narrow(0, 0, n),
            self.masks.narrow(0, 0, self.len as i64),
        )
    }

    /// For every truncation, the rows of its team: into the states of steps
    /// 0..=len ([(len + 1) * rows]), into the final observations ([rows]),
    /// and into the TD targets ([len * rows]). None without truncations.
    pub fn truncated_rows(&self) -> Option<(Tensor, Tensor, Tensor)> {
        if self.truncations.is_empty() {
            return None;
        }
        let (mut state, mut fin, mut at) = (Vec::new(), Vec::new(), Vec::new());
        for &(b, s) in &self.truncations {
            for j in 0..self.team {
                let r = b * self.team + j;
                state.push((s * self.rows + r) as i64);
                fin.push(r as i64);
                at.push((s * self.rows + r) as i64);
            }
        }
        let dev = self.patches.device();
        let t = |v: Vec<i64>| Tensor::from_slice(&v).to_device(dev);
        Some((t(state), t(fin), t(at)))
    }
}

/// The TD target y = r + gamma * ((1 - done) * next + truncated * final):
/// a capture ends the return; a step-limit cut (done and truncated) goes on
/// from the state the episode reached (`final_value`), not from the next
/// episode's first state (`next_value`).
pub fn td_target(
    rewards: &Tensor,
    dones: &Tensor,
    truncated: &Tensor,
    next_value: &Tensor,
    final_value: &Tensor,
    gamma: f64,
) -> Tensor {
    let live: Tensor = 1.0 - dones;
    rewards + (live * next_value + truncated * final_value) * gamma
}

/// Uniform [0, 1) noise shaped like `like`, on its device, drawn from the
/// trainer's own generator: torch's global one is shared by every trainer
/// in the process (tests run in parallel), so runs stay reproducible.
pub fn uniform_like(like: &Tensor, rng: &mut ChaCha8Rng) -> Tensor {
    let n = like.numel();
    let u: Vec<f32> = (0..n).map(|_| rng.gen::<f32>()).collect();
    Tensor::from_slice(&u)
        .view(like.size().as_slice())
        .to_device(like.device())
}

/// Gumbel(0, 1) noise shaped like `like`, from `rng`.
pub fn gumbel_noise(like: &Tensor, rng: &mut ChaCha8Rng) -> Tensor {
    let u = uniform_like(like, rng).clamp(1e-10, 1.0 - 1e-7);
    -(-u.log()).log()
}

/// The Gumbel-softmax straight-through estimator (Jang et al. 2017): the
/// forward value is the one-hot of argmax(logits + noise), a discrete action
/// a critic can read; the gradient is that of the relaxed sample
/// softmax((logits + noise) / temperature).
pub fn gumbel_softmax_st(logits: &Tensor, noise: &Tensor, temperature: f64) -> Tensor {
    let soft = ((logits + noise) / temperature).softmax(-1, Kind::Float);
    let hard = one_hot(&soft.argmax(-1, false), soft.size()[1]);
    hard - soft.detach() + soft
}

/// One-hot rows of `actions` [N] i64 -> [N, n] f32.
pub fn one_hot(actions: &Tensor, n: i64) -> Tensor {
    actions.one_hot(n).to_kind(Kind::Float)
}

/// Polyak averaging: target <- tau * online + (1 - tau) * target, variable by
/// variable (matched by name).
pub fn soft_update(target: &nn::VarStore, online: &nn::VarStore, tau: f64) {
    let online = online.variables();
    tch::no_grad(|| {
        for (name, mut t) in target.variables() {
            let o = &online[&name];
            let mixed = &t * (1.0 - tau) + o * tau;
            t.copy_(&mixed);
        }
    });
}

/// The parameters an off-policy learner keeps beside its networks' modules:
/// online and target variables of actor and critic, an Adam for each online
/// network, and two clocks. MADDPG and MAAC build, undo, checkpoint and
/// restore them alike; only the modules built on them differ.
pub struct Params {
    pub actor: nn::VarStore,
    pub critic: nn::VarStore,
    pub target_actor: nn::VarStore,
    pub target_critic: nn::VarStore,
    pub actor_adam: Adam,
    pub critic_adam: Adam,
    /// Gradient steps taken so far.
    pub gradient_steps: u64,
    /// World-steps collected so far (MADDPG's exploration clock).
    pub collected_steps: u64,
}

/// The clocks of `Params`, kept in `meta.json` (the tensors go into files).
#[derive(Serialize, Deserialize)]
pub struct ParamsState {
    actor_adam_steps: u64,
    critic_adam_steps: u64,
    gradient_steps: u64,
    collected_steps: u64,
}

/// A copy of `Params` taken before an update phase, so a non-finite loss
/// undoes the whole phase, not only its last step.
pub struct Undo {
    point: UndoPoint,
    gradient_steps: u64,
}

/// The modules built on `Params`: (actor, critic, target actor, target
/// critic).
pub type Modules<A, C> = (A, C, A, C);

impl Params {
    /// Online networks from `actor` and `critic`, targets that start as
    /// their copies, and fresh optimisers.
    pub fn new<A, C>(
        device: Device,
        actor_lr: f64,
        critic_lr: f64,
        adam_eps: f64,
        actor: impl Fn(&nn::Path) -> A,
        critic: impl Fn(&nn::Path) -> C,
    ) -> (Params, Modules<A, C>) {
        let actor_vs = nn::VarStore::new(device);
        let online_actor = actor(&actor_vs.root());
        let critic_vs = nn::VarStore::new(device);
        let online_critic = critic(&critic_vs.root());
        let mut target_actor = nn::VarStore::new(device);
        let target_actor_module = actor(&target_actor.root());
        let mut target_critic = nn::VarStore::new(device);
        let target_critic_module = critic(&target_critic.root());
        target_actor.copy(&actor_vs).expect("same shapes");
        target_critic.copy(&critic_vs).expect("same shapes");
        let params = Params {
            actor_adam: Adam::new(&actor_vs, actor_lr, adam_eps),
            critic_adam: Adam::new(&critic_vs, critic_lr, adam_eps),
            actor: actor_vs,
            critic: critic_vs,
            target_actor,
            target_critic,
            gradient_steps: 0,
            collected_steps: 0,
        };
        let modules = (
            online_actor,
            online_critic,
            target_actor_module,
            target_critic_module,
        );
        (params, modules)
    }

    fn stores(&self) -> [&nn::VarStore; 4] {
        [
            &self.actor,
            &self.critic,
            &self.target_actor,
            &self.target_critic,
        ]
    }

    /// Polyak-averages both targets towards their online networks.
    pub fn update_targets(&self, tau: f64) {
        soft_update(&self.target_actor, &self.actor, tau);
        soft_update(&self.target_critic, &self.critic, tau);
    }

    /// Ends a gradient step whose optimisers have stepped: the targets
    /// move `tau` of the way and the step is counted.
    pub fn finish_step(&mut self, tau: f64) {
        self.update_targets(tau);
        self.gradient_steps += 1;
    }

    pub fn undo_point(&self) -> Undo {
        Undo {
            point: UndoPoint::take(&self.stores(), &[&self.actor_adam, &self.critic_adam]),
            gradient_steps: self.gradient_steps,
        }
    }

    pub fn undo(&mut self, undo: Undo) {
        let stores = [
            &self.actor,
            &self.critic,
            &self.target_actor,
            &self.target_critic,
        ];
        undo.point
            .restore(&stores, &mut [&mut self.actor_adam, &mut self.critic_adam]);
        self.gradient_steps = undo.gradient_steps;
    }

    /// Online and target weights, and both Adams' moments in one file.
    pub fn checkpoint_files(&self) -> Vec<(&'static str, NamedTensors)> {
        let mut files: Vec<(&'static str, NamedTensors)> = Self::FILES
            .iter()
            .zip(self.stores())
            .map(|(name, vs)| (*name, named_cpu_tensors(vs)))
            .collect();
        files.push((
            "optimizer.safetensors",
            optimizer_file(&self.actor_adam, &self.critic_adam),
        ));
        files
    }

    const FILES: [&'static str; 4] = [
        "actor.safetensors",
        "critic.safetensors",
        "target_actor.safetensors",
        "target_critic.safetensors",
    ];

    pub fn state(&self) -> serde_json::Value {
        serde_json::to_value(ParamsState {
            actor_adam_steps: self.actor_adam.steps,
            critic_adam_steps: self.critic_adam.steps,
            gradient_steps: self.gradient_steps,
            collected_steps: self.collected_steps,
        })
        .expect("serialisable")
    }

    /// Weights, target networks, Adam moments and clocks, exactly as saved.
    pub fn restore(
        &mut self,
        files: &[(&'static str, NamedTensors)],
        state: serde_json::Value,
        dir: &Path,
    ) -> Result<(), LearnError> {
        let st: ParamsState =
            serde_json::from_value(state).map_err(|e| CheckpointError::Invalid {
                path: dir.to_path_buf(),
                what: format!("learner_state: {e}"),
            })?;
        let stores = [
            &mut self.actor,
            &mut self.critic,
            &mut self.target_actor,
            &mut self.target_critic,
        ];
        for (vs, name) in stores.into_iter().zip(Self::FILES) {
            load_into(vs, file(files, name), &dir.join(name))?;
        }
        restore_optimizers(
            files,
            (&mut self.actor_adam, st.actor_adam_steps),
            (&mut self.critic_adam, st.critic_adam_steps),
            dir,
        )?;
        self.gradient_steps = st.gradient_steps;
        self.collected_steps = st.collected_steps;
        Ok(())
    }
}

/// MADDPG's and MAAC's kind: where their table is in a side's config and
/// how a learner is built from it; the rest follows from the table.
pub struct ReplayKind<C: ReplayConfig> {
    pub table: &'static str,
    pub settings: fn(&SideConfig) -> &C,
    pub build: fn(C, NetConfig, usize, usize, Device) -> Box<dyn Learner>,
}

impl<C: ReplayConfig> LearnerKind for ReplayKind<C> {
    fn settings_table(&self) -> &'static str {
        self.table
    }
    fn off_policy(&self) -> bool {
        true
    }
    fn chunk_len(&self, side: &SideConfig) -> usize {
        (self.settings)(side).replay_settings().chunk_len
    }
    fn gamma(&self, side: &SideConfig) -> f64 {
        (self.settings)(side).gamma()
    }
    fn validate(&self, side: &SideConfig) -> Result<(), ConfigError> {
        (self.settings)(side).check(&side.net)
    }
    fn replay(&self, side: &SideConfig) -> Option<(usize, usize)> {
        let s = (self.settings)(side).replay_settings();
        Some((s.buffer_steps, s.chunk_len))
    }
    fn build(
        &self,
        side: &SideConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> Box<dyn Learner> {
        let cfg = (self.settings)(side).clone();
        (self.build)(cfg, side.net.clone(), vector_len, team, device)
    }
}

/// What an off-policy learner holds beside its own networks and settings:
/// the networks' shape, the team, the variables and optimisers (`Params`),
/// the replay and how an update phase draws on it. MADDPG and MAAC build it
/// alike and differ only in their critic and gradient step.
pub struct ReplayCore {
    pub net: NetConfig,
    pub device: Device,
    pub team: usize,
    /// How many robots' rows the critic reads (the Q critic the whole team,
    /// the attention critic each robot's own).
    pub critic_agents: usize,
    pub settings: ReplaySettings,
    /// Online and target variables, optimisers and clocks.
    pub params: Params,
    pub replay: SequenceReplay,
}

impl ReplayCore {
    /// The core of a learner whose actor is `Actor` and whose critic
    /// `critic` builds, with those modules (online and target).
    #[allow(clippy::too_many_arguments)]
    pub fn new<C>(
        settings: ReplaySettings,
        net: NetConfig,
        vector_len: usize,
        team: usize,
        critic_agents: usize,
        device: Device,
        critic: impl Fn(&nn::Path) -> C,
    ) -> (ReplayCore, Modules<Actor, C>) {
        let (params, modules) = Params::new(
            device,
            settings.actor_lr,
            settings.critic_lr,
            settings.adam_eps,
            |p| Actor::new(p, &net, vector_len),
            critic,
        );
        let replay = SequenceReplay::new(
            (settings.buffer_steps / settings.chunk_len).max(1),
            settings.chunk_len,
            team,
            net.input_side(),
            vector_len,
            net.hidden as usize,
        );
        let core = ReplayCore {
            net,
            device,
            team,
            critic_agents,
            settings,
            params,
            replay,
        };
        (core, modules)
    }
}

/// An off-policy learner: its algorithm, its core, its actor, its gradient
/// step, its critic's step while acting and its exploration. Every one is a
/// `Learner` through the one impl below, so the plumbing MADDPG and MAAC
/// share (the update phase, checkpoints, restore) is written once.
pub trait OffPolicy {
    const ALGORITHM: Algorithm;
    fn core(&self) -> &ReplayCore;
    fn core_mut(&mut self) -> &mut ReplayCore;
    fn policy(&self) -> &Actor;
    /// One gradient step on a sampled batch (critic, actor, targets), its
    /// losses and norms added to `stats`.
    fn gradient_step(
        &mut self,
        b: &Batch,
        stats: &mut UpdateStats,
        rng: &mut ChaCha8Rng,
    ) -> Result<(), BadUpdate>;
    /// The critic's next recurrent state (an off-policy critic values
    /// nothing while acting).
    fn critic_h(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> Tensor;
    /// Share of actions drawn uniformly while training.
    fn explore(&self) -> f64 {
        0.0
    }
}

/// After each rollout: its chunks into the replay and its world-steps onto
/// the clock; then, once the replay holds `learning_starts` world-steps,
/// `gradient_steps(..)` sampled batches. A non-finite step undoes the whole
/// phase (weights, targets, moments), not the replay.
fn update_phase<T: OffPolicy>(
    learner: &mut T,
    ro: &Rollout,
    rng: &mut ChaCha8Rng,
) -> Result<UpdateStats, BadUpdate> {
    let core = learner.core_mut();
    core.replay.push_rollout(ro);
    let (filled, len, team) = (core.replay.filled, core.replay.len, core.replay.team);
    let new_steps = ro.steps * ro.rows / team;
    core.params.collected_steps += new_steps as u64;
    let mut stats = UpdateStats::default();
    let (batch_size, device) = (core.settings.batch_size, core.device);
    if filled * len < core.settings.learning_starts {
        return Ok(stats);
    }
    let undo = core.params.undo_point();
    let steps = gradient_steps(core.settings.replay_ratio, new_steps, batch_size, len);
    for _ in 0..steps {
        let b = learner.core_mut().replay.sample(batch_size, rng, device);
        if let Err(bad) = learner.gradient_step(&b, &mut stats, rng) {
            learner.core_mut().params.undo(undo);
            return Err(bad);
        }
    }
    stats.average();
    Ok(stats)
}

/// A recurrent critic's trunk, as the TD targets read it: its states over
/// a batch's sequences, and one step on from a state.
pub trait CriticTrunk {
    fn unroll(&self, patches: &Tensor, vectors: &Tensor, h0: &Tensor, masks: &Tensor) -> Tensor;
    fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> Tensor;
}

/// The TD targets of a batch, [len * rows], from the target networks:
/// `value(actor states, critic states)` of every next state, and of the
/// states that episodes cut off by the step limit reached, bootstrapped
/// there; no gradient. MADDPG's value is the greedy action's Q, MAAC's the
/// soft value of a sampled one.
pub fn batch_td_targets<C: CriticTrunk>(
    b: &Batch,
    actor: &Actor,
    critic: &C,
    gamma: f64,
    mut value: impl FnMut(&Tensor, &Tensor) -> Tensor,
) -> Tensor {
    let (l, n) = (b.len as i64, b.rows as i64);
    tch::no_grad(|| {
        let ha = actor.unroll_states(&b.patches, &b.vectors, &b.actor_h0, &b.masks);
        let hc = critic.unroll(&b.patches, &b.vectors, &b.critic_h0, &b.masks);
        let next = value(&ha, &hc).narrow(0, n, l * n);
        let mut final_value = next.zeros_like();
        if let Some((state_rows, final_rows, at)) = b.truncated_rows() {
            let p = b.final_patches.index_select(0, &final_rows);
            let v = b.final_vectors.index_select(0, &final_rows);
            let (_, ha_f) = actor.step(&p, &v, &ha.index_select(0, &state_rows));
            let hc_f = critic.step(&p, &v, &hc.index_select(0, &state_rows));
            final_value = final_value.index_copy(0, &at, &value(&ha_f, &hc_f));
        }
        td_target(
            &b.rewards,
            &b.dones,
            &b.truncated,
            &next,
            &final_value,
            gamma,
        )
    })
}

/// The policy's mean entropy over rows of log-probabilities [N, 5] (for
/// the logs; no gradient).
pub fn mean_entropy(log_probs: &Tensor) -> f64 {
    tch::no_grad(|| {
        -(log_probs.exp() * log_probs)
            .sum_dim_intlist(-1, false, Kind::Float)
            .mean(Kind::Float)
    })
    .double_value(&[])
}

/// Gradient steps that sample `replay_ratio` x `new_steps` world-steps in
/// batches of `batch` sequences of `len` steps (at least one).
pub fn gradient_steps(replay_ratio: f64, new_steps: usize, batch: usize, len: usize) -> usize {
    ((replay_ratio * new_steps as f64 / (batch * len) as f64).round() as usize).max(1)
}

impl<T: OffPolicy> Learner for T {
    fn algorithm(&self) -> Algorithm {
        T::ALGORITHM
    }
    fn net(&self) -> &NetConfig {
        &self.core().net
    }
    fn actor(&self) -> &Actor {
        self.policy()
    }
    fn team(&self) -> usize {
        self.core().team
    }
    fn critic_agents(&self) -> usize {
        self.core().critic_agents
    }
    fn chunk_len(&self) -> usize {
        self.core().settings.chunk_len
    }
    fn needs_values(&self) -> bool {
        false
    }
    fn critic_step(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h: &Tensor,
    ) -> (Option<Tensor>, Tensor) {
        (None, self.critic_h(patches, vectors, h))
    }
    fn exploration(&self) -> f64 {
        self.explore()
    }
    fn update(&mut self, ro: &Rollout, rng: &mut ChaCha8Rng) -> Result<UpdateStats, BadUpdate> {
        update_phase(self, ro, rng)
    }
    fn max_bad_updates(&self) -> u32 {
        self.core().settings.max_bad_updates
    }
    fn checkpoint_files(&self) -> Vec<(&'static str, NamedTensors)> {
        self.core().params.checkpoint_files()
    }
    fn learner_state(&self) -> serde_json::Value {
        self.core().params.state()
    }
    /// Weights, target networks, Adam moments and clocks come back exactly;
    /// the replay starts empty and refills for `learning_starts` steps
    /// before learning resumes. Saving it would write `buffer_steps`
    /// world-steps (0.4 GB by default) at every checkpoint, and the data the
    /// current policy collects again is what the critic needs most.
    fn restore(
        &mut self,
        files: &[(&'static str, NamedTensors)],
        state: serde_json::Value,
        dir: &Path,
    ) -> Result<(), LearnError> {
        let core = self.core_mut();
        core.params.restore(files, state, dir)?;
        core.replay.clear();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(t: &Tensor) -> Vec<f32> {
        let n = t.numel();
        let mut v = vec![0f32; n];
        t.to_kind(Kind::Float).copy_data(&mut v, n);
        v
    }

    #[test]
    fn td_target_stops_at_capture_and_bootstraps_a_truncation_from_the_state_reached() {
        // gamma 0.5. Step 0 goes on; step 1 ends in a capture; step 2 is cut
        // by the step limit in a state worth 40 (the next episode's first
        // state is worth 30, which must not count).
        let t = |v: &[f32]| Tensor::from_slice(v);
        let y = td_target(
            &t(&[1.0, 2.0, 3.0]),
            &t(&[0.0, 1.0, 1.0]),
            &t(&[0.0, 0.0, 1.0]),
            &t(&[10.0, 20.0, 30.0]),
            &t(&[99.0, 99.0, 40.0]),
            0.5,
        );
        // 1 + 0.5 * 10 = 6; 2 + 0 = 2; 3 + 0.5 * 40 = 23.
        assert_eq!(values(&y), vec![6.0, 2.0, 23.0]);
    }

    #[test]
    fn gumbel_softmax_is_one_hot_forward_with_the_relaxed_gradient() {
        // Logits 0, 0 with noise 0, ln 3: relaxed sample softmax(0, ln 3) =
        // (0.25, 0.75), so the forward value is (0, 1).
        let logits = Tensor::from_slice(&[0f32, 0.0])
            .view([1, 2])
            .set_requires_grad(true);
        let noise = Tensor::from_slice(&[0f32, 3f32.ln()]).view([1, 2]);
        let y = gumbel_softmax_st(&logits, &noise, 1.0);
        assert_eq!(values(&y), vec![0.0, 1.0]);
        // d y0 / d logits = (y0 (1 - y0), -y0 y1) = (0.1875, -0.1875).
        (&y * Tensor::from_slice(&[1f32, 0.0]).view([1, 2]))
            .sum(Kind::Float)
            .backward();
        let g = values(&logits.grad());
        assert!(
            (g[0] - 0.1875).abs() < 1e-6 && (g[1] + 0.1875).abs() < 1e-6,
            "{g:?}"
        );
        // Temperature 0.5 sharpens the relaxation: softmax(0, 2 ln 3) = (0.1, 0.9)
        // and the gradient is divided by the temperature: 0.1 * 0.9 / 0.5 = 0.18.
        let logits = Tensor::from_slice(&[0f32, 0.0])
            .view([1, 2])
            .set_requires_grad(true);
        let y = gumbel_softmax_st(&logits, &noise, 0.5);
        assert_eq!(values(&y), vec![0.0, 1.0]);
        y.select(1, 0).sum(Kind::Float).backward();
        let g = values(&logits.grad());
        assert!(
            (g[0] - 0.18).abs() < 1e-6 && (g[1] + 0.18).abs() < 1e-6,
            "{g:?}"
        );
    }

    #[test]
    fn the_replay_keeps_each_chunk_with_its_next_and_final_observations() {
        // One world of two robots, 4 steps in chunks of 2; vector[0] names
        // the step and robot (10 t + r). Step 2 is cut by the step limit in
        // a state marked 100 + r; step 3 starts the next episode.
        let net = crate::nn::NetConfig {
            hidden: 2,
            patch_pool: 6,
            ..Default::default()
        };
        let (rows, vl) = (2, 2);
        let mut ro = Rollout::new(4, rows, vl, &net, 2);
        for t in 0..4 {
            for r in 0..rows {
                ro.vectors[(t * rows + r) * vl] = (10 * t + r) as f32;
                ro.actions[t * rows + r] = (t + r) as i64;
                ro.rewards[t * rows + r] = t as f32;
            }
        }
        for r in 0..rows {
            ro.dones[2 * rows + r] = 1.0;
            ro.truncated[2 * rows + r] = 1.0;
            ro.final_vectors[(2 * rows + r) * vl] = (100 + r) as f32;
            ro.masks[3 * rows + r] = 0.0;
            ro.last_vectors[r * vl] = (40 + r) as f32;
            for c in 0..2 {
                ro.actor_h[(c * rows + r) * 2] = (10 * c + r) as f32;
            }
        }
        let mut replay = SequenceReplay::new(10, 2, 2, net.input_side(), vl, 2);
        replay.push_rollout(&ro);
        assert_eq!(replay.filled, 2);
        // Sequence 1 (steps 2, 3, then the observation after the rollout)
        // first, then sequence 0 (steps 0, 1, then step 2).
        let b = replay.batch_of(&[1, 0], Device::Cpu);
        let first = |t: &Tensor| values(&t.select(1, 0));
        assert_eq!(
            first(&b.vectors),
            vec![20., 21., 0., 1., 30., 31., 10., 11., 40., 41., 20., 21.]
        );
        assert_eq!(
            values(&b.masks),
            vec![1., 1., 1., 1., 0., 0., 1., 1., 1., 1., 1., 1.]
        );
        assert_eq!(values(&b.rewards), vec![2., 2., 0., 0., 3., 3., 1., 1.]);
        assert_eq!(values(&b.dones), vec![1., 1., 0., 0., 0., 0., 0., 0.]);
        assert_eq!(values(&b.truncated), values(&b.dones));
        let mut actions = [0i64; 8];
        b.actions.copy_data(&mut actions, 8);
        assert_eq!(actions, [2, 3, 0, 1, 3, 4, 1, 2]);
        assert_eq!(b.truncations, vec![(0, 0)]);
        assert_eq!(first(&b.final_vectors)[..2], [100., 101.]);
        assert_eq!(first(&b.actor_h0), vec![10., 11., 0., 1.]);
        let (state, fin, at) = b.truncated_rows().unwrap();
        for t in [&state, &fin, &at] {
            let mut v = [0i64; 2];
            t.copy_data(&mut v, 2);
            assert_eq!(v, [0, 1]);
        }
    }

    #[test]
    fn the_replay_ratio_sets_the_gradient_steps() {
        // 32 worlds x 100 steps, batches of 32 sequences of 10 steps.
        assert_eq!(gradient_steps(1.0, 3200, 32, 10), 10);
        assert_eq!(gradient_steps(2.0, 3200, 32, 10), 20);
        assert_eq!(gradient_steps(0.01, 3200, 32, 10), 1);
    }

    #[test]
    fn soft_update_moves_targets_by_tau() {
        let online = nn::VarStore::new(Device::Cpu);
        let target = nn::VarStore::new(Device::Cpu);
        let o = online
            .root()
            .var_copy("w", &Tensor::from_slice(&[3f32, 6.0]));
        let t = target
            .root()
            .var_copy("w", &Tensor::from_slice(&[1f32, 2.0]));
        soft_update(&target, &online, 0.25);
        // 0.25 * 3 + 0.75 * 1 = 1.5; 0.25 * 6 + 0.75 * 2 = 3.
        assert_eq!(values(&t), vec![1.5, 3.0]);
        assert_eq!(values(&o), vec![3.0, 6.0]);
        soft_update(&target, &online, 1.0);
        assert_eq!(values(&t), vec![3.0, 6.0]);
    }
}
