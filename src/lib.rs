//! t2e-league: the T2E target-trapping benchmark in Rust, and a league that
//! trains captor and target teams against pools of each other's checkpoints.
//!
//! See ARCHITECTURE.md for the map of the code.
pub mod asz;
pub mod cli;
pub mod env;
pub mod eval;
pub mod heuristics;
pub mod map;
pub mod render;
