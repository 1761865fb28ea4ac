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
//!
//! Here: the `Trainer`, its start and resume, an iteration and its update.
//! `collect.rs` plays the rollout, `save.rs` writes and reads checkpoints,
//! `metrics.rs` is the row an iteration reports, `hooks.rs` what a caller
//! adds to a rollout. `run.rs` is a whole run in its folder (the loop
//! `train` drives: metrics, curves, resume), `periodic_eval.rs` its
//! evaluations in child processes as it goes.

mod collect;
mod csv_rows;
mod hooks;
mod metrics;
pub mod periodic_eval;
pub mod run;
mod save;
mod trainer;
pub use save::SideHandle;
use trainer::LearnerSide;
pub use trainer::Trainer;

use super::kind::kind;
use super::learner::Learner;
use super::offpolicy::sequence_bytes;
use super::persist::{self, RunDir};
use super::rollout::Rollout;
pub use super::run_config::{
    check_rollout, DeviceChoice, Play, SideConfig, SideDefaults, TrainConfig, TrainDefaults,
};
use crate::error::{LearnError, Result, ResultExt};
use crate::nn::run_dir::RunDirError;
pub use hooks::{NoHooks, RolloutHooks};
pub use metrics::Metrics;
use metrics::SideUpdate;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use t2e_core::algorithm::Algorithm;
use t2e_core::env::vec_env::episode_seed;
use t2e_core::env::{Action, EnvConfig, Side, VecEnv};
use t2e_core::error::ConfigError;
use t2e_core::map::PreparedMap;
use tch::{Device, Kind, Tensor};

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
        cfg.validate()?;
        cfg.protocol.check_training_maps(&cfg.maps, &maps)?;
        let maps = training_maps(&cfg, &maps)?;
        let device = cfg.device();
        if cfg.device == DeviceChoice::Cuda && !tch::Cuda::is_available() {
            return Err(LearnError::NoCuda);
        }
        let env_cfg = cfg.learning_env();
        // Later segments of a resumed run play fresh episodes.
        let mut venv = VecEnv::new(
            env_cfg.clone(),
            maps,
            cfg.num_envs,
            mix_seed(cfg.seed, iteration),
        )?;
        let mut learners = Vec::new();
        for (side, side_cfg) in [(Side::Captors, &cfg.captors), (Side::Target, &cfg.target)] {
            match &side_cfg.play {
                Play::Script(spec) => {
                    venv.script(side, || spec.build(side).expect("checked by validate"));
                }
                &Play::Learn(algorithm) => {
                    let env = (&env_cfg, &mut venv);
                    let learner = learner_side(&cfg, side, algorithm, env, device, iteration)?;
                    learners.push(learner);
                }
            }
        }
        venv.reset().context("placing robots")?;
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
        let disagrees = |what: String| RunDirError::StateDisagrees {
            state: state_path.clone(),
            what,
        };
        if state.config_hash != cfg.hash() {
            return Err(disagrees(format!(
                "the run was started with a different configuration (hash {} vs {}); start a new run instead",
                state.config_hash,
                cfg.hash()
            ))
            .into());
        }
        for p in run.clean_stale_temporaries()? {
            tracing::info!("removed {} (left by a killed run)", p.display());
        }
        let mut t = Trainer::starting_at(cfg, maps, state.iteration)?;
        t.env_steps = state.env_steps;
        t.wall_s = state.wall_s;
        for ls in &mut t.learners {
            let name = state
                .checkpoint_of(ls.side)
                .ok_or_else(|| disagrees(format!("names no {} checkpoint", ls.side.name())))?;
            let dir = run.checkpoint(name);
            if !dir.is_dir() {
                return Err(disagrees(format!(
                    "names the checkpoint {}, which is missing",
                    dir.display()
                ))
                .into());
            }
            let meta = persist::load_learner(&dir, ls.learner.as_mut())?;
            if (meta.env_steps, meta.iteration) != (state.env_steps, state.iteration) {
                return Err(disagrees(format!(
                    "says {} env steps at iteration {}, but the checkpoint it names ({}) holds {} at iteration {}; the run folder was changed by hand",
                    state.env_steps,
                    state.iteration,
                    dir.display(),
                    meta.env_steps,
                    meta.iteration
                ))
                .into());
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
                        return Err(LearnError::Diverged {
                            side: ls.side,
                            in_a_row: ls.bad_updates,
                            last: bad.0,
                            limit,
                        });
                    }
                }
            }
            updates.push(update);
        }
        Ok(updates)
    }

    /// Steps of one iteration (all worlds).
    pub fn steps_per_iteration(&self) -> u64 {
        (self.cfg.num_envs * self.cfg.rollout_steps) as u64
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

/// The list the worlds sample episodes from: the protocol's maps by the
/// run's sampling, mixed with any extra maps; apart from `starting_at`
/// because it is the one step that reads map files.
fn training_maps(
    cfg: &TrainConfig,
    maps: &[Arc<PreparedMap>],
) -> Result<Arc<Vec<Arc<PreparedMap>>>> {
    let maps = super::map_sampling::sampling_list(maps, cfg.map_sampling);
    Ok(if cfg.extra_maps.is_off() {
        maps
    } else {
        let spec = &cfg.extra_maps.maps;
        let extra = t2e_core::map::catalog::load_prepared(spec)
            .with_context(|| format!("extra_maps.maps = \"{spec}\""))?;
        t2e_core::protocol::check_extra_maps(spec, &extra).map_err(LearnError::ExtraMapsRefused)?;
        super::extra_maps::mix(&maps, &extra, cfg.extra_maps.share)
    })
}

/// A learning side with its network, rollout buffer and recurrent state;
/// apart from `starting_at` so a run's start reads as maps, worlds, sides.
fn learner_side(
    cfg: &TrainConfig,
    side: Side,
    algorithm: Algorithm,
    (env_cfg, venv): (&EnvConfig, &mut VecEnv),
    device: Device,
    iteration: u64,
) -> Result<LearnerSide> {
    let side_cfg = match side {
        Side::Captors => &cfg.captors,
        Side::Target => &cfg.target,
    };
    let k = env_cfg.num_captors;
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
    Ok(LearnerSide {
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
        teachers: match &side_cfg.ppo.teacher {
            // The config's check again, for its parsed spec: a target of a
            // PPO learner, one robot a world.
            Some(teacher) => {
                let spec =
                    crate::learn::teacher::check(teacher, side, !kind(algorithm).off_policy())
                        .map_err(|e| e.within("ppo").within(side.name()))?;
                crate::learn::teacher::Teacher::per_world(&spec, cfg.num_envs)?
            }
            None => Vec::new(),
        },
        prior_teachers: match &side_cfg.net.prior_teacher {
            Some(planner) => {
                let spec =
                    crate::learn::teacher::check_prior(planner, side_cfg.ppo.teacher.as_deref())
                        .map_err(|e| e.within("net").within(side.name()))?;
                crate::learn::teacher::Teacher::per_world(&spec, cfg.num_envs)?
            }
            None => Vec::new(),
        },
    })
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
            return Err(ConfigError::new(
                format!("{}.{}.buffer_steps", side.name(), k.settings_table()),
                steps,
                format!(
                    "the replay would take {:.1} GiB (at most {} GiB); lower it or net.patch_pool / net.hidden",
                    bytes as f64 / (1u64 << 30) as f64,
                    LIMIT >> 30
                ),
            )
            .into());
        }
    }
    Ok(k.build(side_cfg, vector_len, team, device))
}
