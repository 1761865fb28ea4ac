//! `TrapEnv`: one world of the environment, its reset and step, the
//! rewards of spec §5 and what a step reports.

use super::action::Action;
use super::config::{self, CaptureRule, EnvConfig, RobotSpec};
use super::observe::{self, PATCH_LEN};
use super::physics::{self, dist, Robot};
use super::placement::{self, PlacementError};
use super::sight::Sight;
use crate::asz::{strict_capture_cells, AszFields, Source};
use crate::error::{ConfigError, EnvError};
use crate::map::PreparedMap;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

/// One agent's observation.
#[derive(Clone, Debug, PartialEq)]
pub struct Observation {
    /// 5 + 5 K numbers (spec §5), then the sight's if it is on.
    pub vector: Vec<f32>,
    /// 48 x 48, row-major, 1 = obstacle.
    pub patch: Vec<u8>,
}

/// Per-step facts beside the rewards.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepInfo {
    pub captured: bool,
    /// Per agent: hit a wall this step.
    pub collided: Vec<bool>,
    /// Per captor: touching the target.
    pub contact: Vec<bool>,
    /// |ASZ| in cells, when the strict rule computed it this step.
    pub asz_cells: Option<usize>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct StepResult {
    pub observations: Vec<Observation>,
    pub rewards: Vec<f32>,
    pub terminations: Vec<bool>,
    pub truncations: Vec<bool>,
    pub info: StepInfo,
}

/// Rewards of one step (spec §6), per agent, captors first.
pub fn rewards(
    num_captors: usize,
    dist_change: &[f64],
    contact: &[bool],
    collided: &[bool],
    captured: bool,
    out: &mut [f32],
) {
    let k = num_captors as f64;
    let mut mean_change = 0.0;
    let mut contacts = 0usize;
    for i in 0..num_captors {
        let mut r = -50.0 * dist_change[i] - 0.4;
        if contact[i] {
            r += 5.0;
            contacts += 1;
        }
        if captured {
            r += 200.0;
        }
        if collided[i] {
            r -= 1.0;
        }
        out[i] = r as f32;
        mean_change += dist_change[i] / k;
    }
    let mut r = 50.0 * mean_change - 5.0 / k * contacts as f64 - 0.4;
    if captured {
        r -= 200.0;
    }
    if collided[num_captors] {
        r -= 1.0;
    }
    out[num_captors] = r as f32;
}

/// One world: a map, K captors and a target.
pub struct TrapEnv {
    pub cfg: EnvConfig,
    maps: Arc<Vec<Arc<PreparedMap>>>,
    map: Arc<PreparedMap>,
    pub robots: Vec<Robot>,
    specs: Vec<RobotSpec>,
    /// Steps taken in this episode.
    pub steps: u32,
    /// Distance travelled per robot in this episode (m).
    pub path_len: Vec<f64>,
    prev_dist: Vec<f64>,
    pub captured: bool,
    /// Seed of the current episode.
    pub seed: u64,
    travelled: Vec<f64>,
    dist_change: Vec<f64>,
    contact: Vec<bool>,
    collided: Vec<bool>,
    asz_fields: Option<AszFields>,
}

/// A copy of the world's state (a controller's lookahead plays on one);
/// the ASZ's buffers are not copied. It names every field, so a field
/// added to `TrapEnv` cannot be left out of the copy.
impl Clone for TrapEnv {
    fn clone(&self) -> TrapEnv {
        let TrapEnv {
            cfg,
            maps,
            map,
            robots,
            specs,
            steps,
            path_len,
            prev_dist,
            captured,
            seed,
            travelled,
            dist_change,
            contact,
            collided,
            asz_fields: _,
        } = self;
        TrapEnv {
            cfg: cfg.clone(),
            maps: maps.clone(),
            map: map.clone(),
            robots: robots.clone(),
            specs: specs.clone(),
            steps: *steps,
            path_len: path_len.clone(),
            prev_dist: prev_dist.clone(),
            captured: *captured,
            seed: *seed,
            travelled: travelled.clone(),
            dist_change: dist_change.clone(),
            contact: contact.clone(),
            collided: collided.clone(),
            asz_fields: None,
        }
    }
}

impl TrapEnv {
    /// A world over a set of maps; each episode picks one from its seed.
    pub fn new(cfg: EnvConfig, maps: Arc<Vec<Arc<PreparedMap>>>) -> Result<TrapEnv, EnvError> {
        cfg.validate()?;
        if maps.is_empty() {
            return Err(EnvError::NoMaps);
        }
        let n = cfg.num_agents();
        let mut specs = vec![cfg.captor_spec(); cfg.num_captors];
        specs.push(cfg.target_spec());
        Ok(TrapEnv {
            map: maps[0].clone(),
            maps,
            robots: vec![Robot::default(); n],
            specs,
            steps: 0,
            path_len: vec![0.0; n],
            prev_dist: vec![0.0; cfg.num_captors],
            captured: false,
            seed: 0,
            travelled: vec![0.0; n],
            dist_change: vec![0.0; cfg.num_captors],
            contact: vec![false; cfg.num_captors],
            collided: vec![false; n],
            asz_fields: None,
            cfg,
        })
    }

    pub fn num_agents(&self) -> usize {
        self.cfg.num_agents()
    }

    pub fn num_captors(&self) -> usize {
        self.cfg.num_captors
    }

    /// Index of the target among the agents.
    pub fn target_index(&self) -> usize {
        self.cfg.num_captors
    }

    pub fn agent_names(&self) -> Vec<String> {
        let mut names: Vec<String> = (0..self.cfg.num_captors)
            .map(|i| format!("captor_{i}"))
            .collect();
        names.push("target".into());
        names
    }

    /// The maps episodes draw from (uniformly; a map listed twice is drawn
    /// twice as often).
    pub fn maps(&self) -> &Arc<Vec<Arc<PreparedMap>>> {
        &self.maps
    }

    pub fn map(&self) -> &Arc<PreparedMap> {
        &self.map
    }

    pub fn target(&self) -> &Robot {
        &self.robots[self.cfg.num_captors]
    }

    pub fn captors(&self) -> &[Robot] {
        &self.robots[..self.cfg.num_captors]
    }

    /// Changes the robots' top speeds from the next step on (the league's
    /// curriculum sets the target's speed per episode).
    pub fn set_speeds(&mut self, captor_speed: f64, target_speed: f64) -> Result<(), ConfigError> {
        let cfg = EnvConfig {
            captor_speed,
            target_speed,
            ..self.cfg.clone()
        };
        cfg.validate()?;
        let k = cfg.num_captors;
        for s in &mut self.specs[..k] {
            *s = cfg.captor_spec();
        }
        self.specs[k] = cfg.target_spec();
        self.cfg = cfg;
        Ok(())
    }

    pub fn spec(&self, agent: usize) -> RobotSpec {
        self.specs[agent]
    }

    pub fn is_done(&self) -> bool {
        self.captured || self.steps >= self.cfg.episode_length
    }

    /// Starts an episode: map and placement from `seed` alone.
    pub fn reset(&mut self, seed: u64) -> Result<Vec<Observation>, PlacementError> {
        self.reset_state(seed)?;
        Ok(self.observations())
    }

    /// `reset` without building observations.
    pub fn reset_state(&mut self, seed: u64) -> Result<(), PlacementError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let map = rng.gen_range(0..self.maps.len());
        let robots = placement::place(&self.maps[map], self.cfg.num_captors, &mut rng)?;
        self.set_robots(map, robots);
        self.seed = seed;
        Ok(())
    }

    /// Places robots by hand (tests, renders of set-ups); starts a new episode.
    pub fn set_robots(&mut self, map_index: usize, robots: Vec<Robot>) {
        assert_eq!(robots.len(), self.num_agents());
        self.map = self.maps[map_index].clone();
        self.robots = robots;
        self.steps = 0;
        self.captured = false;
        self.path_len.iter_mut().for_each(|p| *p = 0.0);
        let t = self.target().pos;
        for i in 0..self.cfg.num_captors {
            self.prev_dist[i] = dist(self.robots[i].pos, t);
        }
    }

    /// Advances one step; writes rewards into `rewards_out` (one per agent).
    /// Returns whether the episode ended by capture.
    pub fn step_state(&mut self, actions: &[Action], rewards_out: &mut [f32]) -> StepInfo {
        assert_eq!(actions.len(), self.num_agents(), "one action per agent");
        let drive = self.cfg.drive_force;
        physics::step(
            &self.map,
            &mut self.robots,
            &self.specs,
            actions,
            drive,
            &mut self.travelled,
        );
        self.steps += 1;
        for (p, t) in self.path_len.iter_mut().zip(&self.travelled) {
            *p += t;
        }
        let k = self.cfg.num_captors;
        let target = self.robots[k].pos;
        for i in 0..k {
            let d = dist(self.robots[i].pos, target);
            self.dist_change[i] = d - self.prev_dist[i];
            self.prev_dist[i] = d;
            self.contact[i] = d < config::CONTACT_DIST;
        }
        for (c, r) in self.collided.iter_mut().zip(&self.robots) {
            *c = r.collided;
        }
        let mut asz_cells = None;
        self.captured = match self.cfg.capture_rule {
            CaptureRule::Fast => physics::target_is_trapped(&self.map, target, &self.robots[..k]),
            CaptureRule::Strict => {
                let cells = self.asz_cells();
                asz_cells = Some(cells);
                cells as f64 <= strict_capture_cells(config::RADIUS)
            }
        };
        rewards(
            k,
            &self.dist_change,
            &self.contact,
            &self.collided,
            self.captured,
            rewards_out,
        );
        StepInfo {
            captured: self.captured,
            collided: self.collided.clone(),
            contact: self.contact.clone(),
            asz_cells,
        }
    }

    /// The PettingZoo-style step.
    pub fn step(&mut self, actions: &[Action]) -> StepResult {
        let mut rewards = vec![0f32; self.num_agents()];
        let info = self.step_state(actions, &mut rewards);
        let terminated = self.captured;
        let truncated = !terminated && self.steps >= self.cfg.episode_length;
        StepResult {
            observations: self.observations(),
            rewards,
            terminations: vec![terminated; self.num_agents()],
            truncations: vec![truncated; self.num_agents()],
            info,
        }
    }

    /// Observation of agent `i` into caller buffers (vector: 5 + 5 K and
    /// the env's sight, patch: 48 x 48).
    pub fn write_observation(&self, i: usize, vector: &mut [f32], patch: &mut [u8]) {
        self.write_observation_with(self.cfg.sight, i, vector, patch);
    }

    /// Observation of agent `i` with `sight` rather than the env's own: a
    /// policy that carries its inputs with it (a checkpoint) sees what it
    /// was trained on in any env. `vector` holds 5 + 5 K + `sight.len()`.
    pub fn write_observation_with(
        &self,
        sight: Sight,
        i: usize,
        vector: &mut [f32],
        patch: &mut [u8],
    ) {
        let spec = 5 + 5 * self.cfg.num_captors;
        debug_assert_eq!(vector.len(), spec + sight.len());
        observe::write_vector(&self.robots, i, self.cfg.num_captors, vector);
        sight.write(
            &self.map,
            &self.robots,
            i,
            self.cfg.num_captors,
            &mut vector[spec..],
        );
        let r = &self.robots[i];
        observe::write_patch(&self.map, r.pos, r.theta, patch);
    }

    pub fn observations(&self) -> Vec<Observation> {
        (0..self.num_agents())
            .map(|i| {
                let mut o = Observation {
                    vector: vec![0.0; self.cfg.vector_len()],
                    patch: vec![0; PATCH_LEN],
                };
                self.write_observation(i, &mut o.vector, &mut o.patch);
                o
            })
            .collect()
    }

    /// Arrival-time sources of the captors and of the target.
    pub fn asz_sources(&self) -> (Vec<Source>, Source) {
        let captors = self
            .captors()
            .iter()
            .map(|r| Source {
                pos: r.pos,
                speed: self.cfg.captor_speed,
            })
            .collect();
        let target = Source {
            pos: self.target().pos,
            speed: self.cfg.target_speed,
        };
        (captors, target)
    }

    /// |ASZ| (cells) of the current state.
    pub fn asz_cells(&mut self) -> usize {
        let (captors, target) = self.asz_sources();
        let fields = self.asz_fields.get_or_insert_with(AszFields::new);
        fields.asz_cells(&*self.map, target, &captors)
    }
}
