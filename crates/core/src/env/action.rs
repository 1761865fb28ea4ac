//! The five discrete actions and their drive commands (spec §2).

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[repr(u8)]
pub enum Action {
    Forward = 0,
    TurnLeft = 1,
    TurnRight = 2,
    #[default]
    Stop = 3,
    Backward = 4,
}

impl Action {
    pub const ALL: [Action; 5] = [
        Action::Forward,
        Action::TurnLeft,
        Action::TurnRight,
        Action::Stop,
        Action::Backward,
    ];
    pub const COUNT: usize = 5;

    pub fn from_index(i: usize) -> Action {
        Action::ALL[i]
    }

    pub fn index(self) -> usize {
        self as usize
    }

    /// (u_drive, u_turn): turning also drives forward at 0.8.
    pub fn command(self) -> (f64, f64) {
        match self {
            Action::Forward => (1.0, 0.0),
            Action::TurnLeft => (0.8, 1.0),
            Action::TurnRight => (0.8, -1.0),
            Action::Stop => (0.0, 0.0),
            Action::Backward => (-1.0, 0.0),
        }
    }
}
