//! Who plays in a league, by name: a side's main learner and exploiter
//! (`Seat`) and its permanent heuristic member. A leaf: the config, the
//! directory layout, the processes and the learners all name players, and
//! none of them needs the others for it.

use crate::env::Side;

/// The evaluator's name: its heartbeat row and the recorder of the panel's
/// matches. One name, so the status's filters and the processes agree.
pub const EVALUATOR: &str = "evaluator";

/// The player name of a side's main learner.
pub fn learner_name(side: Side) -> String {
    format!("{}-main", side.name())
}

/// Which learner a process runs: a side's main learner or its main exploiter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Seat {
    pub side: Side,
    pub exploiter: bool,
}

impl Seat {
    pub fn main(side: Side) -> Seat {
        Seat {
            side,
            exploiter: false,
        }
    }

    pub fn exploiter(side: Side) -> Seat {
        Seat {
            side,
            exploiter: true,
        }
    }

    /// Its player name (`captors-main`, `target-exploiter`, ...).
    pub fn name(self) -> String {
        if self.exploiter {
            format!("{}-exploiter", self.side.name())
        } else {
            learner_name(self.side)
        }
    }
}

/// The player name of a side's permanent heuristic member.
pub fn heuristic_name(side: Side) -> String {
    match side {
        Side::Captors => "expert-captors".into(),
        Side::Target => "rule-based-target".into(),
    }
}
