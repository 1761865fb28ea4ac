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

/// What a future's simulation needs besides the world: the ASZ fields it
/// scores the horizon with and buffers for the actions, kept between
/// decisions so that a decision allocates nothing.
pub(super) struct Simulator {
    fields: AszFields,
    lattice: Option<CoarseLattice>,
    actions: Vec<Action>,
    rewards: Vec<f32>,
}

impl Simulator {
    pub(super) fn new() -> Simulator {
        Simulator {
            fields: AszFields::new(),
            lattice: None,
            actions: Vec::new(),
            rewards: Vec::new(),
        }
    }

    /// Plays `first`, then the rule-based target, for `horizon` steps
    /// against `captors`, on a copy of `env`. A model with memory starts
    /// from its present memory and is left with it.
    pub(super) fn future(
        &mut self,
        env: &TrapEnv,
        first: Action,
        horizon: usize,
        captors: &mut dyn Controller,
    ) -> Future {
        let memory = captors.memory();
        let future = self.simulate(env, first, horizon, captors);
        if let Some(memory) = &memory {
            captors.set_memory(memory);
        }
        future
    }

    /// Steps a model with memory once on the real state, as the team it
    /// stands for would have stepped, so that its next futures start from
    /// the real game's memory. A model without memory is left alone (its
    /// random draws, if any, as they were).
    pub(super) fn observe(&mut self, env: &TrapEnv, captors: &mut dyn Controller) {
        if captors.memory().is_some() {
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
    ) -> Future {
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
                return Future::Caught(step);
            }
        }
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
        let mut best = (self.future(env, rule), rule);
        for action in Action::ALL {
            if action == rule {
                continue;
            }
            let future = self.future(env, action);
            if future > best.0 {
                best = (future, action);
            }
        }
        self.sim.observe(env, self.captors.as_mut());
        best.1
    }

    /// The model of the captors it plans against.
    pub fn model(&self) -> &dyn Controller {
        self.captors.as_ref()
    }

    fn future(&mut self, env: &TrapEnv, first: Action) -> Future {
        self.sim
            .future(env, first, self.horizon, self.captors.as_mut())
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
