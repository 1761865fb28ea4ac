//! The training loop behind `t2e-league train`: many worlds stepped in
//! parallel, each learning side's network run batched over all its robots
//! of all worlds, then an update per learning side (`dyn Learner`). Either
//! side learns (MAPPO, IPPO, MADDPG or MAAC); the other is a controller (heuristic, frozen checkpoint)
//! or a second learner, which is the paper's fully competitive game: both
//! always play the other's latest policy.
//!
//! A run folder holds `config.toml` (as given), `metrics.csv`, `curves.png`,
//! `checkpoints/SIDE-STEPS/` and `state.json`, which names the checkpoints
//! a `--resume` continues from.

use super::acting::{gather_side, gather_worlds, sample};
pub use super::config::{
    check_rollout, DeviceChoice, Play, SideConfig, SideDefaults, TrainConfig, TrainDefaults,
};
use super::kind::kind;
use super::learner::Learner;
use super::offpolicy::sequence_bytes;
use super::persist::{self, RunDir, RunState};
use super::rollout::{Rollout, UpdateStats};
use super::shaping::shaping_term;
use super::Algorithm;
use crate::env::vec_env::episode_seed;
use crate::env::{Action, Side, VecEnv};
use crate::map::PreparedMap;
use crate::nn::checkpoint::{checkpoint_name, code_version, CheckpointMeta, FORMAT};
use crate::nn::obs_tensors;
use crate::nn::prior::{add_prior, target_hint};
use anyhow::{anyhow, bail, Context, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use tch::{Device, Kind, Tensor};

/// What a caller adds to a rollout: actions for robots that neither a
/// learner of the trainer nor a controller inside the vector env plays (the
/// league's network opponents, batched per opponent), and a look at every
/// step (finished episodes, opponents for the worlds that restarted).
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

/// One learning side during training.
struct LearnerSide {
    side: Side,
    learner: Box<dyn Learner>,
    rollout: Rollout,
    team: usize,
    rows: usize,
    actor_h: Tensor,
    critic_h: Tensor,
    /// 0 for rows whose world just started an episode.
    next_mask: Vec<f32>,
    /// Updates undone in a row because they were not finite.
    bad_updates: u32,
    /// (phi's signed weight for this side, the side's gamma) when it shapes.
    shaping: Option<(f32, f64)>,
}

/// What a rollout's finished episodes and its clocks add up to.
#[derive(Default)]
struct RolloutTally {
    episodes: usize,
    captures: usize,
    len_sum: f64,
    captor_return: f64,
    target_return: f64,
    time_env: f64,
    time_inference: f64,
}

impl RolloutTally {
    /// The episode means and the rollout's clocks as a metrics row; the
    /// caller fills in the counters and the update's part.
    fn metrics(&self, time_bootstrap: f64) -> Metrics {
        let per = |x: f64| {
            if self.episodes > 0 {
                x / self.episodes as f64
            } else {
                f64::NAN
            }
        };
        Metrics {
            episodes: self.episodes,
            capture_rate: per(self.captures as f64),
            episode_len: per(self.len_sum),
            captor_return: per(self.captor_return),
            target_return: per(self.target_return),
            time_env: self.time_env,
            time_inference: self.time_inference + time_bootstrap,
            ..Metrics::default()
        }
    }
}

/// One side's part of an update, for the metrics.
struct SideUpdate {
    side: Side,
    algorithm: Algorithm,
    learning_rate: Option<f64>,
    /// None when the learner took no gradient step.
    stats: Option<UpdateStats>,
}

impl SideUpdate {
    fn record(self, m: &mut Metrics) {
        match self.side {
            Side::Captors => m.captor_lr = self.learning_rate,
            Side::Target => m.target_lr = self.learning_rate,
        }
        let Some(u) = self.stats else {
            return;
        };
        let fields = match self.side {
            Side::Captors => [
                &mut m.captor_policy_loss,
                &mut m.captor_value_loss,
                &mut m.captor_entropy,
                &mut m.captor_approx_kl,
                &mut m.captor_clip_frac,
            ],
            Side::Target => [
                &mut m.target_policy_loss,
                &mut m.target_value_loss,
                &mut m.target_entropy,
                &mut m.target_approx_kl,
                &mut m.target_clip_frac,
            ],
        };
        // KL and clipping are PPO's; an off-policy learner leaves them empty.
        let ppo_only = |x: f64| (!kind(self.algorithm).off_policy()).then_some(x);
        for (f, v) in fields.into_iter().zip([
            Some(u.policy_loss),
            Some(u.value_loss),
            Some(u.entropy),
            ppo_only(u.approx_kl),
            ppo_only(u.clip_frac),
        ]) {
            *f = v;
        }
    }
}

/// One row of `metrics.csv`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Metrics {
    pub iteration: u64,
    pub env_steps: u64,
    pub wall_s: f64,
    /// Environment steps per second of this iteration (rollout + update).
    pub steps_per_s: f64,
    pub episodes: usize,
    /// Share of the episodes that ended this iteration with a capture.
    pub capture_rate: f64,
    pub episode_len: f64,
    /// Mean undiscounted episode return per robot of each side.
    pub captor_return: f64,
    pub target_return: f64,
    /// Seconds of this iteration stepping worlds, running networks for
    /// actions and values, and updating.
    pub time_env: f64,
    pub time_inference: f64,
    pub time_update: f64,
    pub captor_policy_loss: Option<f64>,
    pub captor_value_loss: Option<f64>,
    pub captor_entropy: Option<f64>,
    pub captor_approx_kl: Option<f64>,
    pub captor_clip_frac: Option<f64>,
    pub target_policy_loss: Option<f64>,
    pub target_value_loss: Option<f64>,
    pub target_entropy: Option<f64>,
    pub target_approx_kl: Option<f64>,
    pub target_clip_frac: Option<f64>,
    /// The learners' actor learning rate this iteration (PPO's; it moves
    /// under `lr_anneal`).
    pub captor_lr: Option<f64>,
    pub target_lr: Option<f64>,
}

pub struct Trainer {
    pub cfg: TrainConfig,
    pub device: Device,
    venv: VecEnv,
    learners: Vec<LearnerSide>,
    rng: ChaCha8Rng,
    actions: Vec<Action>,
    pub iteration: u64,
    pub env_steps: u64,
    /// Training time of earlier segments of a resumed run.
    pub wall_s: f64,
    /// A wall-clock budget for this invocation (`train --for`): from
    /// `wall_s` = .0, .1 seconds of training. Schedules (`lr_anneal`) then
    /// end with whichever budget runs out first, steps or seconds.
    clock_budget: Option<(f64, f64)>,
    config_hash: String,
}

fn mix_seed(seed: u64, iteration: u64) -> u64 {
    episode_seed(seed, usize::MAX, iteration)
}

impl Trainer {
    /// The maps the worlds draw their episodes from: the protocol's own,
    /// and any extra maps mixed in by share (`extra_maps::mix`).
    pub fn maps(&self) -> &Arc<Vec<Arc<PreparedMap>>> {
        self.venv.env(0).maps()
    }

    /// A fresh run on `maps`, starting at iteration `iteration` (0 unless resuming).
    pub fn new(cfg: TrainConfig, maps: Arc<Vec<Arc<PreparedMap>>>) -> Result<Trainer> {
        Trainer::starting_at(cfg, maps, 0)
    }

    fn starting_at(
        cfg: TrainConfig,
        maps: Arc<Vec<Arc<PreparedMap>>>,
        iteration: u64,
    ) -> Result<Trainer> {
        cfg.validate().map_err(anyhow::Error::msg)?;
        cfg.protocol
            .check_training_maps(&cfg.maps, &maps)
            .map_err(anyhow::Error::msg)?;
        let maps = super::map_sampling::sampling_list(&maps, cfg.map_sampling);
        let maps = if cfg.extra_maps.is_off() {
            maps
        } else {
            let spec = &cfg.extra_maps.maps;
            let extra = crate::map::catalog::load_prepared(spec)
                .with_context(|| format!("extra_maps.maps = \"{spec}\""))?;
            crate::protocol::check_extra_maps(spec, &extra)
                .map_err(|e| anyhow::anyhow!("extra_maps.{e}"))?;
            super::extra_maps::mix(&maps, &extra, cfg.extra_maps.share)
        };
        let device = cfg.device();
        if cfg.device == DeviceChoice::Cuda && !tch::Cuda::is_available() {
            bail!("device = \"cuda\" but tch sees no CUDA device; use \"auto\" or \"cpu\"");
        }
        let env_cfg = cfg.learning_env();
        let k = env_cfg.num_captors;
        // Later segments of a resumed run play fresh episodes.
        let mut venv = VecEnv::new(
            env_cfg.clone(),
            maps,
            cfg.num_envs,
            mix_seed(cfg.seed, iteration),
        )
        .map_err(anyhow::Error::msg)?;
        let mut learners = Vec::new();
        for (side, side_cfg) in [(Side::Captors, &cfg.captors), (Side::Target, &cfg.target)] {
            match &side_cfg.play {
                Play::Script(spec) => {
                    venv.script(side, || spec.build(side).expect("checked by validate"));
                }
                &Play::Learn(algorithm) => {
                    let team = side.agents(k).len();
                    let rows = team * cfg.num_envs;
                    // Each side's initial weights from its own seed, drawn
                    // while no other trainer in the process can reseed torch.
                    let init_seed = mix_seed(cfg.seed ^ 0x5eed ^ side as u64, iteration);
                    let learner = crate::nn::seeded(init_seed, || {
                        build_learner(
                            algorithm,
                            side,
                            side_cfg,
                            env_cfg.vector_len(),
                            team,
                            device,
                        )
                    })?;
                    let h = side_cfg.net.hidden;
                    learners.push(LearnerSide {
                        side,
                        rollout: Rollout::new(
                            cfg.rollout_steps,
                            rows,
                            env_cfg.vector_len(),
                            &side_cfg.net,
                            side_cfg.chunk_len(algorithm),
                        ),
                        learner,
                        team,
                        rows,
                        actor_h: Tensor::zeros([rows as i64, h], (Kind::Float, device)),
                        critic_h: Tensor::zeros([rows as i64, h], (Kind::Float, device)),
                        next_mask: vec![0.0; rows],
                        bad_updates: 0,
                        shaping: side_cfg
                            .shaping
                            .potential
                            .filter(|_| !side_cfg.shaping.is_off())
                            .map(|potential| {
                                venv.track_potential(potential);
                                let sign = match side {
                                    Side::Captors => 1.0,
                                    Side::Target => -1.0,
                                };
                                (
                                    sign * side_cfg.shaping.weight as f32,
                                    side_cfg.gamma(algorithm),
                                )
                            }),
                    });
                }
            }
        }
        venv.reset().map_err(|e| anyhow!("placing robots: {e}"))?;
        let n = cfg.num_envs * env_cfg.num_agents();
        Ok(Trainer {
            rng: ChaCha8Rng::seed_from_u64(mix_seed(cfg.seed ^ 0xac7, iteration)),
            actions: vec![Action::Stop; n],
            iteration,
            env_steps: iteration * (cfg.num_envs * cfg.rollout_steps) as u64,
            wall_s: 0.0,
            clock_budget: None,
            config_hash: cfg.hash(),
            device,
            venv,
            learners,
            cfg,
        })
    }

    /// Continues the run in `run_dir` from the checkpoints its `state.json` names.
    pub fn resume(
        cfg: TrainConfig,
        maps: Arc<Vec<Arc<PreparedMap>>>,
        run_dir: &Path,
    ) -> Result<Trainer> {
        let run = RunDir::new(run_dir);
        let state_path = run.state_path();
        let state = run.read_state()?;
        if state.config_hash != cfg.hash() {
            bail!(
                "{}: the run was started with a different configuration (hash {} vs {}); start a new run instead",
                state_path.display(),
                state.config_hash,
                cfg.hash()
            );
        }
        for p in run.clean_stale_temporaries()? {
            tracing::info!("removed {} (left by a killed run)", p.display());
        }
        let mut t = Trainer::starting_at(cfg, maps, state.iteration)?;
        t.env_steps = state.env_steps;
        t.wall_s = state.wall_s;
        for ls in &mut t.learners {
            let name = state.checkpoint_of(ls.side).with_context(|| {
                format!(
                    "{}: names no {} checkpoint",
                    state_path.display(),
                    ls.side.name()
                )
            })?;
            let dir = run.checkpoint(name);
            if !dir.is_dir() {
                bail!(
                    "{}: names the checkpoint {}, which is missing",
                    state_path.display(),
                    dir.display()
                );
            }
            let meta = persist::load_learner(&dir, ls.learner.as_mut())?;
            if (meta.env_steps, meta.iteration) != (state.env_steps, state.iteration) {
                bail!(
                    "{}: says {} env steps at iteration {}, but the checkpoint it names ({}) holds {} at iteration {}; the run folder was changed by hand",
                    state_path.display(),
                    state.env_steps,
                    state.iteration,
                    dir.display(),
                    meta.env_steps,
                    meta.iteration
                );
            }
        }
        Ok(t)
    }

    /// One PPO iteration: a rollout of `rollout_steps` in every world, then
    /// an update of every learning side.
    pub fn iterate(&mut self) -> Result<Metrics> {
        self.iterate_with(&mut NoHooks)
    }

    /// The vector env, for callers that give worlds their own opponents.
    pub fn venv_mut(&mut self) -> &mut VecEnv {
        &mut self.venv
    }

    /// `iterate`, with `hooks` acting for robots no learner here controls
    /// and seeing every step's outcome (the league's opponents): collect a
    /// rollout, bootstrap its last states, update every learning side.
    pub fn iterate_with(&mut self, hooks: &mut dyn RolloutHooks) -> Result<Metrics> {
        let start = Instant::now();
        let tally = self.collect(hooks)?;
        let t2 = Instant::now();
        self.bootstrap();
        let time_bootstrap = t2.elapsed().as_secs_f64();
        let t3 = Instant::now();
        let updates = self.update()?;
        let time_update = t3.elapsed().as_secs_f64();

        self.iteration += 1;
        let steps = (self.cfg.num_envs * self.cfg.rollout_steps) as u64;
        self.env_steps += steps;
        let secs = start.elapsed().as_secs_f64();
        self.wall_s += secs;
        let mut m = tally.metrics(time_bootstrap);
        m.iteration = self.iteration;
        m.env_steps = self.env_steps;
        m.wall_s = self.wall_s;
        m.steps_per_s = steps as f64 / secs;
        m.time_update = time_update;
        for u in updates {
            u.record(&mut m);
        }
        Ok(m)
    }

    /// Plays `rollout_steps` in every world: each learning side acts from
    /// its actor (and values the states with its critic) batched over all
    /// its robots, `hooks` act for the rest, and every step's observations,
    /// actions and rewards (plus any shaping) go into the sides' rollouts.
    fn collect(&mut self, hooks: &mut dyn RolloutHooks) -> Result<RolloutTally> {
        let k = self.cfg.env.num_captors;
        let na = k + 1;
        let vl = self.venv.cfg.vector_len();
        let mut tally = RolloutTally::default();
        for t in 0..self.cfg.rollout_steps {
            let t0 = Instant::now();
            for ls in &mut self.learners {
                let ro = &mut ls.rollout;
                let rows = ls.rows;
                let base = t * rows;
                let pl = ls.learner.net().input_len();
                gather_side(
                    &self.venv,
                    ls.side,
                    ls.learner.net(),
                    &mut ro.vectors[base * vl..(base + rows) * vl],
                    &mut ro.patches[base * pl..(base + rows) * pl],
                );
                ro.masks[base..base + rows].copy_from_slice(&ls.next_mask);
                let l = ro.chunk_len;
                // A critic that values the rollout afterwards leaves its
                // state as it was, and stores its chunk starts itself.
                let critic_steps = !ls.learner.values_after_rollout();
                if t % l == 0 {
                    let c = t / l;
                    let hsz = rows * ro.hidden;
                    ls.actor_h
                        .to_device(Device::Cpu)
                        .copy_data(&mut ro.actor_h[c * hsz..(c + 1) * hsz], hsz);
                    if critic_steps {
                        ls.critic_h
                            .to_device(Device::Cpu)
                            .copy_data(&mut ro.critic_h[c * hsz..(c + 1) * hsz], hsz);
                    }
                }
                let (p, v) = obs_tensors(
                    &ro.patches[base * pl..(base + rows) * pl],
                    &ro.vectors[base * vl..(base + rows) * vl],
                    rows,
                    1,
                    ro.patch_side,
                    self.device,
                );
                let m = Tensor::from_slice(&ls.next_mask)
                    .to_device(self.device)
                    .unsqueeze(1);
                let lr = &ls.learner;
                let prior = lr.net().heuristic_prior;
                // Validated: only a target (one robot per world) leans on it.
                let hints = lr.wants_hints().then(|| {
                    for (e, hint) in ro.hints[base..base + rows].iter_mut().enumerate() {
                        *hint = target_hint(self.venv.env(e));
                    }
                    Tensor::from_slice(&ro.hints[base..base + rows])
                });
                let (probs, values, ha, hc) = tch::no_grad(|| {
                    let (logits, ha) = lr.actor().step(&p, &v, &(&ls.actor_h * &m));
                    let logits = match &hints {
                        Some(hints) => add_prior(logits, hints, prior),
                        None => logits,
                    };
                    let (values, hc) = if critic_steps {
                        let (values, hc) = lr.critic_step(&p, &v, &(&ls.critic_h * &m));
                        (values.map(|v| v.to_device(Device::Cpu)), Some(hc))
                    } else {
                        (None, None)
                    };
                    (
                        logits.softmax(-1, Kind::Float).to_device(Device::Cpu),
                        values,
                        ha,
                        hc,
                    )
                });
                ls.actor_h = ha;
                if let Some(hc) = hc {
                    ls.critic_h = hc;
                }
                let mut pr = vec![0f32; rows * Action::COUNT];
                probs.copy_data(&mut pr, rows * Action::COUNT);
                if let Some(values) = values {
                    values.copy_data(&mut ro.values[base..base + rows], rows);
                }
                let epsilon = lr.exploration() as f32;
                if epsilon > 0.0 {
                    let uniform = epsilon / Action::COUNT as f32;
                    pr.iter_mut()
                        .for_each(|p| *p = (1.0 - epsilon) * *p + uniform);
                }
                for row in 0..rows {
                    let p = &pr[row * Action::COUNT..(row + 1) * Action::COUNT];
                    let a = sample(p, &mut self.rng);
                    ro.actions[base + row] = a as i64;
                    ro.logp[base + row] = p[a].max(1e-12).ln();
                    let (e, j) = (row / ls.team, row % ls.team);
                    self.actions[e * na + ls.side.agents(k).start + j] = Action::from_index(a);
                }
            }
            let t1 = Instant::now();
            // Opponents acting count as environment time, like the scripted
            // controllers that act inside the vector env.
            hooks.before_step(&mut self.venv, &mut self.actions)?;
            let phi_before = self.venv.potentials.clone();
            self.venv
                .step(&self.actions)
                .map_err(|e| anyhow!("placing robots: {e}"))?;
            hooks.after_step(&mut self.venv)?;
            let truncated_worlds: Vec<usize> = (0..self.cfg.num_envs)
                .filter(|&e| self.venv.truncated[e])
                .collect();
            for ls in &mut self.learners {
                let base = t * ls.rows;
                for row in 0..ls.rows {
                    let (e, j) = (row / ls.team, row % ls.team);
                    let done = self.venv.terminated[e] || self.venv.truncated[e];
                    let mut reward = self.venv.rewards[e * na + ls.side.agents(k).start + j];
                    if let Some((weight, gamma)) = ls.shaping {
                        reward += weight
                            * shaping_term(
                                phi_before[e],
                                self.venv.potentials[e],
                                self.venv.final_potentials[e],
                                self.venv.terminated[e],
                                self.venv.truncated[e],
                                gamma,
                            );
                    }
                    ls.rollout.rewards[base + row] = reward;
                    ls.rollout.dones[base + row] = done as u8 as f32;
                    ls.rollout.truncated[base + row] = self.venv.truncated[e] as u8 as f32;
                    ls.next_mask[row] = (!done) as u8 as f32;
                }
                if !truncated_worlds.is_empty() {
                    keep_truncated_states(&self.venv, ls, &truncated_worlds, base, self.device);
                }
            }
            for s in &self.venv.finished {
                tally.episodes += 1;
                tally.captures += s.captured as usize;
                tally.len_sum += s.steps as f64;
                tally.captor_return += s.returns[..k].iter().sum::<f64>() / k as f64;
                tally.target_return += s.returns[k];
            }
            tally.time_inference += (t1 - t0).as_secs_f64();
            tally.time_env += t1.elapsed().as_secs_f64();
        }
        Ok(tally)
    }

    /// The states after the rollout, and their values where a learner
    /// needs them: GAE and the TD targets bootstrap from them.
    fn bootstrap(&mut self) {
        for ls in &mut self.learners {
            let ro = &mut ls.rollout;
            let rows = ls.rows;
            gather_side(
                &self.venv,
                ls.side,
                ls.learner.net(),
                &mut ro.last_vectors,
                &mut ro.last_patches,
            );
            ro.last_masks.copy_from_slice(&ls.next_mask);
            if ls.learner.values_after_rollout() {
                ls.critic_h = ls.learner.value_rollout(ro, &ls.critic_h);
                continue;
            }
            if !ls.learner.needs_values() {
                continue;
            }
            let (p, v) = obs_tensors(
                &ro.last_patches,
                &ro.last_vectors,
                rows,
                1,
                ro.patch_side,
                self.device,
            );
            let m = Tensor::from_slice(&ls.next_mask)
                .to_device(self.device)
                .unsqueeze(1);
            let values = tch::no_grad(|| {
                ls.learner
                    .critic_step(&p, &v, &(&ls.critic_h * &m))
                    .0
                    .expect("a learner that needs values gives them")
                    .to_device(Device::Cpu)
            });
            values.copy_data(&mut ro.last_values, rows);
        }
    }

    /// How far the run is, from 0 to 1, for schedules: the share of
    /// `total_env_steps` done, or of the clock budget when one is set and
    /// further along.
    pub fn progress(&self) -> f64 {
        let by_steps = self.env_steps as f64 / self.cfg.total_env_steps as f64;
        let by_clock = self
            .clock_budget
            .map_or(0.0, |(from, seconds)| (self.wall_s - from) / seconds);
        by_steps.max(by_clock).clamp(0.0, 1.0)
    }

    /// Schedules end when `seconds` more of training have passed, or at
    /// `total_env_steps` if that comes first (`train --for`). A schedule
    /// that follows the clock depends on the machine's speed: two runs of
    /// one seed then anneal at different steps and part ways. The budget is
    /// this invocation's, as `--for` is: a run resumed with `--for D`
    /// starts a new schedule over D from where the steps stand.
    pub fn set_clock_budget(&mut self, seconds: f64) {
        assert!(
            seconds > 0.0 && seconds.is_finite(),
            "a clock budget of {seconds} s"
        );
        self.clock_budget = Some((self.wall_s, seconds));
    }

    /// Every learning side's update on its rollout. A non-finite update is
    /// undone by the learner; `max_bad_updates` of them in a row stop the
    /// run.
    fn update(&mut self) -> Result<Vec<SideUpdate>> {
        let done = self.progress();
        let mut updates = Vec::new();
        for ls in &mut self.learners {
            ls.learner.set_progress(done);
            let mut update = SideUpdate {
                side: ls.side,
                algorithm: ls.learner.algorithm(),
                learning_rate: ls.learner.learning_rate(),
                stats: None,
            };
            match ls.learner.update(&ls.rollout, &mut self.rng) {
                Ok(stats) => {
                    ls.bad_updates = 0;
                    // No gradient step (a replay still filling): no losses to report.
                    update.stats = (stats.gradient_steps > 0).then_some(stats);
                }
                Err(bad) => {
                    ls.bad_updates += 1;
                    let limit = ls.learner.max_bad_updates();
                    tracing::warn!(
                        "{} update at iteration {}: {bad} ({} in a row, limit {limit})",
                        ls.side.name(),
                        self.iteration + 1,
                        ls.bad_updates
                    );
                    if ls.bad_updates >= limit {
                        bail!(
                            "{} learner: {} updates in a row had a non-finite loss or gradient (last: {}); stopping with the last good weights (max_bad_updates = {limit})",
                            ls.side.name(),
                            ls.bad_updates,
                            bad.0
                        );
                    }
                }
            }
            updates.push(update);
        }
        Ok(updates)
    }

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

    /// Steps of one iteration (all worlds).
    pub fn steps_per_iteration(&self) -> u64 {
        (self.cfg.num_envs * self.cfg.rollout_steps) as u64
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

    /// Network FLOPs of one iteration, counted from the layer shapes: the
    /// rollout's forward passes (actor, and the critic where the learner
    /// values states) and PPO's update (each epoch a forward and a
    /// backward, about three forwards, of actor and critic over every row).
    /// NaN for the off-policy learners, whose update cost follows their
    /// replay settings.
    pub fn network_flops_per_iteration(&self) -> f64 {
        let vl = self.venv.cfg.vector_len();
        let mut total = 0.0;
        for ls in &self.learners {
            let net = ls.learner.net();
            let actor = net.forward_flops(1, vl, Action::COUNT);
            let critic = if ls.learner.needs_values() {
                let c = ls.learner.critic_agents();
                net.forward_flops(c, vl * c, 1)
            } else {
                0.0
            };
            let rows = (ls.rows * self.cfg.rollout_steps) as f64;
            let side_cfg = match ls.side {
                Side::Captors => &self.cfg.captors,
                Side::Target => &self.cfg.target,
            };
            let update = kind(ls.learner.algorithm()).update_flops(side_cfg, actor, critic);
            total += rows * (actor + critic + update);
        }
        total
    }

    pub fn learner_sides(&self) -> Vec<(Side, Algorithm)> {
        self.learners
            .iter()
            .map(|l| (l.side, l.learner.algorithm()))
            .collect()
    }
}

/// The learner `algorithm` for `side`, its replay (if any) checked to fit in memory.
fn build_learner(
    algorithm: Algorithm,
    side: Side,
    side_cfg: &SideConfig,
    vector_len: usize,
    team: usize,
    device: Device,
) -> Result<Box<dyn Learner>> {
    let k = kind(algorithm);
    if let Some((steps, len)) = k.replay(side_cfg) {
        let net = &side_cfg.net;
        let bytes = (steps / len).max(1)
            * sequence_bytes(len, team, net.input_len(), vector_len, net.hidden as usize);
        const LIMIT: usize = 16 << 30;
        if bytes > LIMIT {
            bail!(
                "{}.{}.buffer_steps = {steps}: the replay would take {:.1} GiB (at most {} GiB); lower it or net.patch_pool / net.hidden",
                side.name(),
                k.settings_table(),
                bytes as f64 / (1u64 << 30) as f64,
                LIMIT >> 30
            );
        }
    }
    Ok(k.build(side_cfg, vector_len, team, device))
}

/// The states that episodes cut off by the step limit reached (the vector
/// env's final observations) into the rollout at step offset `base`, and,
/// for a learner that needs values, the critic's values of them, continuing
/// each row's recurrent state, into `final_values`: truncation is not the
/// end of the game, so GAE and TD targets bootstrap there.
fn keep_truncated_states(
    venv: &VecEnv,
    ls: &mut LearnerSide,
    worlds: &[usize],
    base: usize,
    device: Device,
) {
    let net = ls.learner.net();
    let (vl, pl, team) = (venv.cfg.vector_len(), net.input_len(), ls.team);
    let n = worlds.len() * team;
    let mut vectors = vec![0f32; n * vl];
    let mut patches = vec![0u8; n * pl];
    gather_worlds(
        venv,
        &venv.final_vectors,
        &venv.final_patches,
        worlds,
        ls.side,
        net,
        &mut vectors,
        &mut patches,
    );
    let rows: Vec<i64> = worlds
        .iter()
        .flat_map(|&e| (0..team).map(move |j| (e * team + j) as i64))
        .collect();
    let ro = &mut ls.rollout;
    for (i, &row) in rows.iter().enumerate() {
        let at = base + row as usize;
        ro.final_patches[at * pl..(at + 1) * pl].copy_from_slice(&patches[i * pl..(i + 1) * pl]);
        ro.final_vectors[at * vl..(at + 1) * vl].copy_from_slice(&vectors[i * vl..(i + 1) * vl]);
    }
    if !ls.learner.needs_values() || ls.learner.values_after_rollout() {
        return;
    }
    let (p, v) = obs_tensors(&patches, &vectors, n, 1, ls.rollout.patch_side, device);
    let values = tch::no_grad(|| {
        let h = ls
            .critic_h
            .index_select(0, &Tensor::from_slice(&rows).to_device(device));
        ls.learner
            .critic_step(&p, &v, &h)
            .0
            .expect("a learner that needs values gives them")
            .to_device(Device::Cpu)
    });
    let mut out = vec![0f32; n];
    values.copy_data(&mut out, n);
    for (row, value) in rows.iter().zip(out) {
        ls.rollout.final_values[base + *row as usize] = value;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_follows_the_probabilities() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let p = [0.1f32, 0.0, 0.6, 0.3, 0.0];
        let mut counts = [0usize; 5];
        for _ in 0..20_000 {
            counts[sample(&p, &mut rng)] += 1;
        }
        assert_eq!((counts[1], counts[4]), (0, 0));
        for (c, q) in counts.iter().zip(p) {
            assert!(
                (*c as f64 / 20_000.0 - q as f64).abs() < 0.015,
                "{counts:?}"
            );
        }
    }
}
