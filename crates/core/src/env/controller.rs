//! The one interface every robot brain implements, per side: rule-based
//! robots, random ones, and (with the learners) network checkpoints.

use super::action::Action;
use super::trap_env::TrapEnv;
use std::ops::Range;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Captors,
    Target,
}

impl Side {
    pub fn name(self) -> &'static str {
        match self {
            Side::Captors => "captors",
            Side::Target => "target",
        }
    }

    pub fn other(self) -> Side {
        match self {
            Side::Captors => Side::Target,
            Side::Target => Side::Captors,
        }
    }

    /// The agent indices of this side in an env with `num_captors` captors
    /// (captors first, the target last).
    pub fn agents(self, num_captors: usize) -> Range<usize> {
        match self {
            Side::Captors => 0..num_captors,
            Side::Target => num_captors..num_captors + 1,
        }
    }
}

pub trait Controller: Send {
    fn name(&self) -> String;
    /// Called after every reset; `seed` is the episode's seed, for controllers
    /// that draw random numbers (same seed, same episode).
    fn reset(&mut self, _env: &TrapEnv, _seed: u64) {}
    /// Chooses the actions of `side`'s robots; `out` has one slot per robot of the side.
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]);
    /// What it carries from the episode's earlier steps into its next
    /// action (a recurrent policy's hidden state), as plain numbers; None
    /// when its actions depend on the present state alone (random draws
    /// aside). A planner that simulates futures with it as a model of a
    /// team starts every future from this memory and puts it back after,
    /// so the model remembers the real game, not the futures it imagined.
    fn memory(&self) -> Option<Vec<f32>> {
        None
    }
    /// Puts back what `memory` returned.
    fn set_memory(&mut self, _memory: &[f32]) {}
    /// Whether `memory` is Some, without copying it out: planners ask
    /// this of every model at every decision.
    fn has_memory(&self) -> bool {
        self.memory().is_some()
    }
    /// Chooses `side`'s actions in several games at once, game `g` from
    /// `memories[g]` (as `memory` gives it), which it leaves holding that
    /// game's memory after the step; `out` holds the games' slots one game
    /// after another. A planner plays its futures with it in lockstep, so
    /// that a network runs one forward for all of them. This default plays
    /// them one by one; a controller whose one forward costs about the same
    /// for many rows does them together. Its own memory afterwards is
    /// unspecified: callers put it back.
    fn act_batch(
        &mut self,
        envs: &[&TrapEnv],
        side: Side,
        memories: &mut [Vec<f32>],
        out: &mut [Action],
    ) {
        assert_eq!(envs.len(), memories.len(), "one memory per game");
        let slots = out.len() / envs.len().max(1);
        for ((env, memory), out) in envs.iter().zip(memories).zip(out.chunks_mut(slots)) {
            self.set_memory(memory);
            self.act(env, side, out);
            *memory = self.memory().unwrap_or_default();
        }
    }
}

/// A controller whose `act_batch` is the trait's own, one game after the
/// other: what batching saves is measured against it, and batched play is
/// checked to decide as it does.
pub struct OneGameAtATime(pub Box<dyn Controller>);

impl Controller for OneGameAtATime {
    fn name(&self) -> String {
        self.0.name()
    }
    fn reset(&mut self, env: &TrapEnv, seed: u64) {
        self.0.reset(env, seed);
    }
    fn act(&mut self, env: &TrapEnv, side: Side, out: &mut [Action]) {
        self.0.act(env, side, out);
    }
    fn memory(&self) -> Option<Vec<f32>> {
        self.0.memory()
    }
    fn set_memory(&mut self, memory: &[f32]) {
        self.0.set_memory(memory);
    }
    fn has_memory(&self) -> bool {
        self.0.has_memory()
    }
}
