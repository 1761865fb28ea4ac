//! Who plays in a league, by name: a side's main learner and exploiter
//! (`Seat`) and its permanent heuristic member. A leaf: the config, the
//! directory layout, the processes and the learners all name players, and
//! none of them needs the others for it.

use std::path::{Path, PathBuf};
use t2e_core::env::Side;

/// The evaluator's name: its heartbeat row and the recorder of the panel's
/// matches. One name, so the status's filters and the processes agree.
pub const EVALUATOR: &str = "evaluator";

/// The player name of a side's main learner.
pub fn learner_name(side: Side) -> String {
    format!("{}-main", side.name())
}

/// What a seat's learner is for. Every question the league asks of a seat
/// (what it draws, whether it drives the curriculum, keeps pace, resets
/// after a snapshot) is answered by `Seat`'s methods below, once for every
/// role, so a new role is one variant here and its answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeatRole {
    /// The side's main learner: plays the whole pool, stays in it.
    Main,
    /// The side's main exploiter (AlphaStar): plays only the other side's
    /// main line and starts over after each snapshot.
    Exploiter,
}

/// Which learner a process runs: a side's main learner or its main exploiter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Seat {
    pub side: Side,
    pub role: SeatRole,
}

impl Seat {
    pub fn main(side: Side) -> Seat {
        Seat {
            side,
            role: SeatRole::Main,
        }
    }

    pub fn exploiter(side: Side) -> Seat {
        Seat {
            side,
            role: SeatRole::Exploiter,
        }
    }

    pub fn is_exploiter(self) -> bool {
        self.role == SeatRole::Exploiter
    }

    /// Its player name (`captors-main`, `target-exploiter`, ...).
    pub fn name(self) -> String {
        match self.role {
            SeatRole::Main => learner_name(self.side),
            SeatRole::Exploiter => format!("{}-exploiter", self.side.name()),
        }
    }

    /// Draws only the other side's main line (and the heuristics until it
    /// has a snapshot), never the rest of the pool.
    pub fn draws_main_line_only(self) -> bool {
        self.role == SeatRole::Exploiter
    }

    /// Moves the target-speed curriculum: the main captors alone, so one
    /// learner's results set the stage every learner plays at.
    pub fn drives_curriculum(self) -> bool {
        self.side == Side::Captors && self.role == SeatRole::Main
    }

    /// Waits for the other side's main learner when it runs ahead
    /// (`pace_env_steps`): the main learners grow together.
    pub fn keeps_pace(self) -> bool {
        self.role == SeatRole::Main
    }
}

/// The player name of a side's permanent heuristic member.
pub fn heuristic_name(side: Side) -> String {
    match side {
        Side::Captors => "expert-captors".into(),
        Side::Target => "rule-based-target".into(),
    }
}

/// What a seat runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Learner(Seat),
    Evaluator,
}

impl Role {
    /// The seat's name (`captors-main`, `target-exploiter`, `evaluator`).
    pub fn name(self) -> String {
        match self {
            Role::Learner(seat) => seat.name(),
            Role::Evaluator => EVALUATOR.into(),
        }
    }

    /// The role a seat name stands for.
    pub fn from_name(name: &str) -> Option<Role> {
        if name == EVALUATOR {
            return Some(Role::Evaluator);
        }
        [Side::Captors, Side::Target]
            .into_iter()
            .flat_map(|side| [Seat::main(side), Seat::exploiter(side)])
            .find(|seat| seat.name() == name)
            .map(Role::Learner)
    }

    pub fn log_path(self, logs: &Path) -> PathBuf {
        logs.join(format!("{}.log", self.name()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_seat_answers_the_leagues_questions_as_its_role_says() {
        // (seat, name, main line only, curriculum, pace); whether it resets is
        // the config's too (`roles::SeatRules`)
        let table = [
            (Seat::main(Side::Captors), "captors-main", false, true, true),
            (Seat::main(Side::Target), "target-main", false, false, true),
            (
                Seat::exploiter(Side::Captors),
                "captors-exploiter",
                true,
                false,
                false,
            ),
            (
                Seat::exploiter(Side::Target),
                "target-exploiter",
                true,
                false,
                false,
            ),
        ];
        for (seat, name, main_line, curriculum, pace) in table {
            assert_eq!(seat.name(), name);
            assert_eq!(seat.draws_main_line_only(), main_line, "{name}");
            assert_eq!(seat.drives_curriculum(), curriculum, "{name}");
            assert_eq!(seat.keeps_pace(), pace, "{name}");
        }
    }
}
