//! The other side's networks a league learner plays against: loaded from
//! the pool (checked against the store's sha256), cached, stacked per
//! architecture, and run in one batched pass per step over the worlds that
//! play them. Heuristic opponents play inside the vector env and never
//! come here.

use crate::error::{IoResultExt, LeagueError, Result};
use crate::store::Player;
use rand_chacha::ChaCha8Rng;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use t2e_core::env::{Action, Side, VecEnv};
use t2e_learners::learn::acting::{gather_worlds, sample};
use t2e_learners::learn::teacher::Teacher;
use t2e_learners::nn::checkpoint::DoesNotFit;
use t2e_learners::nn::prior::{add_prior, target_hint};
use t2e_learners::nn::stacked::{PreparedActor, StackedActors};
use t2e_learners::nn::PolicySnapshot;
use tch::{Device, Kind as TKind, Tensor};

/// A loaded opponent network.
struct Loaded {
    snapshot: Arc<PolicySnapshot>,
    /// The weights laid out for stacking with the other opponents in play.
    prepared: PreparedActor,
    last_used: u64,
}

/// Opponents in play that share one architecture, stacked for one pass.
struct Stack {
    ids: Vec<i64>,
    actors: StackedActors,
}

/// Who plays the other side in one world, this episode.
#[derive(Clone, Debug)]
pub struct WorldOpponent {
    pub player: i64,
    /// Some(player) when a network plays (batched here), None for a
    /// heuristic scripted inside the vector env.
    pub network: Option<i64>,
    /// Recurrent state of the network's robots in this world.
    pub hidden: Vec<f32>,
    pub speed: f64,
}

/// The opponent networks in play and their cost.
pub struct OpponentNets {
    /// The side the opponents play.
    side: Side,
    /// Networks kept loaded at most.
    capacity: usize,
    /// Opponents act greedily instead of sampling.
    greedy: bool,
    cache: HashMap<i64, Loaded>,
    /// Rebuilt only when the set of network opponents in play changes.
    stacks: Vec<Stack>,
    tick: u64,
    /// Per world, the planner a target opponent's prior leans on
    /// (`NetConfig::prior_teacher`) and the member it serves there: a
    /// planner keeps per-episode state, so each world has its own.
    planners: HashMap<usize, (i64, Teacher)>,
    /// Time in opponent networks (gather, forward, sampling) and the robot
    /// rows they acted for: the cost per row of batched opponent inference.
    pub seconds: f64,
    pub rows: u64,
}

impl OpponentNets {
    pub fn new(side: Side, capacity: usize, greedy: bool) -> OpponentNets {
        OpponentNets {
            side,
            capacity,
            greedy,
            cache: HashMap::new(),
            stacks: Vec::new(),
            tick: 0,
            planners: HashMap::new(),
            seconds: 0.0,
            rows: 0,
        }
    }

    /// Keeps one stack per architecture over exactly the network opponents in
    /// play (`ids`, sorted), restacking only the ones whose members changed.
    fn restack(&mut self, ids: Vec<i64>) -> Result<()> {
        let mut parts: Vec<Vec<i64>> = Vec::new();
        for id in ids {
            let p = &self
                .cache
                .get(&id)
                .ok_or_else(|| LeagueError::Pool("opponent network not loaded".into()))?
                .prepared;
            match parts
                .iter_mut()
                .find(|ids| self.cache[&ids[0]].prepared.same_shape(p))
            {
                Some(part) => part.push(id),
                None => parts.push(vec![id]),
            }
        }
        let mut old = std::mem::take(&mut self.stacks);
        for part in parts {
            if let Some(i) = old.iter().position(|s| s.ids == part) {
                self.stacks.push(old.swap_remove(i));
                continue;
            }
            let prepared: Vec<&PreparedActor> =
                part.iter().map(|id| &self.cache[id].prepared).collect();
            let actors = StackedActors::new(&prepared)?;
            self.stacks.push(Stack { ids: part, actors });
        }
        Ok(())
    }

    /// Loads (or finds in the cache) a member's network, its files under
    /// `root` checked against the sha256 the store recorded; returns its
    /// hidden size. A full cache evicts the least recently used network
    /// that no world in `in_use` plays.
    pub fn load(&mut self, root: &Path, member: &Player, in_use: &[i64]) -> Result<usize> {
        self.tick += 1;
        if let Some(l) = self.cache.get_mut(&member.id) {
            l.last_used = self.tick;
            return Ok(l.prepared.net.hidden as usize);
        }
        let (rel, meta_sha) = member
            .checkpoint
            .clone()
            .ok_or_else(|| LeagueError::NoWeights(format!("{} has no checkpoint", member.name)))?;
        let dir = root.join(&rel);
        let got = t2e_core::util::sha256_file(&dir.join("meta.json"))
            .io_context(|| format!("{}: meta.json missing", dir.display()))?;
        if got != meta_sha {
            return Err(LeagueError::Corrupt(format!(
                "{}: meta.json does not match the sha256 the store recorded",
                dir.display()
            )));
        }
        let snapshot = Arc::new(PolicySnapshot::load_recorded(&dir, self.side, &meta_sha)?);
        let (vs, actor) = snapshot.build_actor(Device::Cpu)?;
        if self.cache.len() >= self.capacity {
            if let Some(evict) = self
                .cache
                .iter()
                .filter(|(id, _)| !in_use.contains(id))
                .min_by_key(|(_, l)| l.last_used)
                .map(|(id, _)| *id)
            {
                self.cache.remove(&evict);
            }
        }
        let hidden = actor.hidden as usize;
        let prepared = PreparedActor::new(&actor, &snapshot.meta.net, snapshot.meta.vector_len());
        drop((vs, actor));
        self.cache.insert(
            member.id,
            Loaded {
                snapshot,
                prepared,
                last_used: self.tick,
            },
        );
        Ok(hidden)
    }

    /// Acts for the opponents' robots in every world a network plays
    /// (writing their entries of `actions`), one stacked forward pass per
    /// architecture, and carries each world's recurrent state.
    // Long on purpose: the per-step hot path of a league learner: one stacked forward per architecture over every world, holding the worlds' recurrent state and the action buffer at once.
    pub fn act(
        &mut self,
        venv: &VecEnv,
        worlds: &mut [WorldOpponent],
        num_captors: usize,
        rng: &mut ChaCha8Rng,
        actions: &mut [Action],
    ) -> Result<()> {
        let other = self.side;
        let k = num_captors;
        let na = k + 1;
        let team = other.agents(k).len();
        let mut groups: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
        for (e, w) in worlds.iter().enumerate() {
            if let Some(id) = w.network {
                groups.entry(id).or_default().push(e);
            }
        }
        let started = Instant::now();
        self.restack(groups.keys().copied().collect())?;
        for stack in &self.stacks {
            let first = &self.cache[&stack.ids[0]];
            let net = &first.snapshot.meta.net;
            // The stacked network reads the env's vectors as they are.
            if net.sight != venv.cfg.sight {
                return Err(LeagueError::DoesNotFit {
                    checkpoint: first.snapshot.dir.clone(),
                    cause: DoesNotFit::Sight {
                        trained: net.sight,
                        env: venv.cfg.sight,
                    },
                });
            }
            let (g, h) = (stack.ids.len(), stack.actors.hidden as usize);
            let (vl, pl) = (venv.cfg.vector_len(), net.input_len());
            // Each opponent's rows padded to the most any of them plays.
            let r = stack
                .ids
                .iter()
                .map(|id| groups[id].len() * team)
                .max()
                .unwrap_or(0);
            let mut vectors = vec![0f32; g * r * vl];
            let mut patches = vec![0u8; g * r * pl];
            let mut hidden = vec![0f32; g * r * h];
            for (i, id) in stack.ids.iter().enumerate() {
                let playing = &groups[id];
                let rows = playing.len() * team;
                gather_worlds(
                    venv,
                    &venv.vectors,
                    &venv.patches,
                    playing,
                    other,
                    net,
                    &mut vectors[i * r * vl..(i * r + rows) * vl],
                    &mut patches[i * r * pl..(i * r + rows) * pl],
                );
                for (w, &e) in playing.iter().enumerate() {
                    let at = (i * r + w * team) * h;
                    hidden[at..at + team * h].copy_from_slice(&worlds[e].hidden);
                }
            }
            let side = net.input_side() as i64;
            let (g64, r64) = (g as i64, r as i64);
            let p = Tensor::from_slice(&patches).view([g64, r64, side, side]);
            let v = Tensor::from_slice(&vectors).view([g64, r64, vl as i64]);
            let h_in = Tensor::from_slice(&hidden).view([g64, r64, h as i64]);
            let (logits, h_out) = tch::no_grad(|| stack.actors.step(&p, &v, &h_in));
            // A stack shares one net config, so one prior; only a target
            // (one robot per world) has one.
            let logits = if net.heuristic_prior > 0.0 && team == 1 {
                let mut hints = vec![0i64; g * r];
                for (i, id) in stack.ids.iter().enumerate() {
                    for (w, &e) in groups[id].iter().enumerate() {
                        hints[i * r + w] = match &net.prior_teacher {
                            Some(planner) => {
                                planner_hint(&mut self.planners, e, *id, planner, venv)?
                            }
                            None => target_hint(venv.env(e)),
                        };
                    }
                }
                let hints = Tensor::from_slice(&hints).view([g64, r64]);
                add_prior(logits, &hints, net.heuristic_prior)
            } else {
                logits
            };
            let n = g * r;
            let mut chosen = vec![0i64; n];
            if self.greedy {
                logits.argmax(2, false).copy_data(&mut chosen, n);
            } else {
                let probs = logits.softmax(-1, TKind::Float);
                let mut pr = vec![0f32; n * Action::COUNT];
                probs.copy_data(&mut pr, n * Action::COUNT);
                for (i, id) in stack.ids.iter().enumerate() {
                    for row in i * r..i * r + groups[id].len() * team {
                        chosen[row] =
                            sample(&pr[row * Action::COUNT..(row + 1) * Action::COUNT], rng) as i64;
                    }
                }
            }
            let mut h_new = vec![0f32; n * h];
            h_out.copy_data(&mut h_new, n * h);
            for (i, id) in stack.ids.iter().enumerate() {
                for (w, &e) in groups[id].iter().enumerate() {
                    let row = i * r + w * team;
                    worlds[e]
                        .hidden
                        .copy_from_slice(&h_new[row * h..(row + team) * h]);
                    for (j, agent) in other.agents(k).enumerate() {
                        actions[e * na + agent] = Action::from_index(chosen[row + j] as usize);
                    }
                }
                self.rows += (groups[id].len() * team) as u64;
            }
        }
        self.seconds += started.elapsed().as_secs_f64();
        Ok(())
    }
}

/// The move of the planner that member `member`'s prior leans on, in world
/// `world`: that world's planner, built afresh when another member played
/// there last.
fn planner_hint(
    planners: &mut HashMap<usize, (i64, Teacher)>,
    world: usize,
    member: i64,
    planner: &str,
    venv: &VecEnv,
) -> Result<i64> {
    if planners.get(&world).is_none_or(|(m, _)| *m != member) {
        let spec = t2e_learners::controllers::prior_teacher(planner)?;
        let teacher = Teacher::per_world(&spec, 1)?
            .pop()
            .expect("one world, one planner");
        planners.insert(world, (member, teacher));
    }
    let (_, teacher) = planners.get_mut(&world).expect("inserted above");
    Ok(teacher
        .label(venv.env(world), venv.episode_index(world))
        .index() as i64)
}
