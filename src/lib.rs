//! t2e-league: the T2E target-trapping benchmark in Rust, and a league that
//! trains captor and target teams against pools of each other's checkpoints.
//!
//! See ARCHITECTURE.md for the map of the code.
//!
//! The environment, PettingZoo-style: agents are the captors, then the target.
//!
//! ```
//! use std::sync::Arc;
//! use t2e::env::{Action, EnvConfig, TrapEnv};
//! use t2e::map::{Grid, PreparedMap};
//!
//! // A 6 m x 6 m room in the middle of a 16 m map.
//! let mut grid = Grid::blocked("room", 320);
//! for row in 100..220 {
//!     for col in 100..220 {
//!         grid.set_free(row, col, true);
//!     }
//! }
//! let maps = Arc::new(vec![Arc::new(PreparedMap::new(grid))]);
//! let cfg = EnvConfig { num_captors: 3, target_speed: 1.2, ..EnvConfig::default() };
//! let mut env = TrapEnv::new(cfg, maps).unwrap();
//! let first = env.reset(42).unwrap();
//! assert_eq!(first.len(), 4);
//! assert_eq!(first[0].vector.len(), 20);
//! let step = env.step(&[Action::Forward; 4]);
//! assert_eq!(step.rewards.len(), 4);
//! assert!(!step.terminations[0] && !step.truncations[0]);
//! // Same seed, same episode.
//! assert_eq!(env.reset(42).unwrap(), first);
//! ```
pub mod cli;

// The users' facade: the floors below, each its own crate, under one name
// (`t2e::env`, `t2e::learn`, `t2e::league`): the core (no libtorch, no
// database), the learners (libtorch, no database) and the league (rules,
// store, processes; no command line). The project's own code names each
// module by its real crate (`t2e_core::env`, `t2e_learners::learn`,
// `league::rules::config`), so a path says which floor it lives on.
pub use league;
pub use t2e_core::{
    algorithm, asz, env, error, fs, heuristics, map, protocol, render, util, PROJECT_ROOT,
};
pub use t2e_learners::{controllers, eval, learn, nn, plots};
