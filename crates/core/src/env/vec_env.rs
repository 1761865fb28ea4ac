//! Many worlds stepped in parallel (rayon), with flat observation buffers for
//! batched networks and auto-reset: when an episode ends, its world starts the
//! next episode at once and the buffers hold that episode's first observation.
//! Scripted sides (rule-based robots, frozen checkpoints) act inside the same
//! parallel pass.

use super::action::Action;
use super::config::EnvConfig;
use super::controller::{Controller, Side};
use super::observe::PATCH_LEN;
use super::placement::PlacementError;
use super::potential::Potential;
use super::trap_env::TrapEnv;
use crate::error::{ConfigError, EnvError};
use crate::map::PreparedMap;
use rayon::prelude::*;
use std::sync::Arc;

/// The seed of episode `episode` of world `env` in a run seeded `base`:
/// independent of thread scheduling, so runs are reproducible.
pub fn episode_seed(base: u64, env: usize, episode: u64) -> u64 {
    fn mix(mut z: u64) -> u64 {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    mix(mix(base) ^ mix((env as u64) << 32 ^ episode))
}

/// How one finished episode went.
#[derive(Clone, Debug, PartialEq)]
pub struct EpisodeStats {
    pub env: usize,
    pub seed: u64,
    pub map: String,
    pub steps: u32,
    pub captured: bool,
    /// Undiscounted return per agent.
    pub returns: Vec<f64>,
    /// Mean distance travelled per captor (m).
    pub captor_path_len: f64,
}

struct Slot {
    env: TrapEnv,
    scripted: Vec<(Side, Box<dyn Controller>)>,
    episode: u64,
    returns: Vec<f64>,
}

pub struct VecEnv {
    slots: Vec<Slot>,
    base_seed: u64,
    pub cfg: EnvConfig,
    /// [env][agent][5 + 5 K]
    pub vectors: Vec<f32>,
    /// [env][agent][48 x 48]; untouched when `cfg.observations` is off.
    pub patches: Vec<u8>,
    /// [env][agent]: rewards of the last step.
    pub rewards: Vec<f32>,
    /// [env]: the last step ended the episode by capture / by the step limit.
    pub terminated: Vec<bool>,
    pub truncated: Vec<bool>,
    /// [env][agent][5 + 5 K] and [env][agent][48 x 48]: for worlds whose
    /// episode ended in the last step, the observations of the state it ended
    /// in (the main buffers already hold the next episode's first one), so a
    /// learner can value the state a truncated episode reached. Stale for
    /// other worlds.
    pub final_vectors: Vec<f32>,
    pub final_patches: Vec<u8>,
    /// Episodes that ended in the last step.
    pub finished: Vec<EpisodeStats>,
    /// The potential tracked for reward shaping, if any (`track_potential`).
    potential: Option<Potential>,
    /// [env]: the potential of each world's current state (0 untracked).
    pub potentials: Vec<f32>,
    /// [env]: the potential of the state an episode ended in during the
    /// last step (stale for other worlds), beside `final_vectors`.
    pub final_potentials: Vec<f32>,
}

impl VecEnv {
    pub fn new(
        cfg: EnvConfig,
        maps: Arc<Vec<Arc<PreparedMap>>>,
        num_envs: usize,
        base_seed: u64,
    ) -> Result<VecEnv, EnvError> {
        if num_envs == 0 {
            return Err(ConfigError::new("num_envs", 0, "must be at least 1").into());
        }
        let slots = (0..num_envs)
            .map(|_| {
                Ok(Slot {
                    env: TrapEnv::new(cfg.clone(), maps.clone())?,
                    scripted: Vec::new(),
                    episode: 0,
                    returns: vec![0.0; cfg.num_agents()],
                })
            })
            .collect::<Result<Vec<_>, EnvError>>()?;
        let n = num_envs * cfg.num_agents();
        Ok(VecEnv {
            slots,
            base_seed,
            vectors: vec![0.0; n * cfg.vector_len()],
            patches: if cfg.observations {
                vec![0; n * PATCH_LEN]
            } else {
                Vec::new()
            },
            final_vectors: vec![0.0; n * cfg.vector_len()],
            final_patches: if cfg.observations {
                vec![0; n * PATCH_LEN]
            } else {
                Vec::new()
            },
            rewards: vec![0.0; n],
            terminated: vec![false; num_envs],
            truncated: vec![false; num_envs],
            finished: Vec::new(),
            potential: None,
            potentials: vec![0.0; num_envs],
            final_potentials: vec![0.0; num_envs],
            cfg,
        })
    }

    /// Lets controllers made by `make` play `side` in every world; the
    /// actions passed to `step` for that side are then ignored.
    pub fn script(&mut self, side: Side, make: impl Fn() -> Box<dyn Controller>) {
        for s in &mut self.slots {
            s.scripted.retain(|(sd, _)| *sd != side);
            s.scripted.push((side, make()));
        }
    }

    /// Sets who plays `side` in world `world` from now on: a controller
    /// (reset for the world's current episode), or None to take that side's
    /// actions from `step`'s argument. The league gives each world its own
    /// opponent this way.
    pub fn script_world(
        &mut self,
        world: usize,
        side: Side,
        controller: Option<Box<dyn Controller>>,
    ) {
        let slot = &mut self.slots[world];
        slot.scripted.retain(|(sd, _)| *sd != side);
        if let Some(mut c) = controller {
            c.reset(&slot.env, slot.env.seed);
            slot.scripted.push((side, c));
        }
    }

    /// Sets world `world`'s top speeds (see `TrapEnv::set_speeds`).
    pub fn set_world_speeds(
        &mut self,
        world: usize,
        captor_speed: f64,
        target_speed: f64,
    ) -> Result<(), ConfigError> {
        self.slots[world].env.set_speeds(captor_speed, target_speed)
    }

    /// Computes `potential` of every world's state from now on, into
    /// `potentials` and `final_potentials` (for training-only shaping).
    pub fn track_potential(&mut self, potential: Potential) {
        self.potential = Some(potential);
        for (p, slot) in self.potentials.iter_mut().zip(&self.slots) {
            *p = potential.of(&slot.env);
        }
    }

    /// Index of the episode world `world` is playing (0 for its first).
    pub fn episode_index(&self, world: usize) -> u64 {
        self.slots[world].episode
    }

    pub fn num_envs(&self) -> usize {
        self.slots.len()
    }

    pub fn num_agents(&self) -> usize {
        self.cfg.num_agents()
    }

    pub fn env(&self, i: usize) -> &TrapEnv {
        &self.slots[i].env
    }

    /// Starts episode 0 in every world.
    pub fn reset(&mut self) -> Result<(), PlacementError> {
        let base = self.base_seed;
        let (na, vl, obs) = (
            self.num_agents(),
            self.cfg.vector_len(),
            self.cfg.observations,
        );
        let patch_chunk = if obs { na * PATCH_LEN } else { 0 };
        let mut patches: Vec<&mut [u8]> = if obs {
            self.patches.chunks_mut(patch_chunk).collect()
        } else {
            (0..self.slots.len()).map(|_| &mut [][..]).collect()
        };
        let potential = self.potential;
        self.slots
            .par_iter_mut()
            .zip(self.vectors.par_chunks_mut(na * vl))
            .zip(patches.par_iter_mut())
            .zip(self.potentials.par_iter_mut())
            .enumerate()
            .try_for_each(|(e, (((slot, vec), patch), phi))| {
                slot.episode = 0;
                slot.begin(episode_seed(base, e, 0))?;
                slot.write_obs(vec, patch, vl, obs);
                *phi = potential.map_or(0.0, |p| p.of(&slot.env));
                Ok(())
            })
    }

    /// One step of every world. `actions` holds one action per agent per
    /// world ([env][agent]); scripted sides overwrite theirs.
    // Long on purpose: every world's step in one rayon pass over a zip of
    // all per-world buffers (scripted actions, physics, rewards, shaping,
    // auto-reset); the training hot path, kept whole so the zip is built
    // once and nothing new is allocated or indirected per step.
    pub fn step(&mut self, actions: &[Action]) -> Result<(), PlacementError> {
        let na = self.num_agents();
        assert_eq!(
            actions.len(),
            self.slots.len() * na,
            "one action per agent per world"
        );
        let base = self.base_seed;
        let (vl, obs) = (self.cfg.vector_len(), self.cfg.observations);
        let patch_chunk = if obs { na * PATCH_LEN } else { 0 };
        let mut patches: Vec<&mut [u8]> = if obs {
            self.patches.chunks_mut(patch_chunk).collect()
        } else {
            (0..self.slots.len()).map(|_| &mut [][..]).collect()
        };
        let mut final_patches: Vec<&mut [u8]> = if obs {
            self.final_patches.chunks_mut(patch_chunk).collect()
        } else {
            (0..self.slots.len()).map(|_| &mut [][..]).collect()
        };
        let potential = self.potential;
        let results: Vec<Result<Option<EpisodeStats>, PlacementError>> = self
            .slots
            .par_iter_mut()
            .zip(self.vectors.par_chunks_mut(na * vl))
            .zip(patches.par_iter_mut())
            .zip(
                self.final_vectors
                    .par_chunks_mut(na * vl)
                    .zip(final_patches.par_iter_mut()),
            )
            .zip(self.rewards.par_chunks_mut(na))
            .zip(actions.par_chunks(na))
            .zip(
                self.terminated
                    .par_iter_mut()
                    .zip(self.truncated.par_iter_mut()),
            )
            .zip(
                self.potentials
                    .par_iter_mut()
                    .zip(self.final_potentials.par_iter_mut()),
            )
            .enumerate()
            .map(
                |(
                    e,
                    (
                        (
                            (((((slot, vec), patch), (final_vec, final_patch)), rew), act),
                            (term, trunc),
                        ),
                        (phi, final_phi),
                    ),
                )| {
                    let mut acts = [Action::Stop; 33];
                    acts[..na].copy_from_slice(act);
                    let k = slot.env.num_captors();
                    for (side, ctrl) in &mut slot.scripted {
                        ctrl.act(&slot.env, *side, &mut acts[side.agents(k)]);
                    }
                    slot.env.step_state(&acts[..na], rew);
                    for (r, x) in slot.returns.iter_mut().zip(rew.iter()) {
                        *r += *x as f64;
                    }
                    *term = slot.env.captured;
                    *trunc = !slot.env.captured && slot.env.steps >= slot.env.cfg.episode_length;
                    let mut stats = None;
                    if *term || *trunc {
                        let env = &slot.env;
                        stats = Some(EpisodeStats {
                            env: e,
                            seed: env.seed,
                            map: env.map().grid.name.clone(),
                            steps: env.steps,
                            captured: env.captured,
                            returns: slot.returns.clone(),
                            captor_path_len: env.path_len[..k].iter().sum::<f64>() / k as f64,
                        });
                        slot.write_obs(final_vec, final_patch, vl, obs);
                        if let Some(p) = potential {
                            *final_phi = p.of(&slot.env);
                        }
                        slot.episode += 1;
                        slot.begin(episode_seed(base, e, slot.episode))?;
                    }
                    slot.write_obs(vec, patch, vl, obs);
                    if let Some(p) = potential {
                        *phi = p.of(&slot.env);
                    }
                    Ok(stats)
                },
            )
            .collect();
        self.finished.clear();
        for r in results {
            if let Some(s) = r? {
                self.finished.push(s);
            }
        }
        Ok(())
    }
}

impl Slot {
    fn begin(&mut self, seed: u64) -> Result<(), PlacementError> {
        self.env.reset_state(seed)?;
        self.returns.iter_mut().for_each(|r| *r = 0.0);
        for (_, c) in &mut self.scripted {
            c.reset(&self.env, seed);
        }
        Ok(())
    }

    fn write_obs(&self, vec: &mut [f32], patch: &mut [u8], vl: usize, obs: bool) {
        for i in 0..self.env.num_agents() {
            let v = &mut vec[i * vl..(i + 1) * vl];
            if obs {
                self.env
                    .write_observation(i, v, &mut patch[i * PATCH_LEN..(i + 1) * PATCH_LEN]);
            } else {
                super::observe::write_vector(&self.env.robots, i, self.env.num_captors(), v);
            }
        }
    }
}
