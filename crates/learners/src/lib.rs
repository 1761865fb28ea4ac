//! t2e-learners: the learning floor of t2e-league, over libtorch and the
//! core environment — networks and checkpoints (`nn`), the four learners
//! and their training loop (`learn`), the controller catalogue
//! (`controllers`), the paper's evaluation (`eval`) and the renders
//! (`render`). It knows nothing of the league or its store; the league
//! drives it through `learn::Trainer` and the `learn::RolloutHooks` it
//! defines.
pub mod controllers;
pub mod eval;
pub mod learn;
pub mod nn;
pub mod render;

// The floor below, under the names this crate's modules use for it.
pub use t2e_core::{algorithm, asz, env, error, fs, heuristics, map, protocol, util, PROJECT_ROOT};
