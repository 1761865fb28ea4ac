//! The league's processes and folders, over the rules and the store, one
//! folder per role:
//!
//! - `folder/`: the league directory's layout, its snapshot pool and
//!   opening a league, every check before any write;
//! - `evaluation/`: the evaluator, its panels, and the checks of a new
//!   league's panels that need maps or checkpoints loaded;
//! - `seat/`: one main learner's process and the opponents it plays;
//! - `processes/`: the manager, workers, the seats on workers, the loop
//!   the three supervise in, and spawning the league's child processes;
//! - `exploit/`: a fresh best response against one frozen player;
//! - `status/`: what `status` and `export` read from a league;
//! - `view`: what the manager and `exploit` show while they run.

pub mod evaluation;
pub mod exploit;
pub mod folder;
pub mod processes;
pub mod seat;
pub mod status;
pub mod view;
