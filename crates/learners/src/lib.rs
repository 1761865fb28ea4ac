//! t2e-learners: the learning floor of t2e-league, over libtorch and the
//! core environment — networks and checkpoints (`nn`), the four learners
//! and their training loop (`learn`), the controller catalogue
//! (`controllers`), the paper's evaluation (`eval`) and plots (`plots`);
//! the training loop, the evaluation and the plots fail with an
//! `error::LearnError`, which wraps the narrower errors of `nn` and the core.
//! It knows nothing of the league or its store; the league drives it
//! through `learn::Trainer` and the `learn::RolloutHooks` it defines.
//! The floor below is named by its own crate, `t2e_core`.
pub mod controllers;
pub mod error;
pub mod eval;
pub mod learn;
pub mod nn;
pub mod plots;
