//! The robust lookahead target: the lookahead target (lookahead.rs) planned
//! against several captor models at once, departing from the rule-based
//! target only where every model agrees that departing pays.
//!
//! Planned against one model, the lookahead target learns that model's
//! blind spots: a move the model fails to punish is one another team
//! punishes. So here each of the five moves is simulated `horizon` steps
//! against **each** model, and a move's worth is its worst future over the
//! models. The rule-based move is kept unless some model catches it within
//! the horizon; it is then replaced only by a move that no model catches,
//! the one whose smallest |ASZ| at the horizon over the models is largest.
//! Where no move is free under every model, the rule-based move stays: a
//! departure the models disagree on is the kind that did not carry over to
//! unseen teams. This is safe policy improvement over a baseline (SPIBB):
//! the baseline's action wherever the evidence for another is not
//! unanimous.

use super::lookahead::{End, Future, Lookahead, Simulator};
use super::rule_based::target_action;
use crate::env::{Action, Controller, Side, TrapEnv};

pub struct RobustLookahead {
    horizon: usize,
    models: Vec<Box<dyn Controller>>,
    sim: Simulator,
    decisions: u64,
    contested: u64,
    departures: u64,
}

impl RobustLookahead {
    /// The most captor models one target plans against.
    pub const MAX_MODELS: usize = 8;

    /// A robust lookahead target of `horizon` steps (1 to
    /// `Lookahead::MAX_HORIZON`) against every team of `models` (1 to
    /// `MAX_MODELS`).
    pub fn new(horizon: usize, models: Vec<Box<dyn Controller>>) -> RobustLookahead {
        assert!(
            (1..=Lookahead::MAX_HORIZON).contains(&horizon),
            "robust horizon {horizon} outside 1..={}",
            Lookahead::MAX_HORIZON
        );
        assert!(
            (1..=Self::MAX_MODELS).contains(&models.len()),
            "robust lookahead with {} models, not 1 to {}",
            models.len(),
            Self::MAX_MODELS
        );
        RobustLookahead {
            horizon,
            models,
            sim: Simulator::new(),
            decisions: 0,
            contested: 0,
            departures: 0,
        }
    }

    /// Decisions taken since it was made, and how many of them departed
    /// from the rule-based target's move.
    pub fn departures(&self) -> (u64, u64) {
        (self.decisions, self.departures)
    }

    /// Decisions since it was made in which some model caught the
    /// rule-based move, so that the other moves were simulated.
    pub fn contested(&self) -> u64 {
        self.contested
    }

    /// The captor models it plans against.
    pub fn models(&self) -> &[Box<dyn Controller>] {
        &self.models
    }

    /// The target's action in `env`'s state.
    pub fn target_action(&mut self, env: &TrapEnv) -> Action {
        let action = self.choose(env);
        for model in &mut self.models {
            self.sim.observe(env, model.as_mut());
        }
        action
    }

    fn choose(&mut self, env: &TrapEnv) -> Action {
        self.decisions += 1;
        let rule = target_action(env);
        let RobustLookahead {
            horizon,
            models,
            sim,
            ..
        } = self;
        let mut moves = vec![rule];
        moves.extend(Action::ALL.into_iter().filter(|&a| a != rule));
        let alternatives = &moves[1..];
        // A model with memory (a learned team) plays all five moves in
        // lockstep when it is first asked: one forward for five rows costs
        // about what one for one row does, and the alternatives are at hand
        // if the rule's move is caught.
        let mut batched: Vec<Option<Vec<End>>> = models.iter().map(|_| None).collect();
        let mut rule_caught = false;
        for (model, batch) in models.iter_mut().zip(batched.iter_mut()) {
            // The rule's move only needs to be free: its |ASZ| is never compared.
            let end = if model.has_memory() {
                let mut ends = sim.ends(env, &moves, *horizon, model.as_mut());
                let rule_end = ends.remove(0);
                *batch = Some(ends);
                rule_end
            } else {
                sim.end(env, rule, *horizon, model.as_mut())
            };
            if matches!(end, End::Caught(_)) {
                rule_caught = true;
                break;
            }
        }
        if !rule_caught {
            return rule;
        }
        self.contested += 1;
        let mut best: Option<(usize, Action)> = None;
        for (i, &action) in alternatives.iter().enumerate() {
            let area = Self::worst(sim, models, &mut batched, env, *horizon, alternatives, i);
            if let Some(area) = area {
                if best.is_none_or(|(b, _)| area > b) {
                    best = Some((area, action));
                }
            }
        }
        match best {
            Some((_, action)) => {
                self.departures += 1;
                action
            }
            None => rule,
        }
    }

    /// The smallest |ASZ| (coarse cells) at the horizon over the models if
    /// no model catches `alternatives[i]`, else None. Models without memory
    /// are asked move by move, model by model, as the early exit leaves
    /// them, so their random draws come in a fixed order.
    fn worst(
        sim: &mut Simulator,
        models: &mut [Box<dyn Controller>],
        batched: &mut [Option<Vec<End>>],
        env: &TrapEnv,
        horizon: usize,
        alternatives: &[Action],
        i: usize,
    ) -> Option<usize> {
        let mut worst = usize::MAX;
        for (model, batch) in models.iter_mut().zip(batched.iter_mut()) {
            let end = if model.has_memory() {
                let ends = batch
                    .get_or_insert_with(|| sim.ends(env, alternatives, horizon, model.as_mut()));
                std::mem::replace(&mut ends[i], End::Caught(0))
            } else {
                sim.end(env, alternatives[i], horizon, model.as_mut())
            };
            match sim.score(&end) {
                Future::Caught(_) => return None,
                Future::Free(area) => worst = worst.min(area),
            }
        }
        Some(worst)
    }
}

impl Controller for RobustLookahead {
    fn name(&self) -> String {
        format!("robust:{}", self.horizon)
    }
    fn reset(&mut self, env: &TrapEnv, seed: u64) {
        for model in &mut self.models {
            model.reset(env, seed);
        }
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        match side {
            Side::Target => out[0] = self.target_action(env),
            // The catalogue refuses it for captors before an episode starts.
            Side::Captors => panic!("the robust lookahead controller plays the target only"),
        }
    }
}
