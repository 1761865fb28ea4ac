//! The lookahead target: for each of its five actions it plays the next
//! `horizon` steps forward on a copy of the world, against a model of the
//! captors (the expert captors unless another team is named), itself
//! following the rule-based target after that first action. It plays the
//! action whose future is best: not caught, then the largest |ASZ| at the
//! horizon; caught, then as late as possible. Equal futures keep the
//! rule-based target's action, so it departs from it only where the
//! simulation says a departure pays.
//!
//! It measures how much room there is above the rule-based target before a
//! learner is trained to fill it, and can teach a learned target.

use super::rule_based::target_action;
use crate::asz::{AszFields, CoarseLattice};
use crate::env::{Action, Controller, Side, TrapEnv};

/// Map cells per side of the cells |ASZ| is scored on: 0.2 m, the shaping
/// potential's, so a decision's five scores cost about one fine ASZ.
pub const SCORE_COARSENING: usize = 4;

/// How one action's simulated future ended.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub(super) enum Future {
    /// Caught after this many steps (later is better).
    Caught(usize),
    /// Not caught within the horizon (or the episode ended); |ASZ| at its
    /// end, in coarse cells (larger is better).
    Free(usize),
}

/// How a simulated future ended, before its |ASZ| is scored (scoring
/// costs about one coarse ASZ, and a future whose area is never compared
/// need not pay it).
pub(super) enum End {
    Caught(usize),
    /// The world at the end of a future that was not caught.
    Free(Box<TrapEnv>),
}

/// What a future's simulation needs besides the world: the ASZ fields it
/// scores the horizon with and buffers for the actions, kept between
/// decisions so that a decision allocates little.
pub(super) struct Simulator {
    fields: AszFields,
    lattice: Option<CoarseLattice>,
    actions: Vec<Action>,
    batch_actions: Vec<Action>,
    rewards: Vec<f32>,
}

impl Simulator {
    pub(super) fn new() -> Simulator {
        Simulator {
            fields: AszFields::new(),
            lattice: None,
            actions: Vec::new(),
            batch_actions: Vec::new(),
            rewards: Vec::new(),
        }
    }

    /// Plays `first`, then the rule-based target, for `horizon` steps
    /// against `captors`, on a copy of `env`. A model with memory starts
    /// from its present memory and is left with it.
    pub(super) fn end(
        &mut self,
        env: &TrapEnv,
        first: Action,
        horizon: usize,
        captors: &mut dyn Controller,
    ) -> End {
        let memory = captors.memory();
        let end = self.simulate(env, first, horizon, captors);
        if let Some(memory) = &memory {
            captors.set_memory(memory);
        }
        end
    }

    /// `end` for each of `firsts`, in their order. A model with memory
    /// plays them in lockstep, every future from its present memory, with
    /// one `act_batch` per simulated step for all of them; it is left with
    /// its memory. A model without memory plays them one after the other,
    /// so its random draws (if any) come in the same order as `end`'s.
    pub(super) fn ends(
        &mut self,
        env: &TrapEnv,
        firsts: &[Action],
        horizon: usize,
        captors: &mut dyn Controller,
    ) -> Vec<End> {
        let Some(memory) = captors.memory() else {
            return firsts
                .iter()
                .map(|&first| self.simulate(env, first, horizon, captors))
                .collect();
        };
        let k = env.num_captors();
        let mut sims: Vec<TrapEnv> = firsts.iter().map(|_| env.clone()).collect();
        let mut memories = vec![memory.clone(); firsts.len()];
        let mut caught: Vec<Option<usize>> = vec![None; firsts.len()];
        let mut live: Vec<usize> = Vec::with_capacity(firsts.len());
        let mut live_memories: Vec<Vec<f32>> = Vec::with_capacity(firsts.len());
        self.actions.resize(k + 1, Action::Stop);
        self.rewards.resize(k + 1, 0.0);
        for step in 0..horizon {
            live.clear();
            live.extend((0..firsts.len()).filter(|&g| caught[g].is_none() && !sims[g].is_done()));
            if live.is_empty() {
                break;
            }
            live_memories.clear();
            live_memories.extend(live.iter().map(|&g| std::mem::take(&mut memories[g])));
            self.batch_actions.resize(live.len() * k, Action::Stop);
            {
                let views: Vec<&TrapEnv> = live.iter().map(|&g| &sims[g]).collect();
                captors.act_batch(
                    &views,
                    Side::Captors,
                    &mut live_memories,
                    &mut self.batch_actions,
                );
            }
            for (row, &g) in live.iter().enumerate() {
                memories[g] = std::mem::take(&mut live_memories[row]);
                let sim = &mut sims[g];
                self.actions[..k].copy_from_slice(&self.batch_actions[row * k..(row + 1) * k]);
                self.actions[k] = if step == 0 {
                    firsts[g]
                } else {
                    target_action(sim)
                };
                sim.step_state(&self.actions, &mut self.rewards);
                if sim.captured {
                    caught[g] = Some(step);
                }
            }
        }
        captors.set_memory(&memory);
        sims.into_iter()
            .zip(caught)
            .map(|(sim, caught)| match caught {
                Some(step) => End::Caught(step),
                None => End::Free(Box::new(sim)),
            })
            .collect()
    }

    /// A future's worth: when it was caught, or |ASZ| at its end.
    pub(super) fn score(&mut self, end: &End) -> Future {
        let sim = match end {
            End::Caught(step) => return Future::Caught(*step),
            End::Free(sim) => sim,
        };
        let map = sim.map();
        if !self
            .lattice
            .as_ref()
            .is_some_and(|l| l.covers(map, SCORE_COARSENING))
        {
            self.lattice = Some(CoarseLattice::new(map, SCORE_COARSENING));
        }
        let (captors, target) = sim.asz_sources();
        let lattice = self.lattice.as_ref().expect("set above");
        Future::Free(self.fields.asz_cells(lattice, target, &captors))
    }

    /// Steps a model with memory once on the real state, as the team it
    /// stands for would have stepped, so that its next futures start from
    /// the real game's memory. A model without memory is left alone (its
    /// random draws, if any, as they were).
    pub(super) fn observe(&mut self, env: &TrapEnv, captors: &mut dyn Controller) {
        if captors.has_memory() {
            let k = env.num_captors();
            self.actions.resize(k + 1, Action::Stop);
            captors.act(env, Side::Captors, &mut self.actions[..k]);
        }
    }

    fn simulate(
        &mut self,
        env: &TrapEnv,
        first: Action,
        horizon: usize,
        captors: &mut dyn Controller,
    ) -> End {
        let k = env.num_captors();
        let mut sim = env.clone();
        self.actions.resize(k + 1, Action::Stop);
        self.rewards.resize(k + 1, 0.0);
        for step in 0..horizon {
            if sim.is_done() {
                break;
            }
            captors.act(&sim, Side::Captors, &mut self.actions[..k]);
            self.actions[k] = if step == 0 {
                first
            } else {
                target_action(&sim)
            };
            sim.step_state(&self.actions, &mut self.rewards);
            if sim.captured {
                return End::Caught(step);
            }
        }
        End::Free(Box::new(sim))
    }
}

pub struct Lookahead {
    horizon: usize,
    captors: Box<dyn Controller>,
    sim: Simulator,
}

impl Lookahead {
    /// The longest horizon accepted, in steps.
    pub const MAX_HORIZON: usize = 100;

    /// A lookahead target of `horizon` steps (1 to `MAX_HORIZON`) against
    /// `captors`, the model of the team it meets.
    pub fn new(horizon: usize, captors: Box<dyn Controller>) -> Lookahead {
        assert!(
            (1..=Self::MAX_HORIZON).contains(&horizon),
            "lookahead horizon {horizon} outside 1..={}",
            Self::MAX_HORIZON
        );
        Lookahead {
            horizon,
            captors,
            sim: Simulator::new(),
        }
    }

    /// The target's action in `env`'s state.
    pub fn target_action(&mut self, env: &TrapEnv) -> Action {
        let rule = target_action(env);
        let mut firsts = vec![rule];
        firsts.extend(Action::ALL.into_iter().filter(|&a| a != rule));
        let ends = self
            .sim
            .ends(env, &firsts, self.horizon, self.captors.as_mut());
        let mut best: Option<(Future, Action)> = None;
        for (end, action) in ends.iter().zip(firsts) {
            let future = self.sim.score(end);
            // Ties keep the earlier move, the rule's first.
            if best.is_none_or(|(b, _)| future > b) {
                best = Some((future, action));
            }
        }
        self.sim.observe(env, self.captors.as_mut());
        best.expect("five moves").1
    }

    /// The model of the captors it plans against.
    pub fn model(&self) -> &dyn Controller {
        self.captors.as_ref()
    }
}

impl Controller for Lookahead {
    fn name(&self) -> String {
        format!("lookahead:{}", self.horizon)
    }
    fn reset(&mut self, env: &TrapEnv, seed: u64) {
        self.captors.reset(env, seed);
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        match side {
            Side::Target => out[0] = self.target_action(env),
            // The catalogue refuses it for captors before an episode starts.
            Side::Captors => panic!("the lookahead controller plays the target only"),
        }
    }
}
