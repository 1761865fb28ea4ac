//! The league's processes and folders: the manager, workers, learners, the
//! evaluator and `exploit`, and the league directory they share, over the
//! rules and the store.

pub mod child;
pub mod dir;
pub mod evaluator;
pub mod exploit;
pub mod exploit_key;
pub mod learner;
pub mod manager;
pub mod manager_lease;
pub mod open;
pub mod opponents;
pub mod panels;
pub mod pool;
pub mod preflight;
pub mod process;
pub mod seats;
pub mod status;
pub mod supervisor;
pub mod view;
pub mod worker;
