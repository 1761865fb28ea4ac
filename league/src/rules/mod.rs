//! The league's rules: what is decided, from data alone. Pure and seeded;
//! nothing here names the store or a process (tests/integration/docs/layering.rs).

pub mod config;
pub mod curriculum;
pub mod evaluator_config;
pub mod matchmaking;
pub mod members;
pub mod payoff;
pub mod players;
pub mod ratings;
pub mod roles;
pub mod selection;
pub mod supervision;
