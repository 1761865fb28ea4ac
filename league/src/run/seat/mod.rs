//! One main learner's process (`learner`) and the opponents it plays in
//! each of its worlds (`opponents`).

pub mod learner;
pub mod opponents;
